"""gaze_controller: iKinGazeCtrl's role as a ROS 2 node (a thin adapter over icub_pmp.gaze).

Services
- ``/gaze/look_at`` (icub_interfaces/srv/LookAt): solve the neck and eyes that fixate the
  target (:class:`~icub_pmp.gaze.GazeController`) and publish their minimum-jerk trajectories
  on ``/joint_trajectory`` (the six head joints only: an arm trajectory in progress is not
  disturbed). A goal given while the head moves continues smoothly from the running plan.
  With ``wait`` the answer comes once the joint states show the head settled, with the
  measured fixation error.
- ``/gaze/set_tracking`` (std_srvs/SetBool): switch tracking on or off (= the ``tracking``
  parameter).

Tracking: while ``tracking`` is true, every geometry_msgs/PointStamped on ``tracking_topic``
(at most one per ``tracking_min_interval``) updates the target; the head continues from the
running plan's state (:meth:`~icub_pmp.gaze.GazeController.update`).

Subscribes ``/joint_states`` (read raw on a thread of its own,
:class:`~icub_pmp.ros.joint_state_cache.JointStateCache`; its stamps are the node's
time base, as for the impedance controller). Publishes ``/gaze/fixation_point``
(PointStamped in root_link, the point the optical axes meet at, ``fixation_rate`` Hz on the
node clock) and ``/gaze/target`` (PointStamped in root_link, each new target).

Target frames: empty or ``root_link``, or any frame of the iCub model, at the current
posture. Bad inputs (NaN, unknown frame, behind the head, too close, no joint states yet)
answer success=false with a message, or are dropped with a throttled warning on the tracking
topic; the node never dies on them. Parameters: config/gaze_controller.yaml (=
:class:`~icub_pmp.gaze.GazeControllerConfig` + :class:`~icub_pmp.gaze.GazeNodeConfig`).
"""

from __future__ import annotations

import math
import threading
import time
from typing import NamedTuple

import numpy as np
from geometry_msgs.msg import PointStamped
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from std_srvs.srv import SetBool
from trajectory_msgs.msg import JointTrajectory

from icub_interfaces.srv import LookAt
from icub_pmp.errors import IcubPmpError, InvalidInput
from icub_pmp.gaze import GAZE_JOINTS, GazeController, GazeControllerConfig, GazeNodeConfig
from icub_pmp.gaze.gaze_plan import GazePlan
from icub_pmp.ros.conversions import (
    arrays_to_trajectory,
    make_joint_state,
    point_to_array,
    sec_to_time,
)
from icub_pmp.ros.joint_state_cache import JointStateCache
from icub_pmp.ros.node_runner import spin_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.ros.subscriber_wait import subscriber_note, wait_for_subscribers
from icub_pmp.ros.trajectory_action_server import FIRST_STATE_TIMEOUT

__all__ = ["GazeControllerNode", "main"]

_CONFIGS = (GazeControllerConfig, GazeNodeConfig)
ROOT = "root_link"


class _Active(NamedTuple):
    """The plan last published, its start [s, joint-state time] and the message sent."""

    start: float
    plan: GazePlan
    trajectory: JointTrajectory


class GazeControllerNode(Node):
    """Serve /gaze/look_at and /gaze/set_tracking; publish head trajectories (module doc)."""

    def __init__(self) -> None:
        super().__init__("gaze_controller")
        self._lock = threading.Lock()
        self.params = ConfigParameters(self, _CONFIGS, on_change=self._on_config_change)
        self.gaze = GazeController(self.config)
        self._active: _Active | None = None
        self._last_track = -math.inf
        # the joint states arrive on their own thread: a look_at that waits keeps seeing them
        self._listener = JointStateCache(self)
        reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self.traj_pub = self.create_publisher(JointTrajectory, "/joint_trajectory", reliable)
        self.fixation_pub = self.create_publisher(PointStamped, "/gaze/fixation_point", 10)
        self.target_pub = self.create_publisher(PointStamped, "/gaze/target", reliable)
        self._tracking_sub = None
        self._subscribe_tracking(self.node_config.tracking_topic)
        self._fixation_timer = self.create_timer(
            1.0 / self.node_config.fixation_rate, self._on_fixation_timer)
        self.create_service(LookAt, "/gaze/look_at", self._on_look_at)
        self.create_service(SetBool, "/gaze/set_tracking", self._on_set_tracking)
        self.get_logger().info(
            f"serving /gaze/look_at and /gaze/set_tracking (tracking "
            f"{'on' if self.node_config.tracking else 'off'}, topic "
            f"{self.node_config.tracking_topic})")

    # ------------------------------------------------------------------ parameters
    @property
    def config(self) -> GazeControllerConfig:
        """The gaze controller's configuration."""
        return self.params.get(GazeControllerConfig)

    @property
    def node_config(self) -> GazeNodeConfig:
        """The node's own parameters."""
        return self.params.get(GazeNodeConfig)

    def _on_config_change(self, old: tuple, new: tuple, changed: frozenset[str]) -> None:
        config, node_config = new
        with self._lock:
            if config != old[0]:
                self.gaze = GazeController(config, self.gaze.model)
                self._active = None
        if node_config.tracking_topic != old[1].tracking_topic:
            self._subscribe_tracking(node_config.tracking_topic)
        if node_config.fixation_rate != old[1].fixation_rate:
            self.destroy_timer(self._fixation_timer)
            self._fixation_timer = self.create_timer(
                1.0 / node_config.fixation_rate, self._on_fixation_timer)
        if node_config.tracking != old[1].tracking:
            self.get_logger().info(f"tracking {'on' if node_config.tracking else 'off'} "
                                   f"({node_config.tracking_topic})")

    def _subscribe_tracking(self, topic: str) -> None:
        if self._tracking_sub is not None:
            self.destroy_subscription(self._tracking_sub)
        # best effort matches publishers of either reliability
        self._tracking_sub = self.create_subscription(
            PointStamped, topic, self._on_tracking_target, qos_profile_sensor_data)

    # ------------------------------------------------------------------ inputs
    def _joints(self, wait: float = 0.0) -> tuple[float, dict[str, float]]:
        """(time [s], {joint: position [rad]}) of the latest joint states; before the first
        one arrived, waits up to ``wait`` s of wall time for it (a request right after
        start-up, while DDS is still matching the joint-state subscription)."""
        js = self._listener.latest(wait=wait)
        if js is None:
            when = f"within {wait:g} s" if wait else "yet"
            raise InvalidInput(f"no /joint_states received {when}: the head posture is unknown "
                               "(is sim_bridge running?)")
        return js.t, js.positions

    def _target_in_root(self, msg: PointStamped, joints: dict[str, float]) -> np.ndarray:
        """The message's point [m] in root_link (frames transformed at the current posture)."""
        p = point_to_array(msg.point)
        frame = msg.header.frame_id
        if frame in ("", ROOT):
            return p
        model = self.gaze.model
        pose = model.frame_pose(model.q_from_dict(joints), frame)  # UnknownName if none
        return pose.rotation @ p + pose.translation

    # ------------------------------------------------------------------ planning
    def _look(self, msg: PointStamped, neck_traj_time: float | None, tracking: bool
              ) -> tuple[_Active, str]:
        """Plan toward the message's point, publish it; returns the plan and a note."""
        now, joints = self._joints(wait=0.0 if tracking else FIRST_STATE_TIMEOUT)
        target = self._target_in_root(msg, joints)
        act = self._active
        start = previous = None
        if act is not None:
            elapsed = now - act.start
            if 0.0 <= elapsed < act.plan.duration:
                start = act.plan.state_at(elapsed)
            if tracking:
                previous = act.plan.solution
        plan = self.gaze.plan(target, joints, start=start, previous=previous,
                              neck_traj_time=neck_traj_time)
        wait = self.node_config.subscriber_timeout
        note = subscriber_note(wait_for_subscribers(self.traj_pub, wait), wait)
        # the whole plan from its start sample (t = 0: the controller does not join it from
        # its set-point, whose velocity may differ); its stamp (the planning time, now in the
        # past when it arrives) makes the controller start it at once
        traj = arrays_to_trajectory(plan.joint_names, plan.t, plan.q, plan.qd,
                                    stamp=sec_to_time(now))
        self.traj_pub.publish(traj)
        self.target_pub.publish(self._point(plan.solution.target, now))
        active = _Active(now, plan, traj)
        self._active = active
        return active, note

    def _point(self, p: np.ndarray, t: float) -> PointStamped:
        msg = PointStamped()
        msg.header.stamp = sec_to_time(t)
        msg.header.frame_id = ROOT
        msg.point.x, msg.point.y, msg.point.z = (float(v) for v in p)
        return msg

    # ------------------------------------------------------------------ services
    def _on_look_at(self, req: LookAt.Request, res: LookAt.Response) -> LookAt.Response:
        res.measured_fixation_error = math.nan
        res.settle_time = math.nan
        res.fixation_error = math.nan
        try:
            duration = float(req.duration)
            if not (math.isfinite(duration) and duration >= 0.0):
                raise InvalidInput(f"duration: expected 0 (default) or a time > "
                                   f"eyes_traj_time [s], got {req.duration}")
            with self._lock:
                active, note = self._look(req.target, duration or None, tracking=False)
            self._fill(res, active, note)
            if req.wait:
                self._wait(active, res)
        except IcubPmpError as exc:
            res.success, res.message = False, str(exc)
            self.get_logger().warning(f"/gaze/look_at rejected: {exc}")
        except Exception as exc:  # never let a request kill the node
            res.success, res.message = False, f"internal error: {type(exc).__name__}: {exc}"
            self.get_logger().error(f"/gaze/look_at failed: {res.message}")
        return res

    def _fill(self, res: LookAt.Response, active: _Active, note: str) -> None:
        plan = active.plan
        sol = plan.solution
        res.success = True
        res.head_target = make_joint_state(GAZE_JOINTS, position=sol.positions)
        res.fixation_error = sol.fixation_error
        res.exact = sol.exact
        res.trajectory = active.trajectory
        where = np.round(sol.target, 3).tolist()
        if sol.exact:
            what = f"fixating {where} m (root_link)"
        else:
            what = (f"{where} m (root_link) cannot be fixated exactly: clipped at the limits "
                    f"of {list(sol.clipped)}, predicted fixation error "
                    f"{math.degrees(sol.fixation_error):.2f} deg")
        res.message = f"{what}; head trajectory of {plan.duration:.2f} s published{note}"
        self.get_logger().info(f"/gaze/look_at: {res.message}")

    def _wait(self, active: _Active, res: LookAt.Response) -> None:
        """Block until the joint states (the listener's thread) show the head at the plan's
        targets."""
        nc = self.node_config
        sol = active.plan.solution
        tol = np.array([nc.motion_done_neck] * 3 + [nc.motion_done_eyes] * 3)
        deadline = time.monotonic() + nc.wait_timeout
        while time.monotonic() < deadline:
            now, joints = self._joints()
            if self._active is not active:
                res.message += "; superseded by a newer target before it settled"
                return
            head = self.gaze.head_joints(joints)
            if now >= active.start and np.all(np.abs(head - sol.positions) <= tol):
                res.settle_time = now - active.start
                res.measured_fixation_error = float(
                    self.gaze.fixation_errors(joints, sol.target).max())
                res.message += (f"; settled after {res.settle_time:.2f} s, measured fixation "
                                f"error {math.degrees(res.measured_fixation_error):.3f} deg")
                return
            time.sleep(0.005)
        res.success = False
        res.message += f"; not settled within wait_timeout {nc.wait_timeout} s (wall)"

    def _on_set_tracking(self, req: SetBool.Request, res: SetBool.Response) -> SetBool.Response:
        result = self.set_parameters([Parameter("tracking", value=bool(req.data))])[0]
        res.success = bool(result.successful)
        res.message = (f"tracking {'on' if req.data else 'off'} "
                       f"({self.node_config.tracking_topic})" if result.successful
                       else result.reason)
        return res

    # ------------------------------------------------------------------ tracking, state
    def _on_tracking_target(self, msg: PointStamped) -> None:
        js = self._listener.latest()
        if not self.node_config.tracking or js is None:
            return
        now = js.t
        if now - self._last_track < self.node_config.tracking_min_interval:
            return
        try:
            with self._lock:
                self._look(msg, None, tracking=True)
            self._last_track = now
        except IcubPmpError as exc:
            self.get_logger().warning(f"tracking target dropped: {exc}",
                                      throttle_duration_sec=2.0)
        except Exception as exc:  # never die on a message
            self.get_logger().error(f"tracking target failed: {type(exc).__name__}: {exc}",
                                    throttle_duration_sec=2.0)

    def _on_fixation_timer(self) -> None:
        if self._listener.latest() is None:
            return
        try:
            now, joints = self._joints()
            p = self.gaze.fixation_point(joints)
        except IcubPmpError:
            return
        if p is not None:
            self.fixation_pub.publish(self._point(p, now))


    def destroy_node(self) -> None:
        """Stop the joint-state cache's thread, then destroy the node."""
        self._listener.close()
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp gaze_controller``): an EventsExecutor (its 1 kHz
    ``/clock`` with ``use_sim_time`` costs little there)."""
    spin_node(GazeControllerNode, args)


if __name__ == "__main__":
    main()
