"""TrajectoryActionServer: the impedance controller's FollowJointTrajectory action
(``/impedance_controller/follow_joint_trajectory``, icub_interfaces/action/
FollowJointTrajectory), an adapter over :meth:`ImpedanceController.execute`.

Every goal is accepted. A goal that arrives before the controller's first joint state (right
after a restart the action server is often discovered before the simulator's joint states
reach the controller) waits for it up to ``FIRST_STATE_TIMEOUT`` of wall time. A goal that
cannot start (unknown joints, NaN, points beyond the joint
limits, faster than the joints' velocity/acceleration limits, a safe hold) ends at once with
``INVALID_GOAL`` / ``INVALID_JOINTS`` and the reason in ``error_string``, so a client always
learns why. A running goal ends as its :class:`~icub_pmp.control.trajectory_goal.
TrajectoryGoal` decides (success, preemption, tolerances, safe hold); a cancel request holds
the measured posture of its joints. The execute callbacks are coroutines awaiting a future
that :meth:`resolve` completes from the control loop, so the server runs on the controller's
single-threaded executor next to the 1 kHz loop.
"""

from __future__ import annotations

from typing import Callable

from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.task import Future

from icub_interfaces.action import FollowJointTrajectory
from icub_pmp.control.impedance_controller import ImpedanceController
from icub_pmp.control.trajectory_goal import GoalCode, GoalOutcome, TrajectoryGoal
from icub_pmp.errors import IcubPmpError, UnknownName
from icub_pmp.ros.conversions import time_to_sec, trajectory_extras, trajectory_to_arrays

__all__ = ["TrajectoryActionServer", "ACTION_NAME", "FIRST_STATE_TIMEOUT"]

ACTION_NAME = "/impedance_controller/follow_joint_trajectory"
#: how long a goal that came before the first joint state waits for it [s] of wall time
#: (a restarted node matched the simulator after up to ~4 s at load 10: bench/cli_discovery.py)
FIRST_STATE_TIMEOUT = 10.0


class TrajectoryActionServer:
    """FollowJointTrajectory on ``node`` for ``controller``; ``now()`` gives the time of the
    latest joint state [s] (None before the first)."""

    def __init__(self, node: Node, controller: ImpedanceController,
                 now: Callable[[], float | None], name: str = ACTION_NAME):
        self.node = node
        self.controller = controller
        self.now = now
        self._running: dict[int, tuple[TrajectoryGoal, object, Future]] = {}
        self._first_state: list[Future] = []  # goals waiting for the first joint state
        self._steps = 0
        self.server = ActionServer(
            node, FollowJointTrajectory, name, execute_callback=self._execute,
            goal_callback=lambda _goal: GoalResponse.ACCEPT,
            cancel_callback=lambda _handle: CancelResponse.ACCEPT)

    # ------------------------------------------------------------------ goals
    async def _execute(self, handle) -> FollowJointTrajectory.Result:
        goal = handle.request
        result = FollowJointTrajectory.Result()
        result.joint_names = list(goal.trajectory.joint_names)
        t_now = self.now()
        if t_now is None:
            t_now = await self._wait_first_state()
        try:
            if t_now is None:
                raise IcubPmpError(f"no joint state received within {FIRST_STATE_TIMEOUT:g} s "
                                   "of wall time (is the simulator running?)")
            names, times, pos, vel = trajectory_to_arrays(goal.trajectory,
                                                          self.controller.joint_names)
            acc, eff = trajectory_extras(goal.trajectory)
            start = time_to_sec(goal.trajectory.header.stamp) or t_now
            traj = self.controller.make_trajectory(names, times, pos, vel, acc, eff, start)
            tg = self.controller.execute(traj, t_now, goal.path_tolerance,
                                         goal.goal_tolerance, goal.goal_time_tolerance)
        except IcubPmpError as exc:
            result.error_code = (GoalCode.INVALID_JOINTS if isinstance(exc, UnknownName)
                                 else GoalCode.INVALID_GOAL)
            result.error_string = str(exc)
            self.node.get_logger().warning(f"follow_joint_trajectory goal refused: {exc}")
            handle.abort()
            return result
        done: Future = Future()
        self._running[tg.goal_id] = (tg, handle, done)
        self.node.get_logger().info(
            f"follow_joint_trajectory: {len(tg.joint_names)} joints, "
            f"{tg.end - tg.start:.2f} s", throttle_duration_sec=1.0)
        outcome: GoalOutcome = await done
        result.error_code = outcome.code
        result.error_string = outcome.message
        result.final_error = outcome.final_error.tolist()
        result.execution_time = outcome.execution_time
        if outcome.code == GoalCode.SUCCESSFUL:
            handle.succeed()
        elif outcome.code == GoalCode.CANCELED and handle.is_cancel_requested:
            handle.canceled()
        else:
            handle.abort()
            self.node.get_logger().warning(f"follow_joint_trajectory aborted: "
                                           f"{outcome.message}")
        return result

    async def _wait_first_state(self) -> float | None:
        """The time of the first joint state once it came, None after FIRST_STATE_TIMEOUT."""
        fut: Future = Future()
        self._first_state.append(fut)
        timer = self.node.create_timer(
            FIRST_STATE_TIMEOUT, lambda: fut.done() or fut.set_result(None),
            clock=Clock(clock_type=ClockType.STEADY_TIME))
        try:
            await fut
        finally:
            self.node.destroy_timer(timer)
        return self.now()

    # ------------------------------------------------------------------ from the loop
    def resolve(self, feedback: bool = False) -> None:
        """Complete the goals that ended, act on cancel requests and (``feedback``) publish
        the running goals' feedback. Call after every control step and safe hold."""
        if self._first_state and self.now() is not None:
            for fut in self._first_state:
                if not fut.done():
                    fut.set_result(None)
            self._first_state.clear()
        if not self._running:
            return
        for gid, (tg, handle, done) in list(self._running.items()):
            if not tg.done and handle.is_cancel_requested:
                self.controller.cancel(tg)
            if tg.done:
                del self._running[gid]
                if not done.done():
                    done.set_result(tg.outcome)
            elif feedback and tg.feedback is not None:
                fb = FollowJointTrajectory.Feedback()
                f = tg.feedback
                fb.joint_names = list(tg.joint_names)
                fb.desired = f.desired.tolist()
                fb.actual = f.actual.tolist()
                fb.error = f.error.tolist()
                fb.time_from_start = f.time_from_start
                fb.time_to_go = f.time_to_go
                handle.publish_feedback(fb)
