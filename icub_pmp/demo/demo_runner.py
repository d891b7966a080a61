"""DemoRunner: drives a running node graph for the demo's phases through a
:class:`~icub_pmp.ros.probe.RosProbe` (services, topics, simulated time), and
:class:`PhaseResult`, the outcome of one phase. Used by :mod:`icub_pmp.demo.scenario`, the
other demos and the benchmarks."""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from icub_pmp.kinematics import IcubModel
from icub_pmp.ros.conversions import arrays_to_trajectory, time_to_sec
from icub_pmp.ros.probe import RosProbe
from icub_pmp.ros.reach_goal_message import reach_goal_message

__all__ = ["PROVISIONAL_PHASES", "DemoRunner", "PhaseResult"]


@dataclass
class PhaseResult:
    """Outcome of one demo phase (distances in m, times in s)."""

    name: str
    success: bool
    message: str
    targets: dict[str, list[float]] = field(default_factory=dict)
    planned_residual: dict[str, float] = field(default_factory=dict)
    physics_residual: dict[str, float] = field(default_factory=dict)
    extra: dict[str, float] = field(default_factory=dict)
    sim_start: float = 0.0
    sim_end: float = 0.0
    wall_s: float = 0.0
    #: False for a phase that is run and judged but does not yet fail the demo (its goal is
    #: not met reliably: :data:`PROVISIONAL_PHASES`); the summary says so
    required: bool = True


#: phases run and judged in every demo but not yet failing it: none. The press left it once
#: its hand kept its orientation and its force loop was guarded (docs/decisions/0069: every
#: press-only run on icub and ideal within 10 %, 2.2-3.7 %); the obstacle reach before it
#: (docs/decisions/0060). A phase named here is reported as NOT MET instead of failing.
PROVISIONAL_PHASES: tuple[str, ...] = ()


class DemoRunner:
    """Drive the running graph through a :class:`RosProbe` (services, topics, sim time)."""

    def __init__(self, probe: RosProbe, tolerance: float = 0.01):
        from geometry_msgs.msg import PointStamped, PoseStamped
        from rclpy.qos import qos_profile_sensor_data
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import JointState

        from icub_interfaces.msg import VisualTarget

        self.probe = probe
        self._recorded: list | None = None  # /joint_states kept while a phase records them
        self.model = IcubModel()
        self.tolerance = tolerance
        self.latest: dict[str, object] = {}
        node = probe.node
        self._subs = [
            node.create_subscription(JointState, "/joint_states", self._on_joint_state,
                                     qos_profile_sensor_data),
            node.create_subscription(Clock, "/clock",
                                     lambda m: self.latest.__setitem__("clock", m),
                                     qos_profile_sensor_data),
            node.create_subscription(PointStamped, "/motion/target",
                                     lambda m: self.latest.__setitem__("motion", m), 10),
            node.create_subscription(VisualTarget, "/motion/target/estimate",
                                     self._on_estimate, 10),
        ]
        self.estimates: deque = deque(maxlen=300)
        from geometry_msgs.msg import WrenchStamped
        from std_msgs.msg import Bool

        for h in ("left", "right"):
            self._subs.append(node.create_subscription(
                Bool, f"/wrench_estimator/contact/{h}_hand",
                lambda m, h=h: self.latest.__setitem__(f"contact_{h}", m),
                qos_profile_sensor_data))
            self._subs.append(node.create_subscription(
                WrenchStamped, f"/ground_truth/contact_wrench/{h}_hand",
                lambda m, h=h: self.latest.__setitem__(f"gt_{h}", m), qos_profile_sensor_data))
        # the estimated external force on each hand, the last 2 s (forces_since)
        self._ext_forces: dict[str, deque] = {}
        for h in ("left", "right"):
            self._ext_forces[h] = deque(maxlen=2000)
            self._subs.append(node.create_subscription(
                WrenchStamped, f"/wrench_estimator/external_wrench_root/{h}_hand",
                lambda m, h=h: self._ext_forces[h].append(
                    (time_to_sec(m.header.stamp), m.wrench.force.x, m.wrench.force.y,
                     m.wrench.force.z)), qos_profile_sensor_data))
        # ground truth: the robot's links touching a scene object, kept while a phase records
        from icub_interfaces.msg import ObjectContacts

        self.object_contacts: list | None = None
        self._subs.append(node.create_subscription(
            ObjectContacts, "/ground_truth/object_contacts", self._on_object_contacts,
            qos_profile_sensor_data))
        # ground-truth object poses: the latest, and the last 5 s by stamp (object_position_at)
        self._object_history: dict[str, deque] = {}
        for obj in ("box", "cylinder"):
            self._object_history[obj] = deque(maxlen=5000)
            self._subs.append(node.create_subscription(
                PoseStamped, f"/ground_truth/objects/{obj}",
                lambda m, o=obj: self._on_object(o, m), qos_profile_sensor_data))

    def _on_joint_state(self, msg) -> None:
        self.latest["js"] = msg
        if self._recorded is not None:
            self._recorded.append(msg)

    def _on_object_contacts(self, msg) -> None:
        if self.object_contacts is not None:
            self.object_contacts.extend((c.body, c.object) for c in msg.contacts)

    def force_since(self, hand: str, t: float) -> np.ndarray:
        """Mean estimated external force on ``hand`` [N] (root_link) over the samples stamped
        after ``t`` [s] (KeyError if none)."""
        rows = [r[1:] for r in list(self._ext_forces[hand]) if r[0] > t]
        if not rows:
            raise KeyError(f"no external wrench of the {hand} hand after t = {t:.3f} s")
        return np.mean(np.array(rows), axis=0)

    def _on_estimate(self, msg) -> None:
        self.latest["estimate"] = msg
        self.estimates.append(msg)

    def _on_object(self, name: str, msg) -> None:
        self.latest[name] = msg
        p = msg.pose.position
        self._object_history[name].append((time_to_sec(msg.header.stamp), (p.x, p.y, p.z)))

    # ----------------------------------------------------------------- state
    def sim_time(self) -> float:
        """Latest simulated time [s] (from /clock)."""
        c = self.latest.get("clock")
        return 0.0 if c is None else c.clock.sec + c.clock.nanosec * 1e-9

    def wait_sim(self, duration: float, wall_timeout: float = 300.0) -> None:
        """Wait until ``duration`` s of simulated time have passed."""
        end = self.sim_time() + duration
        if not self.probe.wait_for(lambda: self.sim_time() >= end, wall_timeout):
            raise TimeoutError(f"simulation did not advance {duration} s in {wall_timeout} s")

    def q(self, js=None) -> np.ndarray:  # noqa: ANN001 - ROS type
        """Measured configuration of the model's joints from ``js`` (default the latest
        /joint_states)."""
        js = self.latest["js"] if js is None else js
        return self.model.q_from_dict(dict(zip(js.name, js.position)))

    def hand_positions(self, js=None) -> dict[str, np.ndarray]:  # noqa: ANN001 - ROS type
        """Hand frame positions in root_link measured in the physics [m] (from ``js``,
        default the latest /joint_states)."""
        q = self.q(js)
        return {h: self.model.frame_position(q, self.model.spec.hand_frame(h))
                for h in ("left", "right")}

    def object_position(self, name: str) -> np.ndarray:
        """Ground-truth object position in root_link [m]."""
        p = self.latest[name].pose.position
        return np.array([p.x, p.y, p.z])

    def object_position_at(self, name: str, t: float) -> np.ndarray:
        """Ground-truth object position [m] at sim time ``t`` [s] (the nearest stamp within
        the last 5 s)."""
        hist = list(self._object_history[name])
        if not hist:
            raise KeyError(f"no ground truth received for {name}")
        _, pos = min(hist, key=lambda sp: abs(sp[0] - t))
        return np.array(pos)

    def gaze(self, angles_deg: dict[str, float], duration: float = 1.0) -> None:
        """Move neck/eye joints to ``angles_deg`` through the controller (/joint_trajectory),
        as the iCub gaze controller would, and wait until the motion is done."""
        from trajectory_msgs.msg import JointTrajectory

        js = self.latest["js"]
        now = dict(zip(js.name, js.position))
        names = list(angles_deg)
        q0 = np.array([now[n] for n in names])
        q1 = np.radians([angles_deg[n] for n in names])
        ts = np.linspace(0.0, duration, 26)
        z = ts / duration
        s = 10 * z**3 - 15 * z**4 + 6 * z**5
        msg = arrays_to_trajectory(names, ts, q0 + np.outer(s, q1 - q0))
        if not hasattr(self, "_traj_pub"):
            self._traj_pub = self.probe.node.create_publisher(
                JointTrajectory, "/joint_trajectory", 10)
            self.probe.wait_for(lambda: self._traj_pub.get_subscription_count() > 0, 30.0)
        self._traj_pub.publish(msg)
        self.wait_sim(duration + 0.3)

    def look_at(self, point: np.ndarray, wait: bool = True) -> None:
        """Ask the gaze controller (/gaze/look_at) to fixate ``point`` [m] in root_link."""
        from icub_interfaces.srv import LookAt

        req = LookAt.Request()
        req.target.header.frame_id = "root_link"
        req.target.point.x, req.target.point.y, req.target.point.z = (float(v) for v in point)
        req.wait = wait
        res = self.probe.call("/gaze/look_at", LookAt, req, timeout=120.0)
        if not res.success:
            raise RuntimeError(f"/gaze/look_at {np.round(point, 3).tolist()}: {res.message}")

    def set_tracking(self, on: bool) -> None:
        """Switch the gaze controller's tracking of /motion/target on or off."""
        from std_srvs.srv import SetBool

        res = self.probe.call("/gaze/set_tracking", SetBool, SetBool.Request(data=on),
                              timeout=30.0)
        if not res.success:
            raise RuntimeError(f"/gaze/set_tracking {on}: {res.message}")

    def reset_target(self) -> None:
        """Make the motion segmenter forget the object it follows (/motion/reset_target)."""
        from std_srvs.srv import Trigger

        res = self.probe.call("/motion/reset_target", Trigger, Trigger.Request(), timeout=30.0)
        if not res.success:
            raise RuntimeError(f"/motion/reset_target: {res.message}")

    def contacts(self) -> dict[str, bool]:
        """The wrench estimator's contact flag per hand (False if none received)."""
        return {h: bool(getattr(self.latest.get(f"contact_{h}"), "data", False))
                for h in ("left", "right")}

    def set_object(self, name: str, position: np.ndarray) -> None:
        """Teleport an object (upright) to ``position`` in root_link."""
        from icub_interfaces.srv import SetObjectPose

        req = SetObjectPose.Request()
        req.name = name
        req.pose.position.x, req.pose.position.y, req.pose.position.z = (
            float(v) for v in position)
        req.pose.orientation.w = 1.0
        res = self.probe.call("/sim/set_object_pose", SetObjectPose, req, timeout=30.0)
        if not res.success:
            raise RuntimeError(f"set_object_pose {name}: {res.message}")

    def wait_ready(self, timeout: float = 180.0,
                   services: tuple[str, ...] = ("/pmp/reach", "/cartesian/go_to_pose",
                                                "/sim/set_object_pose", "/sim/move_object",
                                                "/gaze/look_at")
                   ) -> None:
        """Wait for joint states, clock, objects and the ``services`` of the demo."""
        from icub_interfaces.srv import GoToPose, LookAt, MoveObject, Reach, SetObjectPose

        types = {"/pmp/reach": Reach, "/cartesian/go_to_pose": GoToPose,
                 "/sim/set_object_pose": SetObjectPose, "/sim/move_object": MoveObject,
                 "/gaze/look_at": LookAt}
        ok = self.probe.wait_for(
            lambda: all(k in self.latest for k in ("js", "clock", "box", "cylinder")), timeout)
        if not ok:
            raise TimeoutError(f"graph not streaming after {timeout} s: have {list(self.latest)}")
        for srv in services:
            if not self.probe.wait_for_service(srv, types[srv], timeout):
                raise TimeoutError(f"service {srv} not available after {timeout} s")

    def calibrate_estimator(self, timeout: float = 10.0) -> str:
        """Calibrate the wrench estimator's FT offsets (/wrench_estimator/calibrate) on the
        still robot before the first goal, as wholeBodyDynamics is calibrated: the call is
        repeated every 0.6 s of simulated time (a fresh ``calibration_samples`` window) until
        it succeeds or ``timeout`` s of simulated time have passed (RuntimeError with the
        estimator's last reason). Returns the estimator's message (the offsets)."""
        from std_srvs.srv import Trigger

        end = self.sim_time() + timeout
        while True:
            self.wait_sim(0.6)
            res = self.probe.call("/wrench_estimator/calibrate", Trigger, Trigger.Request(),
                                  timeout=60.0)
            if res.success:
                return res.message
            if self.sim_time() >= end:
                raise RuntimeError(f"the wrench estimator did not calibrate within {timeout} s "
                                   f"of simulated time: {res.message}")

    # ----------------------------------------------------------------- phases
    def _action(self, name: str, action_type):  # noqa: ANN202 - ROS type
        """A cached action client of the probe (waits for its server)."""
        if not hasattr(self, "_clients"):
            self._clients = {}
        if name not in self._clients:
            self._clients[name] = self.probe.action_client(name, action_type, timeout=120.0)
        return self._clients[name]

    def pmp_reach(self, name: str, targets: dict[str, np.ndarray], use_torso: bool,
                  tau: float, judge_physics: bool = True, obstacles: list | None = None,
                  obstacle_clearance: float = 0.0,
                  forces: dict[str, np.ndarray] | None = None,
                  orientations: dict[str, np.ndarray] | None = None) -> PhaseResult:
        """Send a goal to the /pmp/reach_action action, wait for its result (the planner
        waits for the hands to settle), measure the hands in the physics. ``obstacles``
        (icub_interfaces/Obstacle) with ``obstacle_clearance`` [m] and ``forces`` (hand -> the
        force it must exert on the world [N], root_link) fill the goal's fields of the same
        names; ``orientations`` (hand -> unit quaternion w, x, y, z in root_link) sets the
        targets' orientations and ``use_orientation`` (given for every hand of ``targets``)."""
        from icub_interfaces.action import Reach

        goal = reach_goal_message(targets, tau, use_torso=use_torso)
        if orientations:
            missing = sorted(set(targets) - set(orientations))
            if missing:
                raise ValueError(f"orientations: none given for {missing}")
            goal.use_orientation = True
            for h, quat in orientations.items():
                o = (goal.left_target if h == "left" else goal.right_target).pose.orientation
                o.w, o.x, o.y, o.z = (float(c) for c in quat)
        goal.obstacles = list(obstacles or [])
        goal.obstacle_clearance = float(obstacle_clearance)
        for h, f in (forces or {}).items():
            v = goal.left_force if h == "left" else goal.right_force
            v.x, v.y, v.z = (float(c) for c in f)
        wall0, sim0 = time.monotonic(), self.sim_time()
        res = self.probe.send_goal(self._action("/pmp/reach_action", Reach), goal, 300.0).result
        # a squeeze aims inside the box: "not_reached" is the expected outcome there
        executed = res.outcome in ("reached", "not_reached")
        result = PhaseResult(name, res.success if judge_physics else executed,
                             f"{res.outcome}: {res.message}",
                             targets={h: list(map(float, p)) for h, p in targets.items()},
                             planned_residual=dict(zip(res.hands, res.planned_residuals)),
                             extra={f"measured_{h}": float(e)
                                    for h, e in zip(res.hands, res.arrival_errors)},
                             sim_start=sim0)
        if goal.obstacles:
            result.extra["planned_clearance_m"] = float(res.obstacle_clearance)
        if forces:
            result.extra["planned_torques_within_limits"] = float(res.torques_within_limits)
        return self._finish(result, targets, wall0, judge_physics)

    def pmp_transport(self, name: str, position: np.ndarray, goal_position: np.ndarray,
                      tau: float, grasps: dict[str, np.ndarray] | None = None) -> PhaseResult:
        """Carry the object held by both hands from ``position`` to ``goal_position`` [m,
        root_link] through /pmp/reach_action's object coupling (hold_object; ``grasps`` =
        hand -> grasp point relative to the object [m], None = where the hands are commanded
        at the start: the planner starts a transport from the controller's set-point). The
        measured hand-to-hand distance at every /joint_states sample of the motion is kept in
        :attr:`transport_distances` (judged by :func:`judge_transport`); the phase's success
        here is only that the goal was executed."""
        from icub_interfaces.action import Reach

        goal = Reach.Goal()
        goal.hands = ["left", "right"]
        goal.use_torso = True
        goal.tau = tau
        goal.hold_object = True
        goal.use_orientation = True  # the hands keep their orientations: the grasp is rigid
        for stamped, p in ((goal.object_pose, position), (goal.object_goal, goal_position)):
            stamped.header.frame_id = "root_link"
            stamped.pose.position.x, stamped.pose.position.y, stamped.pose.position.z = (
                float(v) for v in p)
        for h, g in (grasps or {}).items():
            point = goal.left_grasp if h == "left" else goal.right_grasp
            point.x, point.y, point.z = (float(v) for v in g)

        first = self.latest["js"]
        wall0, sim0 = time.monotonic(), self.sim_time()
        self._recorded = []
        try:
            res = self.probe.send_goal(self._action("/pmp/reach_action", Reach), goal,
                                       300.0).result
        finally:
            recorded, self._recorded = self._recorded, None
        distances = []
        for m in [first] + recorded:
            x = self.hand_positions(m)
            distances.append(float(np.linalg.norm(x["left"] - x["right"])))
        self.transport_distances = np.array(distances)
        ok = res.outcome in ("reached", "not_reached")
        targets = {h: [float(p.x), float(p.y), float(p.z)]
                   for h, p in zip(res.hands, res.final_positions)}
        result = PhaseResult(name, ok, f"{res.outcome}: {res.message}", targets=targets,
                             planned_residual=dict(zip(res.hands, res.planned_residuals)),
                             sim_start=sim0)
        return self._finish(result, {}, wall0, judge_physics=False)

    def cartesian_reach(self, name: str, target: np.ndarray, T: float = 2.0) -> PhaseResult:
        """Go to ``target`` with the /cartesian/go_to_pose_action action (torso + right arm),
        measure the hand."""
        from icub_interfaces.action import GoToPose

        goal = GoToPose.Goal()
        goal.chain = "torso_right_arm"
        goal.target.header.frame_id = "root_link"
        p = goal.target.pose.position
        p.x, p.y, p.z = (float(v) for v in target)
        goal.trajectory_time = T
        wall0, sim0 = time.monotonic(), self.sim_time()
        res = self.probe.send_goal(self._action("/cartesian/go_to_pose_action", GoToPose),
                                   goal, 300.0).result
        result = PhaseResult(name, bool(res.success), f"{res.outcome}: {res.message}",
                             targets={"right": list(map(float, target))},
                             planned_residual={"right": float(res.solver_position_error)},
                             extra={"measured_right": float(res.arrival_position_error)},
                             sim_start=sim0)
        return self._finish(result, {"right": target}, wall0)

    def _finish(self, result: PhaseResult, targets: dict[str, np.ndarray],
                wall0: float, judge_physics: bool = True) -> PhaseResult:
        hands = self.hand_positions()
        result.physics_residual = {h: float(np.linalg.norm(hands[h] - np.asarray(p)))
                                   for h, p in targets.items()}
        result.sim_end = self.sim_time()
        result.wall_s = time.monotonic() - wall0
        far = {h: r for h, r in result.physics_residual.items() if r > self.tolerance}
        if judge_physics and result.success and far:
            result.success = False
            result.message += (f"; in the physics the hand(s) ended {far} m from the target "
                               f"(> {self.tolerance} m)")
        return result

    def move_object(self, name: str, start: np.ndarray, velocity: np.ndarray,
                    duration: float) -> tuple[float, float]:
        """Move an object from ``start`` [m] at constant ``velocity`` [m/s] for ``duration`` s
        of simulated time (/sim/move_object: the simulator moves it step by step, so the
        motion is the same at any load) and wait until it has stopped. Returns the simulated
        times [s] of the motion's start and end."""
        from icub_interfaces.srv import MoveObject

        req = MoveObject.Request()
        req.name = name
        req.pose.position.x, req.pose.position.y, req.pose.position.z = (
            float(v) for v in start)
        req.pose.orientation.w = 1.0
        req.velocity.x, req.velocity.y, req.velocity.z = (float(v) for v in velocity)
        req.duration = float(duration)
        res = self.probe.call("/sim/move_object", MoveObject, req, timeout=30.0)
        if not res.success:
            raise RuntimeError(f"move_object {name}: {res.message}")
        t0, t1 = time_to_sec(res.start), time_to_sec(res.end)
        if not self.probe.wait_for(lambda: self.sim_time() >= t1, 300.0):
            raise TimeoutError(f"move_object {name}: the simulation did not reach the end of "
                               f"the motion (t = {t1:.3f} s) in 300 s")
        return t0, t1
