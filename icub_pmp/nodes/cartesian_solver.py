"""cartesian_solver: the iKinCartesianSolver + cartesianController role as a ROS 2 node.

Services
- ``/cartesian/solve_pose`` (icub_interfaces/srv/SolvePose): eq 11 solved by IPOPT
  (:class:`~icub_pmp.cartesian.IkSolver`); answers joints, residuals, solve time; moves nothing.
- ``/cartesian/go_to_pose`` (icub_interfaces/srv/GoToPose): the same solve, then a
  multi-referential minimum-jerk trajectory published on ``/joint_trajectory`` for the
  impedance controller (:class:`~icub_pmp.cartesian.CartesianController`: a goal given while a
  trajectory of the same chain runs starts from that trajectory's state at the current time,
  so the motion bends smoothly toward the new target).

Subscribes ``/joint_states`` (start configuration). Parameters: the fields of
:class:`IkConfig`, :class:`MinJerkConfig` and :class:`CartesianNodeConfig`
(config/cartesian_solver.yaml), validated when set at run time. Bad requests answer
``success=false`` with a message (and the residual when a solve ran); the node never dies on
them, and IPOPT is bounded in iterations and wall time.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from icub_interfaces.srv import GoToPose, SolvePose
from icub_pmp.cartesian import (
    CartesianController,
    IkConfig,
    IkSolution,
    IkSolver,
    KinematicChain,
    MinJerkConfig,
)
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
from icub_pmp.ros.node_runner import run_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.ros.subscriber_wait import subscriber_note, wait_for_subscribers

__all__ = ["CartesianSolverNode", "main"]

_CONFIGS = (IkConfig, MinJerkConfig, CartesianNodeConfig)


class CartesianSolverNode(Node):
    """Serve /cartesian/solve_pose and /cartesian/go_to_pose; publish /joint_trajectory."""

    def __init__(self) -> None:
        super().__init__("cartesian_solver")
        self.params = ConfigParameters(self, _CONFIGS, check=_check_rest_posture,
                                       on_change=self._on_config_change)
        self.model = IcubModel()
        self.solver = IkSolver(self.model, self.ik_config)
        self.controller = CartesianController(self.solver, self.mj_config)
        for chain in self.node_config.prebuild_chains:
            prob = self.solver.problem(chain)
            self.get_logger().info(
                f"built the eq 11 NLP of {chain} ({prob.chain.n} DoF, "
                f"{'compiled C' if prob.compiled else 'CasADi VM'})"
            )
        self._latest: dict[str, float] | None = None
        self.create_subscription(
            JointState, "joint_states", self._on_joint_states, qos_profile_sensor_data
        )
        self.traj_pub = self.create_publisher(
            JointTrajectory,
            "joint_trajectory",
            QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE),
        )
        self.create_service(SolvePose, "cartesian/solve_pose", self._on_solve_pose)
        self.create_service(GoToPose, "cartesian/go_to_pose", self._on_go_to_pose)
        self.get_logger().info(
            "serving /cartesian/solve_pose and /cartesian/go_to_pose "
            f"(default chain {self.node_config.default_chain})"
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
    def _on_joint_states(self, msg: JointState) -> None:
        try:
            validate_joint_state(msg)
        except InvalidInput as exc:
            self.get_logger().warning(
                f"dropping /joint_states: {exc}", throttle_duration_sec=5.0
            )
            return
        self._latest = joint_state_field(msg)

    def _start_q(self, start_state: JointState) -> np.ndarray:
        """Full configuration (nq,) from the request's start_state or the latest joints."""
        return self.controller.start_configuration(self._latest, self._start_state(start_state))

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
        self.controller.trajectory_time(req.trajectory_time)  # checked before the target
        chain, position, rotation = self._target(req)
        now = self.get_clock().now()
        motion = self.controller.go_to(
            chain, position, rotation, now.nanoseconds * 1e-9,
            trajectory_time=req.trajectory_time, measured=self._latest,
            start_state=self._start_state(req.start_state))
        self._fill(resp, motion.solution)
        traj = motion.trajectory
        if traj is None:
            return
        msg = arrays_to_trajectory(traj.joint_names, traj.t, traj.q, traj.qd, stamp=now.to_msg())
        wait = self.node_config.subscriber_timeout
        listening = subscriber_note(wait_for_subscribers(self.traj_pub, wait), wait)
        self.traj_pub.publish(msg)
        resp.trajectory = msg
        resp.message = (
            f"{motion.solution.message}; trajectory of {len(traj.t)} points over "
            f"{traj.duration:.2f} s" + (" (continued from the running one)" if motion.continued
                                       else "") + listening
        )


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
