"""pmp_planner: the PMP planner (Mohan et al. 2009) as a ROS 2 node.

Action ``/pmp/reach_action`` (icub_interfaces/action/Reach): the way to move the robot. Plans
from the measured /joint_states, slows the plan down to the joints' velocity/acceleration
limits when needed, executes it through the impedance controller's FollowJointTrajectory
action, sends feedback (phase, hand errors measured from /joint_states, time to go) and
answers with the arrival error measured on the robot after the hands settled
(:class:`~icub_pmp.ros.goal_execution.GoalExecution`). Outcomes: reached, not_reached,
unreachable (the mental simulation failed: nothing moves), aborted (with the reason: the
controller's safe hold, a missing controller, a newer goal), canceled, rejected (bad goal).
A held-object transport (``hold_object``) starts from the impedance controller's set-point
(/impedance_controller/state) when it is recent, so a squeezing grasp keeps its squeeze.

Service ``/pmp/reach`` (icub_interfaces/srv/Reach), for mental simulation and quick calls:
plans the goal with a PMP network from the
request's ``start_state`` (if given; joints it lacks come from the latest /joint_states, else
the rest posture), else from the latest ``/joint_states``; with neither, from the ``rest``
posture of config/robot.yaml (parameter ``plan_from_rest_without_state``; the answer's message
says so and the plan is not executed, since the robot's real posture is unknown). Answers
success, per-hand residuals (the distance left at tau, Sect. 4) and the planned
``trajectory_msgs/JointTrajectory`` (the network's joints, time_from_start 0 .. tau).

A plan is sent, i.e. published on ``/joint_trajectory``, only when the request is not
``simulate_only`` and the mental simulation succeeded (Sect. 4: "if the forward simulation is
successful, the movement is executed"); the service does not watch the execution (its answer
says "sent", never "reached"; use the action for that). The predicted hand paths are always
published on ``/pmp/predicted_path/left_hand`` and ``.../right_hand`` (nav_msgs/Path,
root_link).

Target frames: empty or ``root_link``, or any frame of the iCub model (the target is then
expressed in that frame at the start posture). Bad goals (NaN, unknown hand or frame, tau < 0,
no hand, a zero quaternion) answer success=false with a message; the node never dies on a
request. Parameters: config/pmp_planner.yaml (= :class:`icub_pmp.pmp.PmpConfig` +
:class:`icub_pmp.ros.pmp_node_config.PmpNodeConfig` + :class:`icub_pmp.control.arrival_monitor.
ArrivalConfig`).
"""

from __future__ import annotations

import time

import numpy as np
from geometry_msgs.msg import Point
from nav_msgs.msg import Path
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.service_introspection import ServiceIntrospectionState
from trajectory_msgs.msg import JointTrajectory

from icub_interfaces.action import Reach as ReachAction
from icub_interfaces.msg import Obstacles
from icub_interfaces.srv import Reach
from icub_pmp.body_schema.jacobian_source import JacobianSourceConfig, make_provider
from icub_pmp.control.arrival_monitor import ArrivalConfig
from icub_pmp.control.joint_trajectory import JointTrajectory as CoreTrajectory
from icub_pmp.control.trajectory_limits import JointRateLimits, scale_trajectory_time
from icub_pmp.errors import IcubPmpError, InvalidInput, UnknownName
from icub_pmp.kinematics.robot_model import IcubModel
from icub_pmp.kinematics.robot_spec import HANDS
from icub_pmp.pmp import PmpConfig, PmpPlanner, ReachGoal
from icub_pmp.pmp.pinocchio_provider import PinocchioJacobianProvider
from icub_pmp.ros.conversions import (
    arrays_to_trajectory,
    joint_state_field,
    positions_to_path,
    validate_joint_state,
)
from icub_pmp.ros.goal_execution import GoalExecution, arrival_config, end_goal
from icub_pmp.ros.joint_state_cache import JointStateCache, MeasuredState
from icub_pmp.ros.node_runner import run_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.ros.pmp_node_config import PmpNodeConfig
from icub_pmp.ros.reach_request import (
    FramePose,
    ParsedReach,
    ReachRequestConfig,
    parse_obstacles,
    parse_reach_request,
)
from icub_pmp.ros.subscriber_wait import subscriber_note, wait_for_subscribers
from icub_pmp.ros.trajectory_action_server import FIRST_STATE_TIMEOUT
from icub_pmp.ros.warning_throttle import WarningThrottle

__all__ = ["PmpPlannerNode", "main"]

#: a controller set-point at most this much older or newer than the measured joint state
#: [s, simulated] may start a held-object transport (it is published every 10 ms)
SETPOINT_MAX_LAG = 0.05


class PmpPlannerNode(Node):
    """Serves /pmp/reach with a :class:`~icub_pmp.pmp.PmpPlanner`."""

    def __init__(self) -> None:
        super().__init__("pmp_planner")
        self.params = ConfigParameters(
            self, (PmpConfig, PmpNodeConfig, ArrivalConfig, ReachRequestConfig,
                   JacobianSourceConfig),
            on_change=self._on_config_change, read_only=JacobianSourceConfig.field_names())
        # the body model PMP plans on (jacobian_source: the URDF or learned body networks);
        # the URDF model also serves the measured hands, the targets' and obstacles' frames
        provider = make_provider(self.params.get(JacobianSourceConfig))
        self.planner = PmpPlanner(self.config, provider=provider)
        self.urdf_provider = (provider if isinstance(provider, PinocchioJacobianProvider)
                              else PinocchioJacobianProvider(IcubModel(self.planner.spec)))
        self.urdf = self.urdf_provider.icub
        self._names = self.planner.provider.joint_names
        self._valid_state_names = set(self.planner.spec.actuated_joints)
        self.joint_states = JointStateCache(self)
        # the controller's set-point: a held object is carried from the commanded grasp
        self.setpoints = JointStateCache(self, "/impedance_controller/state",
                                         suffix="setpoints")
        self.rate_limits = JointRateLimits.from_spec(self.planner.spec)
        reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self.trajectory_pub = self.create_publisher(JointTrajectory, "/joint_trajectory", reliable)
        self.path_pubs = {
            h: self.create_publisher(Path, f"/pmp/predicted_path/{h}_hand", reliable)
            for h in HANDS
        }
        if self.node_config.warm_up:
            t0 = time.perf_counter()
            self.planner.warm_up(hands=tuple(
                h for h in HANDS if self.planner.spec.hand_frame(h) in provider.frame_names()))
            self.get_logger().info(
                f"posture memory ready ({self.config.posture_memory_size} postures, "
                f"{time.perf_counter() - t0:.2f} s)")
        self._scene: list = []  # the latest valid /pmp/obstacles
        self.warnings = WarningThrottle(self.get_logger(), 5.0)
        self.create_subscription(Obstacles, "/pmp/obstacles", self._on_obstacles, reliable)
        srv = self.create_service(Reach, "/pmp/reach", self._on_reach)
        # requests and responses on /pmp/reach/_service_event, so bags record reach goals
        srv.configure_introspection(
            self.get_clock(), QoSProfile(depth=100), ServiceIntrospectionState.CONTENTS)
        icub = self.urdf
        frames = {h: self.planner.spec.hand_frame(h) for h in HANDS}

        def hands(st: MeasuredState) -> dict[str, np.ndarray]:
            q = icub.q_from_dict(st.positions)
            return {h: icub.frame_position(q, f) for h, f in frames.items()}

        self.execution = GoalExecution(self, self.joint_states, hands,
                                       server_timeout=self.node_config.controller_timeout)
        self.reach_action = ActionServer(
            self, ReachAction, "/pmp/reach_action", execute_callback=self._execute_reach,
            goal_callback=lambda _goal: GoalResponse.ACCEPT,
            cancel_callback=lambda _handle: CancelResponse.ACCEPT)
        self.get_logger().info("serving /pmp/reach (service) and /pmp/reach_action (action)")

    # ------------------------------------------------------------------ parameters
    @property
    def config(self) -> PmpConfig:
        """The planner's configuration."""
        return self.params.get(PmpConfig)

    @property
    def node_config(self) -> PmpNodeConfig:
        """The node's own parameters."""
        return self.params.get(PmpNodeConfig)

    def _on_config_change(self, old: tuple, new: tuple, changed: frozenset[str]) -> None:
        if new[0] != old[0]:
            self.planner = PmpPlanner(new[0], provider=self.planner.provider)

    # ------------------------------------------------------------------ joint states
    def _current_state(self) -> dict[str, float] | None:
        timeout = self.node_config.joint_state_timeout
        st = self.joint_states.latest(wait=FIRST_STATE_TIMEOUT)  # a goal right after start-up
        if st is None:
            return None
        if timeout > 0 and self.joint_states.wall_age() > timeout:
            return None
        unknown = set(st.positions) - self._valid_state_names
        if unknown:
            self.get_logger().warning(f"dropping /joint_states naming unknown joints "
                                      f"{sorted(unknown)}", throttle_duration_sec=5.0)
            return None
        return st.positions

    def _held_start(self, req, start: dict[str, float]) -> tuple[dict[str, float], str]:
        """The start of a held-object transport: the controller's set-point
        (/impedance_controller/state) over the measured posture, when it is as recent as the
        measured state (within ``SETPOINT_MAX_LAG`` of simulated time). A squeezing grasp
        commands the palms inside the object, which holds them apart: planned from the
        measured hands, the trajectory would start by releasing the squeeze and rebuild it
        during the transport (the measured hand-to-hand distance changing with it; Sect. 3.2
        keeps the grasp). Other goals, or without a recent set-point: ``start`` as given.
        Returns (start, note for the message)."""
        if not req.hold_object:
            return start, ""
        sp, measured = self.setpoints.latest(), self.joint_states.latest()
        if sp is None or measured is None or abs(sp.t - measured.t) > SETPOINT_MAX_LAG:
            return start, " (no recent controller set-point: planned from the measured joints)"
        out = dict(start)
        out.update({j: v for j, v in sp.positions.items() if j in self._valid_state_names})
        return out, " (planned from the controller's set-point: the grasp's squeeze is kept)"

    def _limited_trajectory(self, plan) -> tuple[JointTrajectory, float, str]:
        """The plan as a trajectory message within the joints' velocity and acceleration
        limits: (message, tau used [s], a note when it had to be slowed down)."""
        times, vel = np.asarray(plan.t), np.asarray(plan.velocities)
        rep = self.rate_limits.report(
            CoreTrajectory(plan.joint_names, times, plan.positions, vel))
        scale, note = rep.time_scale, ""
        if scale > 1.0 + 1e-3:
            scale *= 1.01  # a small margin over the sampled peak
            times, vel, _ = scale_trajectory_time(times, vel, None, scale)
            note = (f"; slowed down to the joint limits: tau {plan.tau:.3g} -> "
                    f"{plan.tau * scale:.3g} s ({rep.describe()} at the asked tau)")
        msg = arrays_to_trajectory(plan.joint_names, times, plan.positions, vel)
        return msg, float(plan.tau * scale), note

    # ------------------------------------------------------------------ service
    def _on_reach(self, req: Reach.Request, res: Reach.Response) -> Reach.Response:
        t0 = time.perf_counter()
        try:
            start, assumed, note = self._start_of(req)
            parsed = self._goal_of(req, start)
            plan = self.planner.plan(parsed.goal, start)
        except IcubPmpError as exc:
            res.success = False
            res.message = str(exc)
            self.get_logger().warning(f"/pmp/reach rejected: {exc}")
            return res
        except Exception as exc:  # never die on a request
            res.success = False
            res.message = f"internal error: {type(exc).__name__}: {exc}"
            self.get_logger().error(f"/pmp/reach failed: {res.message}")
            return res
        res.hands = list(plan.hands)
        res.residuals = [float(plan.residuals[h]) for h in plan.hands]
        self._fill_answer(res, plan, parsed)
        res.trajectory, _, slowed = self._limited_trajectory(plan)
        execute = plan.success and not req.simulate_only and not assumed
        listening = ""
        if execute:
            wait = self.node_config.subscriber_timeout
            listening = subscriber_note(wait_for_subscribers(self.trajectory_pub, wait), wait)
            self.trajectory_pub.publish(res.trajectory)
        stamp = self.get_clock().now().to_msg()
        for h in plan.hands:
            self.path_pubs[h].publish(
                positions_to_path(plan.hand_paths[h], "root_link", stamp, plan.t))
        res.success = plan.success
        if req.simulate_only:
            what = "simulated only"
        elif execute:
            what = ("sent on /joint_trajectory (execution not monitored: the "
                    "/pmp/reach_action action reports the measured arrival)" + listening)
        else:
            what = "not executed"
        res.message = f"{plan.message}{slowed}; {what}{note}"
        self.get_logger().info(
            f"/pmp/reach {list(plan.hands)}: {res.message} "
            f"[{(time.perf_counter() - t0) * 1e3:.1f} ms with messages]")
        return res

    def _start_of(self, req: Reach.Request) -> tuple[dict[str, float], bool, str]:
        """(start {joint: angle}, whether the posture was assumed, note for the message)."""
        current = self._current_state()
        if req.start_state.name:
            validate_joint_state(req.start_state, valid_names=self._valid_state_names)
            start = dict(current or self.planner.spec.posture("rest"))
            start.update(joint_state_field(req.start_state))
            note = "" if current else " (joints missing from start_state taken from 'rest')"
            return start, False, note
        if current is not None:
            start, note = self._held_start(req, dict(current))
            return start, False, note
        if not self.node_config.plan_from_rest_without_state:
            raise InvalidInput("no /joint_states received yet and no start_state given")
        return (dict(self.planner.spec.posture("rest")), True,
                " (no /joint_states received: planned from the rest posture)")

    def _goal_of(self, req, start: dict[str, float]) -> ParsedReach:
        """Validate the request (service or action goal) and build its goal (root_link)."""
        q_start = self.planner.start_configuration(start)
        q_urdf = self._urdf_q(q_start)
        hand_frames = [self.planner.spec.hand_frame(h) for h in HANDS]
        hand_positions = dict(zip(HANDS, self.urdf_provider.positions(q_urdf, hand_frames)))
        return parse_reach_request(
            req, frames=self._frame_lookup(q_urdf), hand_positions=hand_positions,
            joint_names=self._names, config=self.params.get(ReachRequestConfig), scene=self._scene,
            hand_frames=dict(zip(HANDS, hand_frames)))

    def _urdf_q(self, q: np.ndarray) -> np.ndarray:
        """The URDF model's configuration of the planner's configuration ``q``."""
        return self.urdf.q_from_dict(dict(zip(self._names, q)))

    def _frame_lookup(self, q: np.ndarray):
        """name -> :class:`FramePose` of that URDF frame at the URDF configuration ``q``."""
        names = self.urdf_provider.frame_names()

        def frames(name: str) -> FramePose:
            if name not in names:
                raise UnknownName("frame", name, names)
            pose = self.urdf.frame_pose(q, name)
            return FramePose(pose.rotation.copy(), pose.translation.copy())

        return frames

    def _on_obstacles(self, msg: Obstacles) -> None:
        """The /pmp/obstacles scene: kept if valid (checked with every frame at the rest
        posture), else dropped with a throttled warning."""
        q = self._urdf_q(self.planner.start_configuration(self.planner.spec.posture("rest")))
        try:
            parse_obstacles("/pmp/obstacles", msg.obstacles, self._frame_lookup(q), 0.0,
                            self.params.get(ReachRequestConfig))
        except IcubPmpError as exc:
            self.warnings("obstacles", f"dropping /pmp/obstacles: {exc}")
            return
        self._scene = list(msg.obstacles)

    def _fill_answer(self, res, plan, parsed: ParsedReach) -> None:
        """The new result fields: object path, obstacle clearance, final torques."""
        if plan.object_path is not None:
            res.object_path = [_point(p) for p in plan.object_path]
        res.obstacle_clearance = (float(plan.obstacle_clearance)
                                  if plan.obstacle_clearance is not None else -1.0)
        if plan.final_torques is not None:
            # the network's joints (an idle arm's, appended after them, carries no force)
            res.torque_joints = list(plan.joint_names[:len(plan.final_torques)])
            res.torques = [float(t) for t in plan.final_torques]
            res.torques_within_limits = bool(
                np.all(np.abs(plan.final_torques) <= plan.torque_limits))

    # ------------------------------------------------------------------ the action
    async def _execute_reach(self, handle) -> ReachAction.Result:
        """The /pmp/reach_action goal: plan, execute, judge on the measured robot."""
        generation = self.execution.preempt_running()
        req = handle.request
        res = ReachAction.Result()
        res.hands = list(req.hands)

        def feedback(phase: str, errors: dict, time_to_go: float, progress: float) -> None:
            fb = ReachAction.Feedback()
            fb.phase = phase
            fb.hands = [h for h in res.hands if h in errors]
            fb.hand_errors = [float(errors[h]) for h in fb.hands]
            fb.time_to_go = float(time_to_go)
            fb.progress = float(progress)
            handle.publish_feedback(fb)

        def finish(outcome: str, message: str) -> ReachAction.Result:
            return end_goal(self, handle, res, outcome, message,
                            f"/pmp/reach_action {res.hands}")

        feedback("planning", {}, float(req.tau), 0.0)
        try:
            start = self._current_state()
            if start is None:
                raise InvalidInput("no /joint_states received: the robot's posture is "
                                   "unknown, nothing can be executed")
            start, held_note = self._held_start(req, dict(start))
            parsed = self._goal_of(req, start)
            goal = parsed.goal
            arrival = arrival_config(self.params.get(ArrivalConfig), req.arrival_tolerance)
            plan = self.planner.plan(goal, start)
        except IcubPmpError as exc:
            return finish("rejected", str(exc))
        except Exception as exc:  # never die on a goal
            return finish("rejected", f"internal error: {type(exc).__name__}: {exc}")
        res.hands = list(plan.hands)
        res.planned_residuals = [float(plan.residuals[h]) for h in plan.hands]
        self._fill_answer(res, plan, parsed)
        stamp = self.get_clock().now().to_msg()
        for h in plan.hands:
            self.path_pubs[h].publish(
                positions_to_path(plan.hand_paths[h], "root_link", stamp, plan.t))
        if not plan.success:
            return finish("unreachable", f"{plan.message}; not executed")
        traj, res.tau_used, slowed = self._limited_trajectory(plan)
        res.trajectory = traj
        out = await self.execution.run(
            traj, _final_targets(goal), arrival, feedback, lambda: handle.is_cancel_requested,
            generation)
        if out.arrival is not None:
            res.arrival_errors = [float(out.arrival.errors[h]) for h in res.hands]
            res.final_positions = [_point(out.arrival.positions[h]) for h in res.hands]
        res.execution_time = float(out.execution_time)
        return finish(out.outcome, f"{out.message} (planned: residuals "
                      + ", ".join(f"{h} {plan.residuals[h] * 1e3:.2f} mm" for h in plan.hands)
                      + f"{slowed}){held_note}")


def _final_targets(goal: ReachGoal) -> dict[str, np.ndarray]:
    """Where each hand must arrive: its target, or its grasp point at the object's goal."""
    out = dict(goal.targets)
    if goal.held_object is not None:
        out.update(goal.held_object.hand_targets())
    return out


def _point(p: np.ndarray) -> Point:
    return Point(x=float(p[0]), y=float(p[1]), z=float(p[2]))


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp pmp_planner``)."""
    run_node(PmpPlannerNode, args, "pmp_planner")

if __name__ == "__main__":
    main()
