"""FaultInjector: kill one node of the running lockstep graph in the middle of a reach, watch
what the others do, restart it and time the recovery (issue 22, "faults in the running
graph").

One :meth:`FaultInjector.run` = one row of the fault table:

1. a reach goal (``/pmp/reach_action``, executed by the controller on the simulator) starts;
2. once the robot moves, ``node`` gets ``SIGKILL`` or ``SIGTERM`` (its whole process group);
3. for ``observe_s`` seconds the others are watched: still running, the controller's state
   on ``/impedance_controller/status`` (safe hold and why), the simulator's on ``/sim/status``
   (holding, lockstep time-outs), the interrupted goal's end;
4. the node is restarted; ``rejoin_s`` is the wall time until it serves again (its key
   interface is back, :data:`READY`), and a service client created *before* the restart calls
   ``/pmp/reach`` with a bounded wait (it must wait or answer, never hang);
5. the next reach goal must succeed on the measured robot: then (with the others alive and
   the early call answered) the fault is recovered.
"""

from __future__ import annotations

import dataclasses
import signal
import threading
import time
from typing import Any

from icub_pmp.graph import NodeGraph
from icub_pmp.ros.probe import RosProbe
from icub_pmp.ros.reach_goal_message import reach_goal_message
from icub_pmp.testing.graph_interfaces import PERIPERSONAL_FUZZ_MAPS

__all__ = ["FaultInjector", "FaultOutcome", "FAULT_GRAPH", "FAULT_PARAMS", "FULL_FAULT_GRAPH",
           "FULL_FAULT_PARAMS", "format_table", "reach_goal"]

#: the lockstep graph of the fault table (the simulator steps on the controller's commands)
FAULT_GRAPH = ["sim_bridge", "wrench_estimator", "impedance_controller", "pmp_planner"]
FAULT_PARAMS: dict[str, dict[str, object]] = {
    "sim_bridge": {"mode": "lockstep", "cameras_enabled": False},
}
#: every node of the project (bench/reliability.py's full matrix): the reach path above plus the
#: nodes a user starts beside it; cameras on, so the soak's vision step has images (the Cartesian
#: solver on the CasADi VM and the peripersonal maps grown small, as in the fuzz graph)
FULL_FAULT_GRAPH = FAULT_GRAPH + ["gaze_controller", "cartesian_solver", "motion_segmenter",
                                  "robot_state_publisher", "body_schema", "peripersonal_space"]
FULL_FAULT_PARAMS: dict[str, dict[str, object]] = {
    "sim_bridge": {"mode": "lockstep", "cameras_enabled": True},
    "cartesian_solver": {"codegen": False},
    "peripersonal_space": {"maps_dir": str(PERIPERSONAL_FUZZ_MAPS), "grow_if_missing": True,
                           "babble_samples": 2000},
}
#: a node without a key topic serves again once a request to its service is answered
#: (after a SIGKILL the dead server stays matched until its DDS lease expires)
READY_SERVICE = {
    "gaze_controller": "/gaze/set_tracking",
    "cartesian_solver": "/cartesian/solve_pose",
    "peripersonal_space": "/peripersonal/check_reach",
    "body_schema": "/body_schema/stop_babbling",
}
#: two targets the reaches alternate between (right hand, root_link [m])
TARGETS = ([-0.30, 0.17, 0.02], [-0.26, 0.12, 0.10])


@dataclasses.dataclass
class FaultOutcome:
    """One row of the fault table (module doc)."""

    node: str
    fault: str
    others_alive: bool = False
    controller: str = ""
    simulator: str = ""
    interrupted_goal: str = ""
    early_call: str = ""
    rejoin_s: float = float("nan")
    next_goal: str = ""
    recovered: bool = False

    def row(self) -> str:
        """The table row (see :func:`format_table`)."""
        return (f"{self.node:21s} {self.fault:7s} {'yes' if self.others_alive else 'NO':6s} "
                f"{self.controller[:34]:34s} {self.simulator[:30]:30s} "
                f"{self.interrupted_goal[:26]:26s} {self.early_call[:22]:22s} "
                f"{self.rejoin_s:7.2f} {self.next_goal[:18]:18s}")


def format_table(rows: list[FaultOutcome]) -> str:
    """The fault table: node, fault, others alive, what the controller and the simulator did,
    how the interrupted goal ended, the early service call, rejoin time [s], next goal."""
    head = (f"{'node':21s} {'fault':7s} {'others':6s} {'controller':34s} {'simulator':30s} "
            f"{'interrupted goal':26s} {'call before match':22s} {'rejoin':>7s} next goal")
    return "\n".join([head] + [r.row() for r in rows])


def reach_goal(target: list[float], tau: float = 1.5) -> Any:
    """A right-hand reach goal for ``/pmp/reach_action`` to ``target`` [m, root_link]."""
    return reach_goal_message({"right": target}, tau)


class _StatusLog:
    """Every /impedance_controller/status and /sim/status since :meth:`mark`."""

    def __init__(self, probe: RosProbe) -> None:
        from icub_interfaces.msg import ControllerStatus, SimStatus
        from icub_pmp.ros.qos import LATCHED_QOS

        self.lock = threading.Lock()
        self.ctrl: list[Any] = []
        self.sim: list[Any] = []
        self.subs = [
            probe.node.create_subscription(ControllerStatus, "/impedance_controller/status",
                                           lambda m: self._add(self.ctrl, m), LATCHED_QOS),
            probe.node.create_subscription(SimStatus, "/sim/status",
                                           lambda m: self._add(self.sim, m), LATCHED_QOS)]

    def _add(self, log: list[Any], m: Any) -> None:
        with self.lock:
            log.append(m)

    def mark(self) -> None:
        with self.lock:
            self.ctrl.clear()
            self.sim.clear()

    def controller(self) -> str:
        with self.lock:
            holds = [m for m in self.ctrl if m.status == "safe_hold"]
            if holds:
                return f"safe_hold: {holds[0].safe_hold_reason}"
            return ",".join(dict.fromkeys(m.status for m in self.ctrl)) or "(no status)"

    def simulator(self) -> str:
        with self.lock:
            if not self.sim:
                return "(no status)"
            timeouts = self.sim[-1].lockstep_timeouts - self.sim[0].lockstep_timeouts
            states = ",".join(dict.fromkeys(m.status for m in self.sim))
            held = [m.message for m in self.sim if m.status == "holding"]
            return (f"{states}; {timeouts} lockstep timeouts"
                    + (f"; {held[0]}" if held else ""))


class FaultInjector:
    """Runs fault rows on ``graph`` (started with :data:`FAULT_GRAPH`/:data:`FAULT_PARAMS`)
    through ``probe`` (module doc)."""

    def __init__(self, probe: RosProbe, graph: NodeGraph, observe_s: float = 3.0,
                 goal_timeout: float = 120.0, ready_timeout: float = 180.0,
                 answer_timeout: float = 15.0):
        from icub_interfaces.action import Reach

        self.probe = probe
        self.graph = graph
        self.observe_s = observe_s
        self.goal_timeout = goal_timeout
        self.ready_timeout = ready_timeout
        self.answer_timeout = answer_timeout
        self.status = _StatusLog(probe)
        self.client = probe.action_client("/pmp/reach_action", Reach, timeout=ready_timeout)
        self._k = 0

    # ------------------------------------------------------------------ readiness
    def _fresh(self, topic: str, msg_type: Any) -> bool:
        return bool(self.probe.collect(topic, msg_type, 2, timeout=5.0))

    def ready(self, node: str) -> bool:
        """True once ``node`` serves again (one poll)."""
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import JointState

        if node == "sim_bridge":
            return self._fresh("/clock", Clock)
        if node == "wrench_estimator":
            return self._fresh("/estimated_joint_torques", JointState)
        if node == "impedance_controller":
            return self._fresh("/effort_command", JointState)
        if node == "pmp_planner":
            # after a SIGKILL the dead server stays "ready" until its DDS lease expires: the
            # restarted process must also have said that it serves
            return (self.client.server_is_ready()
                    and "serving /pmp/reach" in self.graph.procs[node].output())
        if node in READY_SERVICE:
            return self._answers(node)
        # any other node: on the graph, and the running process has logged its start-up line
        return (f"/{node}" in self.probe.node_names()
                and "[INFO]" in self.graph.procs[node].output())

    def _answers(self, node: str) -> bool:
        """True when ``node``'s :data:`READY_SERVICE` answers a good request within 10 s."""
        from geometry_msgs.msg import Point
        from std_srvs.srv import SetBool, Trigger

        from icub_interfaces.srv import CheckReach, SolvePose
        from icub_pmp.testing.graph_interfaces import good_solve_pose

        name = READY_SERVICE[node]
        if node == "gaze_controller":
            srv, req = SetBool, SetBool.Request(data=False)
        elif node == "cartesian_solver":
            srv, req = SolvePose, good_solve_pose()
        elif node == "peripersonal_space":
            srv, req = CheckReach, CheckReach.Request(points=[Point(x=-0.3, y=0.15, z=0.05)])
        else:
            srv, req = Trigger, Trigger.Request()
        try:
            self.probe.call(name, srv, req, timeout=10.0)
        except TimeoutError:
            return False
        return True

    def wait_ready(self, timeout: float | None = None) -> bool:
        """Wait until every node of the graph serves."""
        limit = self.ready_timeout if timeout is None else timeout
        return self.probe.wait_for(
            lambda: all(self.ready(n) for n in self.graph.procs), limit)

    # ------------------------------------------------------------------ goals
    def _target(self) -> list[float]:
        self._k += 1
        return TARGETS[self._k % 2]

    def reach(self, timeout: float | None = None) -> tuple[bool, str]:
        """An executed reach goal: (succeeded?, outcome: message)."""
        try:
            res = self.probe.send_goal(self.client, reach_goal(self._target()),
                                       timeout=timeout or self.goal_timeout)
        except (TimeoutError, RuntimeError) as exc:
            return False, f"no result: {exc}"
        return bool(res.result.success), f"{res.result.outcome}: {res.result.message}"

    # ------------------------------------------------------------------ one fault
    def run(self, node: str, sig: int) -> FaultOutcome:
        """One row: ``sig`` to ``node`` mid-reach, observe, restart, next goal."""
        from icub_interfaces.srv import Reach

        out = FaultOutcome(node, signal.Signals(sig).name)
        early = self.probe.node.create_client(Reach, "/pmp/reach")
        feedback: list[Any] = []
        goal = reach_goal(self._target(), tau=2.0)
        sent = self.probe.on_spin_thread(
            lambda: self.client.send_goal_async(goal, feedback_callback=feedback.append))
        self.probe.wait_for(lambda: sent.done() and len(feedback) >= 3, 60.0)
        self.status.mark()
        self.graph.procs[node].signal(sig)
        try:
            self.graph.procs[node].proc.wait(15.0)
        except Exception:  # did not stop within 15 s: that is a finding, force it
            out.interrupted_goal = "node ignored the signal for 15 s; "
            self.graph.procs[node].kill()
        time.sleep(self.observe_s)
        others = {n: p.alive() for n, p in self.graph.procs.items() if n != node}
        out.others_alive = all(others.values())
        out.controller = self.status.controller()
        out.simulator = self.status.simulator()
        out.interrupted_goal += self._interrupted(sent, node)
        t0 = time.monotonic()
        self.graph.start(node)
        rejoined: list[float] = []
        poll = threading.Thread(target=lambda: self.probe.wait_for(
            lambda: self.ready(node) and not rejoined.append(time.monotonic() - t0),
            self.ready_timeout), daemon=True)
        poll.start()
        out.early_call = self._early_call(early)
        poll.join(self.ready_timeout + 10.0)
        if rejoined:
            out.rejoin_s = rejoined[0]
        ok, text = self.reach()
        if not ok:  # a goal sent while the graph was still settling: one more try, once the
            # controller has left its safe hold and joint states flow (as a user would retry)
            self.probe.wait_for(self._settled, 15.0)
            ok, text = self.reach()
        out.next_goal = text
        out.recovered = ok and out.others_alive and not out.early_call.startswith("HANG")
        self.probe.destroy(early)
        return out

    def _settled(self) -> bool:
        """The controller out of its safe hold and the simulator's joint states flowing."""
        from sensor_msgs.msg import JointState

        with self.status.lock:
            last = self.status.ctrl[-1] if self.status.ctrl else None
        return (last is None or last.status != "safe_hold") and self._fresh("/joint_states",
                                                                            JointState)

    def _interrupted(self, sent: Any, node: str) -> str:
        if not sent.done():
            return "not acknowledged"
        handle = sent.result()
        result = handle.get_result_async()
        wait = 15.0 if node == "pmp_planner" else self.goal_timeout
        if not self.probe.wait_for(result.done, wait):
            return "lost with its server" if node == "pmp_planner" else "no result (hang)"
        r = result.result().result
        return f"{r.outcome}: {r.message}"

    def _early_call(self, client: Any) -> str:
        """A client made before the restart calls /pmp/reach at once, as ``icub call`` does:
        a bounded wait for the service, a bounded wait for the answer (a clear error), and
        the user's retry. After a SIGKILL the dead server stays "available" until its DDS
        lease expires, so the first request can go to it and be lost: that must end in the
        clear error, and the retry must reach the restarted server."""
        from icub_pmp.testing.graph_interfaces import good_reach

        t0 = time.monotonic()
        lost = 0
        while time.monotonic() - t0 < self.ready_timeout:
            if not client.wait_for_service(timeout_sec=self.ready_timeout):
                return f"no server after {self.ready_timeout:g} s (clear error)"
            fut = client.call_async(good_reach())
            if self.probe.wait_for(fut.done, self.answer_timeout):
                r = fut.result()
                return (f"{'ok' if r.success else 'rejected'} after "
                        f"{time.monotonic() - t0:.1f} s"
                        + (f", {lost} request(s) lost to the dead server, retried" if lost
                           else ""))
            client.remove_pending_request(fut)  # the clear error: no answer in time
            lost += 1
        return f"HANG (no answer in {self.ready_timeout:g} s, {lost} tries)"
