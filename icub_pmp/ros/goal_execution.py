"""GoalExecution: the execution half of a Cartesian goal action (pmp_planner's reach,
cartesian_solver's go-to-pose), shared by both nodes.

Given a planned ``trajectory_msgs/JointTrajectory`` and the hand targets, :meth:`run` (a
coroutine, awaited from an action server's execute callback):

1. sends the trajectory to the impedance controller's FollowJointTrajectory action and waits
   for it to be accepted (a missing controller is an abort with a clear reason);
2. while the controller executes it, publishes feedback about every ``feedback_period`` s:
   the phase, the hands' distances to their targets measured from /joint_states (forward
   kinematics of the measured joints), the time to go;
3. honours a cancel request (the controller holds the measured posture) and a preemption by a
   newer goal of the same server;
4. after the controller's result, waits until the hands have settled
   (:class:`~icub_pmp.control.arrival_monitor.ArrivalMonitor`) and judges the arrival on the
   measured hands.

:meth:`run_closed_loop` executes instead with a velocity law closed on the measured joints
(the cartesianController's way, :class:`~icub_pmp.cartesian.min_jerk_velocity_law.
MinJerkVelocityLaw`): a timer on the node's clock (simulated time) runs the law every period
and publishes the joint velocities on ``/impedance_controller/velocity_command`` (eq 7) until
the hands have settled, then the arrival is judged the same way.

Everything runs on the node's executor thread: waiting is done by awaiting futures that a
wall-clock timer completes (no blocking, no extra threads).
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Callable, Mapping, NamedTuple, Protocol

import numpy as np
from rclpy.action import ActionClient
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.task import Future
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from icub_interfaces.action import FollowJointTrajectory
from icub_pmp.control.arrival_monitor import Arrival, ArrivalConfig, ArrivalMonitor
from icub_pmp.control.trajectory_goal import GoalCode
from icub_pmp.errors import InvalidInput
from icub_pmp.ros.joint_state_cache import JointStateCache, MeasuredState

__all__ = ["GoalExecution", "ExecutionOutcome", "CONTROLLER_ACTION", "VELOCITY_TOPIC",
           "VelocityLaw", "end_goal", "arrival_config"]

#: the impedance controller's trajectory-execution action
CONTROLLER_ACTION = "/impedance_controller/follow_joint_trajectory"
#: the impedance controller's velocity-mode input (eq 7)
VELOCITY_TOPIC = "/impedance_controller/velocity_command"

_CODE_NAMES = {v: k for k, v in vars(GoalCode).items() if isinstance(v, int)}


class ExecutionOutcome(NamedTuple):
    """How an executed goal ended: ``outcome`` (reached | not_reached | aborted | canceled),
    a one-line ``message``, the arrival judgement (None when the motion did not complete) and
    the execution time from sending to the judgement [s, joint states' clock]."""

    outcome: str
    message: str
    arrival: Arrival | None
    execution_time: float

    @property
    def success(self) -> bool:
        return self.outcome == "reached"


FeedbackFn = Callable[[str, Mapping[str, float], float, float], None]
HandsFn = Callable[[MeasuredState], Mapping[str, np.ndarray]]
#: measured state -> the full model configuration (nq,) [rad]
ConfigurationFn = Callable[[MeasuredState], np.ndarray]


class VelocityLaw(Protocol):
    """What :meth:`GoalExecution.run_closed_loop` runs: ``period`` [s], ``joint_names``,
    ``command(q_full) -> (n,) joint velocities [rad/s]``."""

    period: float
    joint_names: tuple[str, ...]

    def command(self, q_full: np.ndarray) -> np.ndarray: ...


class GoalExecution:
    """Execution of planned trajectories for one action server of ``node``.

    ``hands``: measured state -> {hand: (3,) position [m]} (forward kinematics);
    ``server_timeout``: wall time to wait for the controller's action server (and after
    which a vanished server aborts the goal) [s]; ``stale_timeout``: wall time without
    joint states that aborts a running goal [s].
    """

    def __init__(self, node: Node, joint_states: JointStateCache, hands: HandsFn,
                 action: str = CONTROLLER_ACTION, server_timeout: float = 5.0,
                 feedback_period: float = 0.1, stale_timeout: float = 5.0,
                 callback_group=None):
        self.node = node
        self.joint_states = joint_states
        self.hands = hands
        self.server_timeout = float(server_timeout)
        self.feedback_period = float(feedback_period)
        self.stale_timeout = float(stale_timeout)
        self.client = ActionClient(node, FollowJointTrajectory, action,
                                   callback_group=callback_group)
        self._ticks: list[Future] = []
        self._generation = 0
        self._callback_group = callback_group
        self._law: tuple[VelocityLaw, ConfigurationFn] | None = None
        self._law_timer = None
        self._velocity_pub = None
        self.law_steps = 0  # periods the running law has commanded
        node.create_timer(0.02, self._on_tick, callback_group=callback_group,
                          clock=Clock(clock_type=ClockType.STEADY_TIME))

    # ------------------------------------------------------------------ waiting
    def _on_tick(self) -> None:
        ticks, self._ticks = self._ticks, []
        for f in ticks:
            if not f.done():
                f.set_result(None)

    async def sleep(self) -> None:
        """Yield to the executor until the next tick (about 20 ms of wall time)."""
        f = Future()
        self._ticks.append(f)
        await f

    def preempt_running(self) -> int:
        """Mark every running :meth:`run` as preempted by a newer goal; returns the new
        generation (pass it to :meth:`run`)."""
        self._generation += 1
        return self._generation

    # ------------------------------------------------------------------ the run
    async def run(self, trajectory: JointTrajectory, targets: Mapping[str, np.ndarray],
                  arrival: ArrivalConfig, feedback: FeedbackFn,
                  cancel_requested: Callable[[], bool], generation: int,
                  goal_tolerance: float = 0.0) -> ExecutionOutcome:
        """Execute ``trajectory`` and judge the arrival of ``targets`` (see module doc).

        ``feedback(phase, hand_errors, time_to_go, progress)`` is called about every
        ``feedback_period`` s; ``cancel_requested()`` is polled; ``generation`` is the value
        :meth:`preempt_running` returned for this goal (a newer one preempts it)."""
        t_start = self._sim_now()
        start_wall = time.monotonic()
        while not self.client.server_is_ready():
            if time.monotonic() - start_wall > self.server_timeout:
                return ExecutionOutcome(
                    "aborted", f"the controller's action {self.client._action_name} is not "
                    f"available after {self.server_timeout:g} s (is impedance_controller "
                    f"running?)", None, 0.0)
            await self.sleep()
        goal = FollowJointTrajectory.Goal()
        goal.trajectory = trajectory
        if goal_tolerance > 0:
            goal.goal_tolerance = [float(goal_tolerance)]
        sent = self.client.send_goal_async(goal)
        while not sent.done():
            await self.sleep()
        handle = sent.result()
        if handle is None or not handle.accepted:
            return ExecutionOutcome("aborted", "the controller rejected the trajectory", None,
                                    0.0)
        result_future = handle.get_result_async()
        duration = _duration(trajectory)
        monitor = ArrivalMonitor(targets, arrival)
        t0 = self._sim_now() if t_start is None else t_start
        last_fb = 0.0
        canceled = preempted = False
        gone_since: float | None = None
        while not result_future.done():
            # the controller's server gone (node killed): its result will never come
            if not self.client.server_is_ready():
                gone_since = gone_since or time.monotonic()
                if time.monotonic() - gone_since > self.server_timeout:
                    return ExecutionOutcome(
                        "aborted", "impedance_controller is gone (its action server "
                        f"disappeared for {self.server_timeout:g} s): the motion's state is "
                        "unknown", self._judge_now(monitor), 0.0)
            else:
                gone_since = None
            if self.joint_states.wall_age() > self.stale_timeout:
                return ExecutionOutcome(
                    "aborted", f"no /joint_states for {self.stale_timeout:g} s of wall time "
                    "(simulator paused or gone)", self._judge_now(monitor), 0.0)
            if cancel_requested() and not canceled:
                canceled = True
                handle.cancel_goal_async()
            if generation != self._generation and not preempted:
                preempted = True  # the newer goal's trajectory takes the joints over
            now = time.monotonic()
            if now - last_fb >= self.feedback_period:
                last_fb = now
                st = self._observe(monitor)
                if st is not None and t0 is not None:
                    elapsed = st.t - t0
                    feedback("executing", monitor.errors, max(0.0, duration - elapsed),
                             min(1.0, elapsed / duration) if duration > 0 else 1.0)
            await self.sleep()
        res = result_future.result()
        code = res.result.error_code if res is not None else GoalCode.INVALID_GOAL
        text = res.result.error_string if res is not None else "no result"
        t_end = self._sim_now()
        elapsed = (t_end - t0) if (t_end is not None and t0 is not None) else 0.0
        if canceled or code == GoalCode.CANCELED:
            return ExecutionOutcome("canceled", "canceled: the arms hold where they are",
                                    self._judge_now(monitor), elapsed)
        if preempted or generation != self._generation:
            return ExecutionOutcome("aborted", "preempted by a new goal", None, elapsed)
        if code not in (GoalCode.SUCCESSFUL, GoalCode.GOAL_TOLERANCE_VIOLATED):
            name = _CODE_NAMES.get(code, str(code))
            return ExecutionOutcome("aborted", f"the controller aborted the motion ({name}): "
                                    f"{text}", self._judge_now(monitor), elapsed)
        # settle, then judge on the measured hands
        monitor.set_end(t_end if t_end is not None else math.inf)
        while True:
            st = self._observe(monitor)
            if monitor.settled():
                break
            if cancel_requested():
                return ExecutionOutcome("canceled", "canceled while settling",
                                        self._judge_now(monitor), elapsed)
            if generation != self._generation:
                return ExecutionOutcome("aborted", "preempted by a new goal", None, elapsed)
            if st is None or self.joint_states.wall_age() > self.stale_timeout:
                return ExecutionOutcome(
                    "aborted", f"no /joint_states for {self.stale_timeout:g} s of wall time "
                    "while settling (simulator paused or gone)", self._judge_now(monitor),
                    elapsed)
            now = time.monotonic()
            if now - last_fb >= self.feedback_period:
                last_fb = now
                feedback("settling", monitor.errors, 0.0, 1.0)
            await self.sleep()
        verdict = monitor.judge()
        t_fin = self._sim_now()
        elapsed = (t_fin - t0) if (t_fin is not None and t0 is not None) else elapsed
        errs = ", ".join(f"{h} {e * 1e3:.1f} mm" for h, e in verdict.errors.items())
        if verdict.reached:
            return ExecutionOutcome("reached", f"reached: measured arrival error {errs}",
                                    verdict, elapsed)
        extra = "" if code == GoalCode.SUCCESSFUL else f" (controller: {text})"
        return ExecutionOutcome(
            "not_reached", f"not reached: measured arrival error {errs} (tolerance "
            f"{arrival.arrival_tolerance * 1e3:.1f} mm){extra}", verdict, elapsed)

    # ------------------------------------------------------------------ closed loop
    def _on_law_period(self) -> None:
        """One period of the running velocity law (timer on the node's clock)."""
        if self._law is None:
            return
        law, configuration = self._law
        st = self.joint_states.latest()
        if st is None:
            return
        try:
            qd = law.command(configuration(st))
        except Exception as exc:  # a law that fails stops: the controller holds
            self.node.get_logger().error(f"velocity law stopped: {exc!r}")
            self._stop_law()
            return
        self._publish_velocity(law.joint_names, qd)
        self.law_steps += 1

    def _publish_velocity(self, names: tuple[str, ...], qd: np.ndarray) -> None:
        msg = JointState()
        msg.header.stamp = self.node.get_clock().now().to_msg()
        msg.name = list(names)
        msg.velocity = [float(v) for v in qd]
        self._velocity_pub.publish(msg)

    def _stop_law(self) -> None:
        """Stop commanding: zero velocities once (the controller holds its set-point)."""
        if self._law is not None:
            law = self._law[0]
            self._law = None
            self._publish_velocity(law.joint_names, np.zeros(len(law.joint_names)))

    async def run_closed_loop(self, law: VelocityLaw, configuration: ConfigurationFn,
                              duration: float, targets: Mapping[str, np.ndarray],
                              arrival: ArrivalConfig, feedback: FeedbackFn,
                              cancel_requested: Callable[[], bool],
                              generation: int) -> ExecutionOutcome:
        """Run ``law`` (started by the caller) every ``law.period`` s of the node's clock on
        the measured joints (``configuration`` maps a measured state to the model's q) until
        the hands of ``targets`` have settled after ``duration`` [s], then judge the arrival
        (module doc). Cancel and preemption stop the law at once (the arm holds)."""
        if self._velocity_pub is None:
            self._velocity_pub = self.node.create_publisher(JointState, VELOCITY_TOPIC, 10)
        if self._law_timer is None or self._law_timer.timer_period_ns != int(law.period * 1e9):
            if self._law_timer is not None:
                self.node.destroy_timer(self._law_timer)
            self._law_timer = self.node.create_timer(
                law.period, self._on_law_period, callback_group=self._callback_group)
        start_wall = time.monotonic()
        while self._velocity_pub.get_subscription_count() == 0:
            if time.monotonic() - start_wall > self.server_timeout:
                return ExecutionOutcome(
                    "aborted", f"nobody subscribes to {VELOCITY_TOPIC} after "
                    f"{self.server_timeout:g} s (is impedance_controller running?)", None, 0.0)
            await self.sleep()
        monitor = ArrivalMonitor(targets, arrival)
        t0 = self._sim_now()
        if t0 is None:
            return ExecutionOutcome("aborted", "no /joint_states: the posture is unknown",
                                    None, 0.0)
        monitor.set_end(t0 + duration)
        self.law_steps = 0
        self._law = (law, configuration)
        last_fb = 0.0
        try:
            while True:
                st = self._observe(monitor)
                if cancel_requested():
                    return ExecutionOutcome("canceled", "canceled: the arms hold where they "
                                            "are", self._judge_now(monitor), st.t - t0)
                if generation != self._generation:
                    return ExecutionOutcome("aborted", "preempted by a new goal", None,
                                            st.t - t0)
                if self.joint_states.wall_age() > self.stale_timeout:
                    return ExecutionOutcome(
                        "aborted", f"no /joint_states for {self.stale_timeout:g} s of wall "
                        "time (simulator paused or gone)", self._judge_now(monitor),
                        st.t - t0)
                if monitor.settled():
                    break
                now = time.monotonic()
                if now - last_fb >= self.feedback_period:
                    last_fb = now
                    elapsed = st.t - t0
                    feedback("executing" if elapsed < duration else "settling",
                             monitor.errors, max(0.0, duration - elapsed),
                             min(1.0, elapsed / duration) if duration > 0 else 1.0)
                await self.sleep()
        finally:
            if self._law is not None and self._law[0] is law:
                self._stop_law()
        verdict = monitor.judge()
        t_fin = self._sim_now()
        elapsed = t_fin - t0 if t_fin is not None else duration
        errs = ", ".join(f"{h} {e * 1e3:.1f} mm" for h, e in verdict.errors.items())
        if verdict.reached:
            return ExecutionOutcome("reached", f"reached: measured arrival error {errs} "
                                    f"(closed loop, {self.law_steps} velocity commands)",
                                    verdict, elapsed)
        return ExecutionOutcome(
            "not_reached", f"not reached: measured arrival error {errs} (tolerance "
            f"{arrival.arrival_tolerance * 1e3:.1f} mm, closed loop)", verdict, elapsed)

    # ------------------------------------------------------------------ helpers
    def _sim_now(self) -> float | None:
        st = self.joint_states.latest()
        return None if st is None else st.t

    def _observe(self, monitor: ArrivalMonitor) -> MeasuredState | None:
        st = self.joint_states.latest()
        if st is not None:
            monitor.update(st.t, self.hands(st))
        return st

    def _judge_now(self, monitor: ArrivalMonitor) -> Arrival | None:
        self._observe(monitor)
        try:
            return monitor.judge()
        except Exception:
            return None


def end_goal(node: Node, handle, result, outcome: str, message: str, what: str):  # noqa: ANN001, ANN201
    """End a Cartesian goal (its ``result`` has ``outcome``, ``message``, ``success``):
    succeeded when ``outcome`` is 'reached', canceled when a cancel was asked, else aborted;
    logged (``what``: the action and goal) and returned."""
    result.outcome, result.message = outcome, message
    result.success = outcome == "reached"
    if result.success:
        handle.succeed()
    elif outcome == "canceled" and handle.is_cancel_requested:
        handle.canceled()
    else:
        handle.abort()
    text = f"{what}: {outcome}: {message}"
    if result.success:
        node.get_logger().info(text)
    else:
        node.get_logger().warning(text)
    return result


def arrival_config(base: ArrivalConfig, tolerance: float) -> ArrivalConfig:
    """``base`` with a goal's ``arrival_tolerance`` [m] (0 = keep the base's); raises
    InvalidInput on a negative or non-finite one."""
    tol = float(tolerance)
    if not math.isfinite(tol) or tol < 0:
        raise InvalidInput(f"arrival_tolerance: expected a finite distance >= 0 m "
                           f"(0 = default), got {tolerance}")
    return dataclasses.replace(base, arrival_tolerance=tol) if tol > 0 else base


def _duration(traj: JointTrajectory) -> float:
    if not traj.points:
        return 0.0
    d = traj.points[-1].time_from_start
    return d.sec + d.nanosec * 1e-9
