"""TrajectoryActionServer: the impedance controller's FollowJointTrajectory action
(``/impedance_controller/follow_joint_trajectory``, icub_interfaces/action/
FollowJointTrajectory), an adapter over :meth:`ImpedanceController.execute`.

Every goal is accepted; a goal that cannot start (unknown joints, NaN, points beyond the joint
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
from rclpy.node import Node
from rclpy.task import Future

from icub_interfaces.action import FollowJointTrajectory
from icub_pmp.control.impedance_controller import ImpedanceController
from icub_pmp.control.trajectory_goal import GoalCode, GoalOutcome, TrajectoryGoal
from icub_pmp.errors import IcubPmpError, UnknownName
from icub_pmp.ros.conversions import time_to_sec, trajectory_extras, trajectory_to_arrays

__all__ = ["TrajectoryActionServer", "ACTION_NAME"]

ACTION_NAME = "/impedance_controller/follow_joint_trajectory"


class TrajectoryActionServer:
    """FollowJointTrajectory on ``node`` for ``controller``; ``now()`` gives the time of the
    latest joint state [s] (None before the first)."""

    def __init__(self, node: Node, controller: ImpedanceController,
                 now: Callable[[], float | None], name: str = ACTION_NAME):
        self.node = node
        self.controller = controller
        self.now = now
        self._running: dict[int, tuple[TrajectoryGoal, object, Future]] = {}
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
        try:
            t_now = self.now()
            if t_now is None:
                raise IcubPmpError("no joint state received yet")
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

    # ------------------------------------------------------------------ from the loop
    def resolve(self, feedback: bool = False) -> None:
        """Complete the goals that ended, act on cancel requests and (``feedback``) publish
        the running goals' feedback. Call after every control step and safe hold."""
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
