"""impedance_controller: the 1 kHz joint controller (stands in for the iCub controller boards;
the core is :class:`icub_pmp.control.ImpedanceController`).

subscribes /joint_states (JointState: position + velocity), /estimated_joint_torques
           (JointState effort, from wrench_estimator), /joint_trajectory
           (trajectory_msgs/JointTrajectory, reliable), /impedance_controller/velocity_command
           (JointState: name + velocity [rad/s]; velocity mode, eq 7)
publishes  /effort_command (JointState: name + effort [N m]; in lockstep the stamp is copied
           from the /joint_states message it answers), /impedance_controller/state (JointState
           every ``state_publish_every`` steps: position = desired q_d, velocity = desired
           q_dot_d, effort = the commanded torque)
           /impedance_controller/status (icub_interfaces/ControllerStatus, reliable + transient
           local: status, safe-hold reason, ages, counters; on change and every wall second)
services   /impedance_controller/hold (std_srvs/Trigger): stop every motion, hold the last
           measured posture
actions    /impedance_controller/follow_joint_trajectory (icub_interfaces/action/
           FollowJointTrajectory): execute a trajectory with feedback and a measured result
           (:class:`~icub_pmp.ros.trajectory_action_server.TrajectoryActionServer`)

Stepping: with ``lockstep`` every /joint_states message is answered at once (with
``wait_for_estimate``, while the simulator says on /sim/status that it runs lockstep, only
once the estimate of the same stamp has arrived, or after ``estimate_timeout`` of wall time
without it: every 1 kHz step then uses the estimate of its own joint state; no waiting
before the first estimate, when the estimator runs on one sample in N > 1 (the gap between
estimates is larger than between joint states) or once the last one is older than
``estimate_timeout``, so a
stopped estimator costs no wall time and the ``estimate_lost_timeout`` safe hold comes in
simulated time; a free-running simulator does not wait for anyone, so neither does the
controller), so the 1 kHz loop is
exact in simulated time; otherwise a timer at ``rate_hz`` steps on the latest joint state.
Trajectories start at their header stamp (0 = now, a past stamp = now) in the time of the
joint states. Bad input (NaN, unknown joints, non-increasing times, points beyond the joint
limits, missing joints, faster than the joints' velocity/acceleration limits) is dropped
with a warning; the controller keeps running. Watchdogs: a 20 Hz timer on the node clock
(simulated time with ``use_sim_time``, as the everyday graph runs) trips the safe hold when
no joint state came for ``state_timeout``; a wall-clock timer trips it when none came for
``state_wall_timeout`` of wall time (the simulator is paused or gone: simulated time has
stopped, so only wall time can tell); estimates older than ``estimate_timeout`` switch the
torque loop off and none for ``estimate_lost_timeout`` latches a safe hold. Each is logged
once and shown on the status topic. A joint state older than the newest (a restarted
simulator: simulated time went back, :class:`~icub_pmp.time_jump_detector.TimeJumpDetector`)
ends the running goals, drops the old timeline's estimate and the lockstep estimate gate and
holds the measured posture; it is said in the log. All :class:`ImpedanceControllerConfig`
parameters can change at run time (validated).

In-process inputs (``in_process_inputs=True``, the composed ``torque_loop`` process of
:mod:`icub_pmp.nodes.torque_loop`): the node does not subscribe to /joint_states and
/estimated_joint_torques; whoever hosts it hands them over with :meth:`take_joint_state` (the
message's bytes) and :meth:`take_estimate` (stamp, names, torques), with the same checks and
the same lockstep gate as the subscriptions. ``effort_listener`` (set by the composed
``robot_loop`` process, :mod:`icub_sim_bridge.robot_loop_node`) gets every effort command (stamp
[ns], joint names, torques [N m]) before it is published; :meth:`set_sim_mode` tells the node
the simulator's stepping mode in-process (as /sim/status does). """

from __future__ import annotations

import time
from typing import Callable

import numpy as np
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from icub_interfaces.msg import ControllerStatus, SimStatus
from icub_pmp.control.estimate_gate import EstimateGate
from icub_pmp.control.impedance_controller import ImpedanceController
from icub_pmp.control.impedance_controller_config import ImpedanceControllerConfig
from icub_pmp.errors import IcubPmpError, InvalidInput
from icub_pmp.ros.conversions import (
    joint_state_arrays,
    time_to_sec,
    trajectory_extras,
    trajectory_to_arrays,
)
from icub_pmp.ros.node_runner import spin_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.ros.qos import LATCHED_QOS
from icub_pmp.ros.raw_messages import (
    RawJointStateReader,
    RawJointStateWriter,
    read_joint_state,
)
from icub_pmp.ros.trajectory_action_server import TrajectoryActionServer
from icub_pmp.ros.warning_throttle import WarningThrottle
from icub_pmp.time_jump_detector import TimeJumpDetector

__all__ = ["ImpedanceControllerNode", "main"]

_TRAJ_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


class ImpedanceControllerNode(Node):
    """The impedance_controller node (module doc)."""

    def __init__(self, in_process_inputs: bool = False) -> None:
        """``in_process_inputs``: joint states and estimates come by direct calls (module
        doc), not from their topics."""
        super().__init__("impedance_controller")
        self.params = ConfigParameters(self, ImpedanceControllerConfig,
                                       on_change=self._on_config_change)
        config = self.params.config
        self.controller = ImpedanceController(config)
        self.names = list(self.controller.joint_names)
        self._js_names: list[str] | None = None
        self._js_idx: np.ndarray | None = None
        self._est_names: list[str] | None = None
        self.gate: EstimateGate[tuple[float, np.ndarray, np.ndarray, int]] = EstimateGate()
        self.clock = TimeJumpDetector()  # the joint states' time going back
        self.warn = WarningThrottle(self.get_logger())  # one budget per kind of warning
        self._latest: tuple[float, np.ndarray, np.ndarray] | None = None
        self._latest_new = False
        self._t_last: float | None = None
        self._status = "no_estimate"
        self._js_wall: float | None = None
        self._status_sent: tuple | None = None
        self._status_wall = 0.0
        self.steps = 0
        self.dropped = 0
        # in-process output (module doc): the composed robot_loop process sets it
        self.effort_listener: Callable[[int, list[str], np.ndarray], None] | None = None

        sd = qos_profile_sensor_data
        self.pub_effort = self.create_publisher(JointState, "/effort_command", sd)
        self.pub_state = self.create_publisher(JointState, "/impedance_controller/state", sd)
        self._effort_writer = RawJointStateWriter(list(self.names))
        self._state_writer = RawJointStateWriter(list(self.names))
        # the two 1 kHz inputs are read from their bytes (raw_messages), not deserialised
        self._js_reader = RawJointStateReader()
        self._est_reader = RawJointStateReader()
        if not in_process_inputs:
            self.create_subscription(JointState, "/joint_states", self._on_joint_state, sd,
                                     raw=True)
            self.create_subscription(JointState, "/estimated_joint_torques", self._on_estimate,
                                     sd, raw=True)
        self.create_subscription(JointTrajectory, "/joint_trajectory", self._on_trajectory,
                                 _TRAJ_QOS)
        self.create_subscription(JointState, "/impedance_controller/velocity_command",
                                 self._on_velocity, _TRAJ_QOS)
        self.create_service(Trigger, "/impedance_controller/hold", self._on_hold)
        self._sim_mode = ""  # the simulator's stepping mode (/sim/status), "" = none seen
        # stamps [ns]: the last estimate and joint state, and the gaps before them (an
        # estimator on one sample in N leaves N - 1 joint states without their own estimate)
        self._est_ns = self._js_ns = -(2**62)
        self._est_gap_ns = self._js_gap_ns = 2**62
        self.create_subscription(SimStatus, "/sim/status", self._on_sim_status, LATCHED_QOS)
        self.pub_status = self.create_publisher(ControllerStatus, "/impedance_controller/status",
                                                LATCHED_QOS)
        self.action = TrajectoryActionServer(self, self.controller, lambda: self._t_last)
        self.create_timer(0.05, self._on_watchdog)
        # wall-clock watchdog: simulated time stops with the simulator, wall time does not
        self.create_timer(0.1, self._on_wall_watchdog,
                          clock=Clock(clock_type=ClockType.STEADY_TIME))
        # wall-clock timer: a joint state waiting for its estimate is answered without it
        # after estimate_timeout of wall time (the simulator waits for us: sim time stands)
        self.create_timer(0.005, self._on_pending_timeout,
                          clock=Clock(clock_type=ClockType.STEADY_TIME))
        self._timer = None
        self._apply_stepping(config)
        self.get_logger().info(
            f"impedance_controller: {len(self.names)} joints, mode {config.mode}, feed-forward "
            f"{config.feedforward}, torque loop {'on' if config.torque_loop else 'off'}, "
            f"{'lockstep' if config.lockstep else f'timer at {config.rate_hz} Hz'}")

    # ------------------------------------------------------------------ parameters
    def _on_config_change(self, old: ImpedanceControllerConfig, new: ImpedanceControllerConfig,
                          changed: frozenset[str]) -> None:
        self.controller.set_config(new)
        if (old.lockstep, old.rate_hz) != (new.lockstep, new.rate_hz):
            self._apply_stepping(new)
        if old.mode != new.mode:
            self.get_logger().info(f"mode {old.mode} -> {new.mode}")

    def _apply_stepping(self, cfg: ImpedanceControllerConfig) -> None:
        if self._timer is not None:
            self.destroy_timer(self._timer)
            self._timer = None
        if not cfg.lockstep:
            self._timer = self.create_timer(1.0 / cfg.rate_hz, self._on_timer)

    # ------------------------------------------------------------------ inputs
    def _warn(self, kind: str, text: str) -> None:
        self.dropped += 1
        self.warn(kind, text)

    def _on_joint_state(self, data: bytes) -> None:
        try:
            msg = read_joint_state(self._js_reader, data)
            if msg.name != self._js_names:
                self._js_idx = None
                self._js_names = list(msg.name)
            q, v, self._js_idx = joint_state_arrays(msg, self.names, self._js_idx)
            if v is None:
                raise InvalidInput("JointState has no velocities")
        except IcubPmpError as exc:
            self._js_names = None
            self._warn("joint_state", f"/joint_states dropped: {exc}")
            return
        ns = msg.stamp_ns
        self._js_wall = time.monotonic()
        jump = self.clock.observe(ns)
        if jump is not None:  # a restarted simulator: nothing of the old timeline holds
            self.gate.reset()
            self.get_logger().warning(
                f"{jump.describe()} (a simulator restart?): trajectories stopped, the old "
                "estimate forgotten, holding the measured posture", throttle_duration_sec=1.0)
        cfg = self.controller.config
        if not cfg.lockstep:
            self._latest = (ns * 1e-9, q, v)
            self._latest_new = True
            return
        sample = (ns * 1e-9, q, v, ns)
        if ns > self._js_ns:
            self._js_gap_ns, self._js_ns = ns - self._js_ns, ns
        age = self.controller.estimate_age(ns * 1e-9)
        if (cfg.wait_for_estimate and cfg.torque_loop and self._sim_mode == "lockstep"
                and 0.0 <= age <= cfg.estimate_timeout  # estimates come
                and 2 * self._est_gap_ns <= 3 * self._js_gap_ns):  # one per joint state
            sample = self.gate.offer(ns, sample)
            if sample is None:
                return  # waits for its estimate
        self._step(*sample)

    def _on_sim_status(self, msg: SimStatus) -> None:
        """Follow the simulator's stepping mode (``wait_for_estimate`` acts in lockstep)."""
        self.set_sim_mode(msg.mode)

    def set_sim_mode(self, mode: str) -> None:
        """The simulator's stepping mode (``lockstep`` or ``free_run``), from /sim/status or
        in-process."""
        if mode != self._sim_mode:
            waits = (mode == "lockstep" and self.controller.config.wait_for_estimate
                     and self.controller.config.torque_loop)
            what = "each joint state waits for its estimate" if waits else \
                "joint states do not wait for estimates"
            self.get_logger().info(f"simulator mode {mode!r}: {what}")
            self._sim_mode = mode
            if not waits:
                held = self.gate.expired(-1.0)  # answer a held joint state at once
                if held is not None:
                    self._step(*held)

    def take_joint_state(self, data: bytes) -> None:
        """A /joint_states message (its CDR bytes) handed over in-process (module doc)."""
        self._on_joint_state(data)

    def take_estimate(self, stamp_ns: int, names: list[str], tau: np.ndarray) -> None:
        """The joint torques ``tau`` [N m] of ``names`` estimated for the joint state stamped
        ``stamp_ns`` [ns], handed over in-process (module doc)."""
        try:
            self.controller.set_estimate(stamp_ns * 1e-9, names, tau)
        except IcubPmpError as exc:
            self._warn("estimate", f"in-process estimate dropped: {exc}")
            return
        self._estimate_arrived(stamp_ns)

    def _on_estimate(self, data: bytes) -> None:
        try:
            msg = read_joint_state(self._est_reader, data)
            tau = msg.effort
            if tau.shape != (len(msg.name),):
                raise InvalidInput(f"effort has {tau.size} values for {len(msg.name)} names")
            ns = msg.stamp_ns
            self.controller.set_estimate(ns * 1e-9, msg.name, tau)
        except IcubPmpError as exc:
            self._warn("estimate", f"/estimated_joint_torques dropped: {exc}")
            return
        self._estimate_arrived(ns)

    def _estimate_arrived(self, ns: int) -> None:
        """The estimate stamped ``ns`` is stored: step the joint state waiting for it."""
        if ns > self._est_ns:
            self._est_gap_ns, self._est_ns = ns - self._est_ns, ns
        sample = self.gate.estimate(ns)
        if sample is not None:
            self._step(*sample)

    def _on_trajectory(self, msg: JointTrajectory) -> None:
        try:
            if self._t_last is None:
                raise InvalidInput("no joint state received yet")
            names, times, pos, vel = trajectory_to_arrays(msg, self.names)
            acc, eff = trajectory_extras(msg)
            start = time_to_sec(msg.header.stamp) or self._t_last
            traj = self.controller.make_trajectory(names, times, pos, vel, acc, eff, start)
            self.controller.set_trajectory(traj, self._t_last)
        except IcubPmpError as exc:
            self.dropped += 1
            self.get_logger().warning(f"/joint_trajectory rejected: {exc}")
            return
        self.get_logger().info(
            f"trajectory: {len(names)} joints, {len(times)} points, {times[-1]:.2f} s",
            throttle_duration_sec=1.0)

    def _on_velocity(self, msg: JointState) -> None:
        try:
            if self._t_last is None:
                raise InvalidInput("no joint state received yet")
            if len(msg.velocity) != len(msg.name):
                raise InvalidInput(
                    f"{len(msg.velocity)} velocities for {len(msg.name)} joint names")
            self.controller.set_velocity_command(list(msg.name), np.asarray(msg.velocity),
                                                 self._t_last)
        except IcubPmpError as exc:
            self._warn("velocity", f"/impedance_controller/velocity_command rejected: {exc}")

    def _on_hold(self, request: Trigger.Request, response: Trigger.Response
                 ) -> Trigger.Response:
        if self._t_last is None:
            response.success = False
            response.message = "no joint state received yet: nothing to hold"
            return response
        self.controller.hold()
        response.success = True
        response.message = "holding the last measured posture"
        self.get_logger().info(response.message)
        return response

    # ------------------------------------------------------------------ status
    def _publish_status(self, force: bool = False) -> None:
        c = self.controller
        reason = c.safe_hold_reason or ""
        status = "safe_hold" if c.safe_hold else self._status
        key = (status, reason, len(c.goals))
        now = time.monotonic()
        if not force and key == self._status_sent and now - self._status_wall < 1.0:
            return
        self._status_sent, self._status_wall = key, now
        m = ControllerStatus()
        t = self._t_last or 0.0
        m.header.stamp.sec = int(t)
        m.header.stamp.nanosec = int(round((t - int(t)) * 1e9)) % 1_000_000_000
        m.status = status
        m.safe_hold_reason = reason
        m.joint_state_wall_age = -1.0 if self._js_wall is None else now - self._js_wall
        m.estimate_age = c.estimate_age(t) if self._t_last is not None else -1.0
        m.steps = self.steps
        m.stale_estimate_steps = c.stale_estimate_steps
        m.active_goals = len(c.goals)
        m.lockstep = c.config.lockstep
        m.mode = c.config.mode
        self.pub_status.publish(m)

    def _on_wall_watchdog(self) -> None:
        timeout = self.controller.config.state_wall_timeout
        if (timeout > 0 and self._js_wall is not None and not self.controller.safe_hold
                and time.monotonic() - self._js_wall > timeout):
            reason = (f"no joint state for {timeout:g} s of wall time: the simulator is "
                      "paused or gone")
            self.controller.enter_safe_hold(reason)
            self.action.resolve()
            self.get_logger().warning(f"{reason}; safe hold at the last measured posture "
                                      "(motions aborted)")
        self._publish_status()

    # ------------------------------------------------------------------ stepping
    def _on_timer(self) -> None:
        # free-running: step on the latest joint state; in safe hold, wait for a new one
        if self._latest is None or (self.controller.safe_hold and not self._latest_new):
            return
        self._latest_new = False
        t, q, v = self._latest
        self._step(t, q, v, self.get_clock().now().nanoseconds)

    def _on_pending_timeout(self) -> None:
        sample = self.gate.expired(self.controller.config.estimate_timeout)
        if sample is not None:
            self._warn("pending", "no estimate for the pending joint state: answered without it")
            self._step(*sample)

    def _on_watchdog(self) -> None:
        now = self.get_clock().now().nanoseconds * 1e-9
        if self.controller.check_watchdog(now):
            self.action.resolve()
            self._publish_status(force=True)
            self.get_logger().warning(
                f"no joint state for {self.controller.config.state_timeout} s: safe hold at "
                "the last measured posture (motions aborted)")

    def _step(self, t: float, q: np.ndarray, v: np.ndarray, stamp_ns: int) -> None:
        """One control step on the joint state of time ``t`` [s]; the effort command is
        stamped ``stamp_ns`` [ns] (lockstep: the joint state's own stamp)."""
        was_safe = self.controller.safe_hold
        try:
            out = self.controller.step(t, q, v)
        except IcubPmpError as exc:
            self._warn("step", f"control step at t = {t:.3f} s skipped: {exc}")
            return
        self._t_last = t
        self.steps += 1
        if self.effort_listener is not None:  # in-process: before it is published
            self.effort_listener(stamp_ns, self.names, out.tau)
        # serialised directly (raw_messages): the names are encoded once
        self.pub_effort.publish(self._effort_writer.write(
            stamp_ns, effort=out.tau))
        self.action.resolve(feedback=self.steps % self.controller.config.feedback_every == 0)
        if was_safe and not self.controller.safe_hold:
            self.get_logger().info("safe hold released: holding the measured posture")
        elif self.controller.safe_hold and not was_safe:
            self.get_logger().warning(f"safe hold: {self.controller.safe_hold_reason}")
        self._publish_status()
        if out.status != self._status:
            # throttled: a starved estimator on a loaded machine makes the status flap
            text = f"torque loop: {self._status} -> {out.status}"
            if out.status == "ok":
                self.get_logger().info(text, throttle_duration_sec=5.0)
            else:
                self.get_logger().warning(text, throttle_duration_sec=5.0)
            self._status = out.status
        every = self.controller.config.state_publish_every
        if every and self.steps % every == 0:
            self.pub_state.publish(self._state_writer.write(
                stamp_ns, out.setpoint.q, out.setpoint.v, out.tau))


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp impedance_controller``)."""
    spin_node(ImpedanceControllerNode, args, "impedance_controller")


if __name__ == "__main__":
    main()
