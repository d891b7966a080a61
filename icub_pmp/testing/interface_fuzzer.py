"""InterfaceFuzzer: drawn requests, goals and messages sent to the running graph over DDS.

Each case goes to a real node (a :class:`~icub_pmp.graph.NodeGraph` process) through the
test's :class:`~icub_pmp.ros.probe.RosProbe`; the outcome is tallied in a
:class:`~icub_pmp.testing.fuzz_tally.FuzzTally`:

- services: answered within the interface's time budget (else a hang), a rejection
  (``success`` false) carries a message (else unclear), the node's process still runs (else a
  crash; the node is restarted so the other interfaces can go on);
- actions: the goal is acknowledged, and ends (by itself, or canceled after ``run_s``) within
  the budget; an aborted goal's result says why;
- topics: drawn messages, out-of-order and duplicated stamps, a burst at ten times the
  expected rate, and corrupt serialized bytes: every subscriber's process still runs.

The cases come from :mod:`.message_fuzz` (hypothesis, derandomised: the same cases on every
run).
"""

from __future__ import annotations

import copy
import time
from typing import Any, Callable, Sequence

from hypothesis import HealthCheck, Phase, given, settings

from icub_pmp.graph import NodeGraph
from icub_pmp.ros.probe import RosProbe
from icub_pmp.testing.fuzz_tally import FuzzTally, InterfaceTally
from icub_pmp.testing.message_fuzz import (
    FuzzVocabulary,
    message_strategy,
    out_of_order_stamps,
    restamp,
)

__all__ = ["InterfaceFuzzer", "fuzz_settings", "rejection_message"]


def fuzz_settings(max_examples: int) -> settings:
    """Hypothesis settings for DDS fuzzing: ``max_examples`` derandomised cases, no deadline,
    no shrinking (a case's outcome is tallied, never raised), no example database."""
    return settings(max_examples=max_examples, deadline=None, derandomize=True, database=None,
                    phases=[Phase.generate], suppress_health_check=list(HealthCheck))


def rejection_message(response: Any) -> tuple[bool, str] | None:
    """(rejected?, message) of a response or result with ``success``/``message``,
    ``error_code``/``error_string``, ``success``/``outcome`` or SetParameters' ``results``
    (``successful``/``reason`` each); None if it has none of them."""
    if hasattr(response, "error_code"):
        return response.error_code != 0, str(getattr(response, "error_string", ""))
    results = getattr(response, "results", None)  # rcl_interfaces/SetParameters
    if isinstance(results, (list, tuple)) and all(hasattr(r, "successful") for r in results):
        bad = [r for r in results if not r.successful]
        return bool(bad), "; ".join(str(r.reason) for r in bad)
    if hasattr(response, "success"):
        return (not response.success), str(getattr(response, "message", ""))
    return None


class InterfaceFuzzer:
    """Fuzz the interfaces of ``graph``'s nodes through ``probe`` (module doc)."""

    def __init__(self, probe: RosProbe, graph: NodeGraph, vocab: FuzzVocabulary | None = None,
                 tally: FuzzTally | None = None, restart_timeout: float = 120.0):
        self.probe = probe
        self.graph = graph
        self.vocab = vocab or FuzzVocabulary.icub()
        self.tally = tally if tally is not None else FuzzTally()
        self.restart_timeout = restart_timeout

    # ------------------------------------------------------------------ crash handling
    def _check_alive(self, t: InterfaceTally, nodes: Sequence[str], case: str) -> bool:
        """True if every node of ``nodes`` still runs; else count a crash, keep the evidence
        and restart the dead nodes."""
        dead = [n for n in nodes if not self.graph.procs[n].alive()]
        for n in dead:
            t.crashes += 1
            t.note(f"{n} died after {case[:300]}: {self.graph.procs[n].output()[-1500:]}")
            self.graph.start(n)
        return not dead

    def _run_cases(self, strategy: Any, n: int, case: Callable[[Any], bool]) -> None:
        """Run ``case`` on ``n`` drawn inputs (stops early when ``case`` returns False)."""
        stop = [False]

        @fuzz_settings(n)
        @given(strategy)
        def run(value: Any) -> None:
            if not stop[0]:
                stop[0] = not case(value)

        run()

    # ------------------------------------------------------------------ services
    def fuzz_service(self, name: str, srv_type: Any, node: str, budget: float, n: int
                     ) -> InterfaceTally:
        """``n`` drawn requests to service ``name`` served by ``node``; each must be answered
        within ``budget`` s of wall time."""
        t = self.tally.get(name, "service", node)
        client = self.probe.node.create_client(srv_type, name)
        try:
            if not client.wait_for_service(timeout_sec=60.0):
                t.hangs += 1
                t.note(f"{name} not available")
                return t

            def case(req: Any) -> bool:
                t.cases += 1
                fut = client.call_async(req)
                if not self.probe.wait_for(fut.done, budget):
                    client.remove_pending_request(fut)
                    t.hangs += 1
                    t.note(f"no answer in {budget} s to {str(req)[:300]}")
                else:
                    self._judge(t, fut.result(), req)
                if not self._check_alive(t, [node], str(req)):
                    client.wait_for_service(timeout_sec=self.restart_timeout)
                return True

            self._run_cases(message_strategy(srv_type.Request, self.vocab), n, case)
        finally:
            self.probe.destroy(client)
        return t

    @staticmethod
    def _judge(t: InterfaceTally, response: Any, case: Any) -> None:
        verdict = rejection_message(response)
        if verdict is None or not verdict[0]:
            return
        if verdict[1].strip():
            t.reject(verdict[1])
        else:
            t.unclear += 1
            t.note(f"rejection without a message for {str(case)[:300]}")

    # ------------------------------------------------------------------ actions
    def fuzz_action(self, name: str, action_type: Any, node: str, budget: float, n: int,
                    run_s: float = 2.0) -> InterfaceTally:
        """``n`` drawn goals to action ``name``: each acknowledged within ``budget`` s; a goal
        still running after ``run_s`` s is canceled and must end within ``budget`` s."""
        t = self.tally.get(name, "action", node)
        client = self.probe.action_client(name, action_type, timeout=60.0)
        try:
            def case(goal: Any) -> bool:
                t.cases += 1
                self._one_goal(t, client, goal, budget, run_s)
                if not self._check_alive(t, [node], str(goal)):
                    self.probe.wait_for(client.server_is_ready, self.restart_timeout)
                return True

            self._run_cases(message_strategy(action_type.Goal, self.vocab), n, case)
        finally:
            self.probe.destroy(client)
        return t

    def _one_goal(self, t: InterfaceTally, client: Any, goal: Any, budget: float,
                  run_s: float) -> None:
        sent = self.probe.on_spin_thread(lambda: client.send_goal_async(goal))
        if not self.probe.wait_for(sent.done, budget):
            t.hangs += 1
            t.note(f"goal not acknowledged in {budget} s: {str(goal)[:300]}")
            return
        handle = sent.result()
        if not handle.accepted:
            t.rejected += 1  # the action protocol carries no reason for a rejection
            return
        result = handle.get_result_async()
        if not self.probe.wait_for(result.done, run_s):
            self.probe.on_spin_thread(handle.cancel_goal_async)
            if not self.probe.wait_for(result.done, budget):
                t.hangs += 1
                t.note(f"goal not ended {budget} s after its cancel: {str(goal)[:300]}")
                return
        res = result.result()
        verdict = rejection_message(res.result)
        from action_msgs.msg import GoalStatus

        if res.status == GoalStatus.STATUS_ABORTED and verdict is not None:
            if verdict[1].strip():
                t.reject(verdict[1])
            else:
                t.unclear += 1
                t.note(f"aborted without a message: {str(goal)[:300]}")

    # ------------------------------------------------------------------ topics
    def _publisher(self, t: InterfaceTally, topic: str, msg_type: Any) -> Any:
        """A reliable, transient-local publisher on ``topic``, once a subscriber matched;
        when none matched in 30 s (a wrong topic name, a node that does not subscribe) it
        counts as a hang: the cases would reach no node."""
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        # reliable + transient local: matches every subscriber (best effort or reliable,
        # volatile or latched like /sim/status)
        pub = self.probe.node.create_publisher(
            msg_type, topic, QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE,
                                        durability=DurabilityPolicy.TRANSIENT_LOCAL))
        if not self.probe.wait_for(lambda: pub.get_subscription_count() >= 1, 30.0):
            t.hangs += 1
            t.note(f"no subscriber of {topic} matched in 30 s: the cases reach no node")
        return pub

    def fuzz_topic(self, topic: str, msg_type: Any, nodes: Sequence[str], n: int,
                   period: float = 0.005) -> InterfaceTally:
        """``n`` drawn messages on ``topic`` (one every ``period`` s); every node of ``nodes``
        (its subscribers) must still run afterwards."""
        t = self.tally.get(topic, "topic", ",".join(nodes))
        pub = self._publisher(t, topic, msg_type)
        last: list[Any] = [None]
        try:
            def case(msg: Any) -> bool:
                t.cases += 1
                pub.publish(msg)
                last[0] = msg
                time.sleep(period)
                return True

            self._run_cases(message_strategy(msg_type, self.vocab), n, case)
            time.sleep(0.5)
            self._check_alive(t, nodes, f"fuzzed {topic}, e.g. {last[0]}")
        finally:
            self.probe.destroy(pub)
        return t

    def disorder_topic(self, topic: str, template: Any, nodes: Sequence[str], n: int = 20,
                       rate_hz: float = 1000.0, burst_s: float = 0.5) -> InterfaceTally:
        """Topic-level cases with a valid ``template`` message: ``n`` copies with out-of-order
        and repeated stamps from the template's on, then a burst at ten times ``rate_hz``
        for ``burst_s`` s (as fast as this process publishes, if slower), then ``n`` corrupt
        serialized messages (truncated CDR, garbage bytes). The subscribers must still run."""
        from rclpy.serialization import serialize_message

        t = self.tally.get(f"{topic} (order/rate/cdr)", "topic", ",".join(nodes))
        pub = self._publisher(t, topic, type(template))
        try:
            h = getattr(template, "header", None)
            t0 = h.stamp.sec + h.stamp.nanosec * 1e-9 if h is not None else time.time()
            stamps = out_of_order_stamps(n, t0, 1.0 / rate_hz)
            for m in restamp([copy.deepcopy(template) for _ in range(n)], stamps):
                pub.publish(m)
                t.cases += 1
            # the burst: serialised beforehand, so the publishing loop only paces and sends
            period = 1.0 / (10.0 * rate_hz)
            k_max = int(burst_s / period)
            burst = [serialize_message(restamp([template], [t0 + k * period])[0])
                     for k in range(k_max)]
            b0 = time.monotonic()
            for k, data in enumerate(burst):
                pub.publish(data)
                lag = b0 + (k + 1) * period - time.monotonic()
                if lag > 0:
                    time.sleep(lag)
            t.cases += len(burst)
            t.burst_hz = max(t.burst_hz, len(burst) / max(time.monotonic() - b0, 1e-9))
            raw = serialize_message(template)
            for i in range(n):
                cut = raw[: (len(raw) * i) // n] if i % 2 == 0 else bytes(
                    (b * 7 + i) % 256 for b in raw[: 4 + i * 5])
                pub.publish(cut)
                t.cases += 1
            time.sleep(1.0)
            self._check_alive(t, nodes, f"out-of-order/burst/corrupt CDR on {topic}")
        finally:
            self.probe.destroy(pub)
        return t
