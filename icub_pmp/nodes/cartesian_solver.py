"""cartesian_solver: the iKinCartesianSolver + cartesianController role as a ROS 2 node.

Services
- ``/cartesian/solve_pose`` (icub_interfaces/srv/SolvePose): eq 11 solved by IPOPT
  (:class:`~icub_pmp.cartesian.IkSolver`); answers joints, residuals, solve time; moves nothing.
- ``/cartesian/go_to_pose`` (icub_interfaces/srv/GoToPose): the same solve, then a
  multi-referential minimum-jerk trajectory published on ``/joint_trajectory`` for the
  impedance controller (:class:`~icub_pmp.cartesian.CartesianController`: a goal given while a
  trajectory of the same chain runs starts from that trajectory's state at the current time,
  so the motion bends smoothly toward the new target).

Action ``/cartesian/go_to_pose_action`` (icub_interfaces/action/GoToPose): the same plan,
executed through the impedance controller's FollowJointTrajectory action, with feedback (the
hand's distance to the target measured from /joint_states) and a result measured on the robot
after the hand settled (:class:`~icub_pmp.ros.goal_execution.GoalExecution`). With
``execution: closed_loop`` the action runs the generator fed back with the measured joints
every period (the cartesianController's scheme, Fig 8 of the reaching paper:
:class:`~icub_pmp.cartesian.min_jerk_velocity_law.MinJerkVelocityLaw`) and sends joint
velocities on ``/impedance_controller/velocity_command`` instead. The service
answers "sent", never "reached". Trajectories faster than the joints' velocity/acceleration
limits (config/robot.yaml) are slowed down to them, and the answer says so.

Subscribes ``/joint_states`` (start configuration). Parameters: the fields of
:class:`IkConfig`, :class:`MinJerkConfig`, :class:`CartesianNodeConfig` and
:class:`~icub_pmp.control.arrival_monitor.ArrivalConfig` (config/cartesian_solver.yaml),
validated when set at run time. Bad requests answer ``success=false`` with a message (and the
residual when a solve ran); the node never dies on them, and IPOPT is bounded in iterations
and wall time.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np
from geometry_msgs.msg import Point
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from icub_interfaces.action import GoToPose as GoToPoseAction
from icub_interfaces.srv import GoToPose, SolvePose
from icub_pmp.cartesian import (
    CartesianController,
    IkConfig,
    IkSolution,
    IkSolver,
    KinematicChain,
    MinJerkConfig,
)
from icub_pmp.cartesian.min_jerk_velocity_law import MinJerkVelocityLaw
from icub_pmp.control.arrival_monitor import ArrivalConfig
from icub_pmp.control.trajectory_limits import JointRateLimits
from icub_pmp.errors import IcubPmpError, InvalidInput, UnknownName
from icub_pmp.kinematics.robot_model import IcubModel
from icub_pmp.kinematics.robot_spec import RobotSpec
from icub_pmp.kinematics.rotations import quat_wxyz_to_matrix
from icub_pmp.ros.cartesian_node_config import CartesianNodeConfig
from icub_pmp.ros.conversions import (
    arrays_to_trajectory,
    joint_state_field,
    make_joint_state,
    point_to_array,
    pose_to_arrays,
    validate_joint_state,
)
from icub_pmp.ros.goal_execution import GoalExecution, arrival_config, end_goal
from icub_pmp.ros.joint_state_cache import JointStateCache, MeasuredState
from icub_pmp.ros.node_runner import run_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.ros.subscriber_wait import subscriber_note, wait_for_subscribers
from icub_pmp.ros.trajectory_action_server import FIRST_STATE_TIMEOUT

__all__ = ["CartesianSolverNode", "main"]

_CONFIGS = (IkConfig, MinJerkConfig, CartesianNodeConfig, ArrivalConfig)


class CartesianSolverNode(Node):
    """Serve /cartesian/solve_pose and /cartesian/go_to_pose; publish /joint_trajectory."""

    def __init__(self) -> None:
        super().__init__("cartesian_solver")
        self.params = ConfigParameters(self, _CONFIGS, check=_check_rest_posture,
                                       on_change=self._on_config_change)
        self.model = IcubModel()
        self.solver = IkSolver(self.model, self.ik_config)
        self.controller = CartesianController(self.solver, self.mj_config,
                                              JointRateLimits.from_spec(self.model.spec))
        for chain in self.node_config.prebuild_chains:
            prob = self.solver.problem(chain)
            self.get_logger().info(
                f"built the eq 11 NLP of {chain} ({prob.chain.n} DoF, "
                f"{'compiled C' if prob.compiled else 'CasADi VM'})"
            )
        self.joint_cache = JointStateCache(self)
        self.traj_pub = self.create_publisher(
            JointTrajectory,
            "joint_trajectory",
            QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE),
        )
        self.create_service(SolvePose, "cartesian/solve_pose", self._on_solve_pose)
        self.create_service(GoToPose, "cartesian/go_to_pose", self._on_go_to_pose)
        self.execution = GoalExecution(self, self.joint_cache, self._hands,
                                       server_timeout=self.node_config.controller_timeout)
        self.go_action = ActionServer(
            self, GoToPoseAction, "cartesian/go_to_pose_action",
            execute_callback=self._execute_go_to_pose,
            goal_callback=lambda _goal: GoalResponse.ACCEPT,
            cancel_callback=lambda _handle: CancelResponse.ACCEPT)
        self.get_logger().info(
            "serving /cartesian/solve_pose, /cartesian/go_to_pose and the action "
            f"/cartesian/go_to_pose_action (default chain {self.node_config.default_chain})"
        )

    # ------------------------------------------------------------------ parameters
    @property
    def ik_config(self) -> IkConfig:
        """The solver's configuration (eq 11, IPOPT)."""
        return self.params.get(IkConfig)

    @property
    def mj_config(self) -> MinJerkConfig:
        """The min-jerk trajectory configuration."""
        return self.params.get(MinJerkConfig)

    @property
    def node_config(self) -> CartesianNodeConfig:
        """The node's own parameters."""
        return self.params.get(CartesianNodeConfig)

    def _on_config_change(self, old: tuple, new: tuple, changed: frozenset[str]) -> None:
        self.solver.reconfigure(new[0])
        self.controller.config = new[1]

    # ------------------------------------------------------------------ inputs
    @property
    def _latest(self) -> dict[str, float] | None:
        """The latest measured joints {name: rad}, None before the first or when it names
        joints the model does not know (a stray publisher: dropped with a warning)."""
        st = self.joint_cache.latest()
        if st is None:
            return None
        unknown = set(st.positions) - set(self.model.spec.actuated_joints)
        if unknown:
            self.get_logger().warning(f"dropping /joint_states naming unknown joints "
                                      f"{sorted(unknown)}", throttle_duration_sec=5.0)
            return None
        return st.positions

    def _start_q(self, start_state: JointState) -> np.ndarray:
        """Full configuration (nq,) from the request's start_state or the latest joints."""
        given = self._start_state(start_state)
        if given is None:
            self.joint_cache.wait_for_first(FIRST_STATE_TIMEOUT)  # a request right after start-up
        return self.controller.start_configuration(self._latest, given)

    @staticmethod
    def _start_state(start_state: JointState) -> dict[str, float] | None:
        """The request's start_state as {joint: angle} (None when empty), validated."""
        if len(start_state.name) == 0:
            return None
        validate_joint_state(start_state)
        return joint_state_field(start_state)

    def _target(self, req: Any) -> tuple[str, np.ndarray, np.ndarray | None]:
        chain = req.chain or self.node_config.default_chain
        KinematicChain.from_name(chain, self.model.spec)  # raises UnknownName
        frame = req.target.header.frame_id
        if frame not in ("", self.model.spec.root_frame):
            raise UnknownName("target frame", frame, ("", self.model.spec.root_frame))
        if req.use_orientation:
            position, quat = pose_to_arrays(req.target.pose)
            return chain, position, quat_wxyz_to_matrix(quat)
        return chain, point_to_array(req.target.pose.position), None

    # ------------------------------------------------------------------ services
    def _fill(self, resp: Any, sol: IkSolution) -> None:
        resp.success = bool(sol.success)
        resp.message = sol.message
        resp.solution = make_joint_state(sol.joint_names, position=sol.q)
        resp.position_error = float(sol.position_error)
        resp.orientation_error = float(sol.orientation_error)
        resp.solve_time = float(sol.solve_time)
        resp.iterations = int(sol.iterations)
        resp.solver_status = sol.status

    def _on_solve_pose(self, req: SolvePose.Request, resp: SolvePose.Response):
        try:
            chain, position, rotation = self._target(req)
            sol = self.solver.solve(chain, position, rotation, self._start_q(req.start_state))
            self._fill(resp, sol)
        except IcubPmpError as exc:
            resp.success, resp.message = False, str(exc)
            resp.position_error = resp.orientation_error = math.nan
        except Exception as exc:  # never let a request kill the node
            self.get_logger().error(f"solve_pose failed unexpectedly: {exc!r}")
            resp.success, resp.message = False, f"internal error: {exc!r}"
        return resp

    def _on_go_to_pose(self, req: GoToPose.Request, resp: GoToPose.Response):
        try:
            self._go_to_pose(req, resp)
        except IcubPmpError as exc:
            resp.success, resp.message = False, str(exc)
            if not resp.solver_status:
                resp.position_error = resp.orientation_error = math.nan
        except Exception as exc:  # never let a request kill the node
            self.get_logger().error(f"go_to_pose failed unexpectedly: {exc!r}")
            resp.success, resp.message = False, f"internal error: {exc!r}"
        return resp

    def _go_to_pose(self, req: GoToPose.Request, resp: GoToPose.Response) -> None:
        msg, note, _ = self._plan_go_to_pose(req, resp, self._start_state(req.start_state))
        if msg is None:
            return
        wait = self.node_config.subscriber_timeout
        listening = subscriber_note(wait_for_subscribers(self.traj_pub, wait), wait)
        self.traj_pub.publish(msg)
        resp.trajectory = msg
        resp.message = (f"{note}; sent on /joint_trajectory (execution not monitored: the "
                        f"/cartesian/go_to_pose_action action reports the measured arrival)"
                        + listening)

    def _plan_go_to_pose(self, req: Any, resp: Any, start_state: dict[str, float] | None
                         ) -> tuple[JointTrajectory | None, str, Any]:
        """Solve and roll out (:class:`CartesianController`), fill ``resp`` with the solution:
        (the trajectory message, or None when the solve failed; the message; the motion)."""
        self.controller.trajectory_time(req.trajectory_time)  # checked before the target
        chain, position, rotation = self._target(req)
        now = self.get_clock().now()
        motion = self.controller.go_to(
            chain, position, rotation, now.nanoseconds * 1e-9,
            trajectory_time=req.trajectory_time, measured=self._latest,
            start_state=start_state)
        self._fill(resp, motion.solution)
        traj = motion.trajectory
        if traj is None:
            return None, motion.solution.message, motion
        msg = arrays_to_trajectory(traj.joint_names, traj.t, traj.q, traj.qd, stamp=now.to_msg())
        note = (f"{motion.solution.message}; trajectory of {len(traj.t)} points over "
                f"{traj.duration:.2f} s"
                + (" (continued from the running one)" if motion.continued else "")
                + (f"; {motion.slowdown}" if motion.slowdown else ""))
        return msg, note, motion

    # ------------------------------------------------------------------ the action
    def _hands(self, st: MeasuredState) -> dict[str, np.ndarray]:
        q = self.model.q_from_dict(st.positions, default=self.model.posture("rest"))
        spec = self.model.spec
        return {h: self.model.frame_position(q, spec.hand_frame(h)) for h in ("left", "right")}

    async def _execute_go_to_pose(self, handle) -> GoToPoseAction.Result:
        """/cartesian/go_to_pose_action: solve, execute, judge on the measured robot."""
        generation = self.execution.preempt_running()
        req = handle.request
        res = GoToPoseAction.Result()

        def feedback(phase: str, errors: dict, time_to_go: float, progress: float) -> None:
            fb = GoToPoseAction.Feedback()
            fb.phase = phase
            fb.position_error = float(next(iter(errors.values()), math.nan))
            fb.time_to_go, fb.progress = float(time_to_go), float(progress)
            handle.publish_feedback(fb)

        def finish(outcome: str, message: str) -> GoToPoseAction.Result:
            return end_goal(self, handle, res, outcome, message, "/cartesian/go_to_pose_action")

        feedback("solving", {}, float(req.trajectory_time), 0.0)
        try:
            if self.joint_cache.latest(wait=FIRST_STATE_TIMEOUT) is None:  # right after start-up
                raise InvalidInput("no /joint_states received: the robot's posture is "
                                   "unknown, nothing can be executed")
            arrival = arrival_config(self.params.get(ArrivalConfig), req.arrival_tolerance)
            chain, position, _ = self._target(req)
            hand = "left" if "left" in chain else "right"
            solved = GoToPose.Response()
            msg, note, motion = self._plan_go_to_pose(req, solved, None)
        except IcubPmpError as exc:
            return finish("rejected", str(exc))
        except Exception as exc:  # never die on a goal
            return finish("rejected", f"internal error: {type(exc).__name__}: {exc}")
        res.solver_position_error = float(solved.position_error)
        res.solver_orientation_error = float(solved.orientation_error)
        if msg is None:
            return finish("unreachable", f"{note}; not executed")
        res.trajectory = msg
        res.trajectory_time_used = float(msg.points[-1].time_from_start.sec
                                         + msg.points[-1].time_from_start.nanosec * 1e-9)
        msg.header.stamp.sec, msg.header.stamp.nanosec = 0, 0  # start when accepted
        if self.node_config.execution == "closed_loop":
            out = await self._execute_closed_loop(motion, hand, position, arrival, feedback,
                                                  handle, generation)
        else:
            out = await self.execution.run(
                msg, {hand: position}, arrival, feedback, lambda: handle.is_cancel_requested,
                generation)
        if out.arrival is not None:
            p = out.arrival.positions[hand]
            res.arrival_position_error = float(out.arrival.errors[hand])
            res.final_position = Point(x=float(p[0]), y=float(p[1]), z=float(p[2]))
        res.execution_time = float(out.execution_time)
        return finish(out.outcome, f"{out.message} (solver: {note})")


    async def _execute_closed_loop(self, motion: Any, hand: str, position: np.ndarray,
                                   arrival: Any, feedback: Any, handle: Any, generation: int
                                   ) -> Any:
        """The min-jerk generator fed back with the measured joints every period, its joint
        velocities to the controller's velocity mode (``execution: closed_loop``); T is the
        goal's, stretched as the planned trajectory was to the joint rate limits."""
        chain = self.controller.solver.problem(motion.solution.chain).chain
        T = self.controller.trajectory_time(handle.request.trajectory_time) * motion.time_scale
        law = MinJerkVelocityLaw(self.model, chain, self.mj_config, T)
        rest = self.model.posture("rest")

        def configuration(st: MeasuredState) -> np.ndarray:
            return self.model.q_from_dict(st.positions, default=rest)

        law.start(configuration(self.joint_cache.latest()), motion.solution.q)
        return await self.execution.run_closed_loop(
            law, configuration, motion.trajectory.duration, {hand: position}, arrival,
            feedback, lambda: handle.is_cancel_requested, generation)


def _check_rest_posture(configs: tuple) -> None:
    """The rest posture of the IkConfig must be a posture of config/robot.yaml."""
    RobotSpec.load().posture(configs[0].rest_posture)  # raises UnknownName


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp cartesian_solver``)."""
    # IPOPT's linear solver (MUMPS) is built with OpenMP; on a 10-variable problem its thread
    # pool costs more than it gives (about 20 % per solve). Read when the IPOPT plugin loads
    # (the first NLP is built in the node's constructor); a value set by the user wins.
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    run_node(CartesianSolverNode, args, "cartesian_solver")

if __name__ == "__main__":
    main()
