"""GazeController: iKinGazeCtrl for the simulated iCub, without ROS.

Given a fixation point in root_link, the controller (after iKinGazeCtrl, robotology/icub-main
``src/modules/iKinGazeCtrl``; Roncone, Pattacini, Metta, Natale, "A Cartesian 6-DoF Gaze
Controller for Humanoid Robots", RSS 2016):

1. checks the point: finite, in front of the head (the head-centre frame with the neck straight
   must see it at z > 0; iKinGazeCtrl acts on a point "iff the point is in front of us") and
   not nearer than ``min_distance`` to the eyes;
2. solves the neck (:class:`NeckSolver`: the head centre points at the target, roll kept near
   0, within the neck limits) and the eyes at that neck posture (:class:`EyeFixation`: tilt,
   version and vergence in closed form, clipped into the eye limits); the predicted fixation
   error (the angle between each optical axis and the point) says whether the point can be
   fixated exactly;
3. rolls out the two minimum-jerk controllers of iKinGazeCtrl's ``Controller`` (``controller.cpp``:
   ``mjCtrlNeck`` with ``neck_traj_time``, ``mjCtrlEyes`` with the shorter ``eyes_traj_time``,
   the feedback min-jerk velocity controllers of Pattacini et al. 2010, closed on an ideal
   plant and sampled exactly at the controller period, :class:`MinJerkLoop`):

       q_dot_neck = F_neck(q_neck* - q_neck)
       q_dot_eyes = F_eyes(e(q_neck) - q_eyes) + d e(q_neck) / dt

   where ``e(q_neck)`` are the eye angles that fixate the target from the neck's current
   posture. The eyes reach the target fast (a saccade, about 1.5 eyes_traj_time) and then keep
   it fixated while the slower neck turns, ending centred: the second term is the eyes'
   counter-rotation for the neck's motion (iKinGazeCtrl's oculo-collic reflex,
   ``EyePinvRefGen::getEyesCounterVelocity``), its first the pseudo-inverse fixation loop
   reduced to its solution.

Tracking (:meth:`GazeController.update`): a new target during a plan continues from the
plan's state at that time (positions and filter states), so the motion bends smoothly; the
neck target is kept while the target moves less than ``neck_activation_angle`` from it
(iKinGazeCtrl's ``NECKSOLVER_ACTIVATIONANGLE``), the eyes always follow.

Joint positions come as {name: rad} (e.g. /joint_states): torso and neck for the head pose
(missing torso joints are 0), the eye joints for the start of a plan.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from icub_pmp.control.joint_trajectory import JointTrajectory
from icub_pmp.control.trajectory_limits import JointRateLimits
from icub_pmp.errors import InvalidInput
from icub_pmp.gaze.eye_fixation import EYE_JOINTS, EyeFixation
from icub_pmp.gaze.gaze_controller_config import GazeControllerConfig
from icub_pmp.gaze.gaze_plan import GazePlan, GazeState
from icub_pmp.gaze.gaze_solution import GAZE_JOINTS, GazeSolution
from icub_pmp.gaze.min_jerk_loop import MinJerkLoop
from icub_pmp.gaze.neck_solver import NeckSolver
from icub_pmp.kinematics.eye_kinematics import EyeKinematics
from icub_pmp.kinematics.robot_model import IcubModel

__all__ = ["GazeController"]


class GazeController:
    """The gaze controller core (module doc).

    Args:
        config: parameters (defaults: iKinGazeCtrl's).
        model: the pinocchio model of the upper body (built from config/robot.yaml if None).
    """

    def __init__(self, config: GazeControllerConfig | None = None,
                 model: IcubModel | None = None):
        self.config = config or GazeControllerConfig()
        self.model = model or IcubModel()
        self.eyes = EyeKinematics.from_model(self.model)
        c = self.config
        self.fixation = EyeFixation(self.eyes, c.joint_limit_margin)
        self.neck = NeckSolver(self.model, self.fixation.T_head_center, c.rest_weight,
                               c.joint_limit_margin, c.rest_joint_weights)
        self._neck_idx = self.neck.idx
        self.joint_names = GAZE_JOINTS
        #: the head joints' velocity/acceleration limits (config/robot.yaml): a plan whose
        #: neck would exceed them is replanned with a longer neck trajectory time
        self.rate_limits = JointRateLimits.from_spec(self.model.spec, GAZE_JOINTS)

    # ------------------------------------------------------------------ inputs
    def configuration(self, joints: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """(model configuration (nq,), eye angles (3,)) [rad] of ``joints`` {name: rad}.

        Joints the model lacks (besides the eyes) are ignored; missing model joints are 0,
        missing eye joints 0. Raises :class:`InvalidInput` on a non-finite value.
        """
        bad = sorted(n for n, v in joints.items() if not math.isfinite(float(v)))
        if bad:
            raise InvalidInput(f"joints: non-finite position for {bad}")
        q = self.model.q_from_dict({n: float(v) for n, v in joints.items()})
        eyes = np.array([float(joints.get(n, 0.0)) for n in EYE_JOINTS])
        return q, eyes

    def check_target(self, target: np.ndarray, q_model: np.ndarray) -> np.ndarray:
        """Validate a fixation point (3,) [m] in root_link for the torso of ``q_model``.

        Raises :class:`InvalidInput` when it is not 3 finite numbers, lies behind the head
        (not in front of the head centre with the neck straight) or is nearer than
        ``min_distance`` to the eyes' midpoint.
        """
        p = np.asarray(target, dtype=float).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise InvalidInput(f"target: expected 3 finite coordinates [m], got {p.tolist()}")
        q0 = np.array(q_model, dtype=float)
        q0[self._neck_idx] = 0.0
        T = self.fixation.head_center(self.neck.head_pose(q0))
        v = T[:3, :3].T @ (p - T[:3, 3])
        dist = float(np.linalg.norm(v))
        if v[2] <= 0.0:
            raise InvalidInput(
                f"target {np.round(p, 3).tolist()} m is behind the head ({-v[2]:.3f} m behind "
                f"the eyes' plane with the neck straight); expected a point in front of the robot")
        if dist < self.config.min_distance:
            raise InvalidInput(
                f"target {np.round(p, 3).tolist()} m is too close to the eyes ({dist:.3f} m; "
                f"min_distance {self.config.min_distance} m)")
        return p

    # ------------------------------------------------------------------ solve
    def eyes_for(self, q_model: np.ndarray, target: np.ndarray
                 ) -> tuple[np.ndarray, tuple[str, ...]]:
        """Eye angles (3,) [rad] that fixate ``target`` from the head pose of ``q_model``,
        clipped into the eye limits, and the names of the clipped joints."""
        return self.fixation.clip(self.fixation.angles(self.neck.head_pose(q_model), target))

    def solve(self, target: np.ndarray, joints: Mapping[str, float],
              previous: GazeSolution | None = None) -> GazeSolution:
        """The head posture that fixates ``target`` (3,) [m] in root_link (module doc, 1-2).

        ``joints`` gives the torso and the neck's warm start. With ``previous`` (tracking),
        its neck target is kept when ``target`` is within ``neck_activation_angle`` of it.
        """
        q, _ = self.configuration(joints)
        p = self.check_target(target, q)
        neck_solved = True
        if previous is not None and self._within_activation(q, previous, p):
            neck = previous.neck.copy()
            neck_solved = False
            at_limit: tuple[str, ...] = ()
        else:
            ns = self.neck.solve(q, p)
            neck, at_limit = ns.neck, ns.at_limit
        q[self._neck_idx] = neck
        T_head = self.neck.head_pose(q)
        raw = self.fixation.angles(T_head, p)
        eyes, clipped = self.fixation.clip(raw)
        errors = self.fixation.errors(T_head, eyes, p)
        pointing = self.neck.pointing_error(q, p)
        exact = bool(errors.max() <= self.config.fixation_tolerance)
        limits = tuple(n for n in at_limit if not exact) + clipped
        return GazeSolution(p, neck, eyes, errors, pointing, exact, limits, neck_solved)

    def _within_activation(self, q_model: np.ndarray, previous: GazeSolution,
                           p: np.ndarray) -> bool:
        """Whether ``p`` is within ``neck_activation_angle`` of the previous target, seen from
        the head centre at the previous neck target."""
        q = np.array(q_model, dtype=float)
        q[self._neck_idx] = previous.neck
        a = self.neck.direction(q, p)
        b = self.neck.direction(q, previous.target)
        angle = math.atan2(float(np.linalg.norm(np.cross(a, b))), float(a @ b))
        return angle <= self.config.neck_activation_angle

    # ------------------------------------------------------------------ plan
    def plan(self, target: np.ndarray, joints: Mapping[str, float],
             start: GazeState | None = None, previous: GazeSolution | None = None,
             neck_traj_time: float | None = None) -> GazePlan:
        """Solve and roll out the neck and eye trajectories to ``target`` (module doc, 3),
        within the head joints' velocity and acceleration limits: when the neck would exceed
        them (a large head turn), the neck trajectory time is lengthened until it does not
        (the eyes' time is kept: their limits are ten times the neck's).

        Args:
            target: fixation point (3,) [m] in root_link.
            joints: current joint positions {name: rad} (torso, neck, eyes).
            start: controller state to continue from (a running plan's, for tracking);
                default: the neck and eyes of ``joints`` at rest.
            previous: the running plan's solution (keeps its neck target, see :meth:`solve`).
            neck_traj_time: overrides the configured neck trajectory time [s] (> the eyes').

        Raises:
            InvalidInput: bad target (see :meth:`check_target`), joints or trajectory time.
        """
        c = self.config
        T_neck = c.neck_traj_time if neck_traj_time is None else float(neck_traj_time)
        if not (math.isfinite(T_neck) and c.eyes_traj_time < T_neck <= c.max_neck_traj_time):
            raise InvalidInput(
                f"neck_traj_time: expected a time longer than eyes_traj_time = "
                f"{c.eyes_traj_time} s and at most max_neck_traj_time = "
                f"{c.max_neck_traj_time} s, got {neck_traj_time}")
        for _ in range(6):
            plan = self._rollout(target, joints, start, previous, T_neck)
            if len(plan.t) < 2:
                return plan
            rep = self.rate_limits.report(
                JointTrajectory(GAZE_JOINTS, plan.t, plan.q, plan.qd))
            if rep.within(0.02):
                return plan
            T_neck *= rep.time_scale * 1.05
        return plan

    def _rollout(self, target: np.ndarray, joints: Mapping[str, float],
                 start: GazeState | None, previous: GazeSolution | None,
                 T_neck: float) -> GazePlan:
        """One roll-out of :meth:`plan` with the neck trajectory time ``T_neck`` [s]."""
        c = self.config
        q, eyes0 = self.configuration(joints)
        # the start and the path keep to the hard limits, the targets to the margin
        lo, hi = self.model.lower[self._neck_idx], self.model.upper[self._neck_idx]
        if start is not None:
            neck = np.clip(start.neck, lo, hi)
            eyes = np.array(start.eyes, dtype=float)
            q[self._neck_idx] = neck
        else:
            neck = np.clip(q[self._neck_idx], lo, hi)
            eyes = eyes0
        eyes, _ = self.fixation.clip(eyes, margin=False)
        sol = self.solve(target, dict(zip(self.model.joint_names, q)), previous)
        Ts = c.period
        loop_neck = MinJerkLoop(3, T_neck, Ts)
        loop_eyes = MinJerkLoop(3, c.eyes_traj_time, Ts)
        if start is not None:
            loop_neck.x = np.array(start.neck_filter, dtype=float)
            loop_eyes.x = np.array(start.eyes_filter, dtype=float)
        p = sol.target
        q[self._neck_idx] = neck
        fix, _ = self.eyes_for(q, p)
        ts, qs, qds, states = [], [], [], []
        k = 0
        n_max = int(math.ceil(c.max_duration_factor * T_neck / Ts))
        n_min = int(math.ceil(1.5 * c.eyes_traj_time / Ts))
        while True:
            done = (k >= n_min
                    and float(np.abs(sol.neck - neck).max()) < c.settle_tolerance
                    and float(np.abs(fix - eyes).max()) < c.settle_tolerance
                    and float(np.abs(loop_neck.x[0]).max()) * Ts < c.settle_tolerance
                    and float(np.abs(loop_eyes.x[0]).max()) * Ts < c.settle_tolerance)
            if done:  # the last sample: exactly at the targets, at rest
                neck, eyes = sol.neck, sol.eyes
                loop_neck.x[:] = 0.0
                loop_eyes.x[:] = 0.0
            states.append(GazeState(neck, eyes, loop_neck.x, loop_eyes.x))
            ts.append(k * Ts)
            qs.append(np.concatenate((neck, eyes)))
            if done or k >= n_max:
                qds.append(np.zeros(6))
                break
            u_neck, u_eyes = loop_neck.velocity, loop_eyes.velocity
            neck_next = np.clip(sol.neck - loop_neck.step(sol.neck - neck), lo, hi)
            q[self._neck_idx] = neck_next
            fix_next, _ = self.eyes_for(q, p)
            eyes_next, _ = self.fixation.clip(fix_next - loop_eyes.step(fix - eyes),
                                              margin=False)
            qds.append(np.concatenate((u_neck, u_eyes + (fix_next - fix) / Ts)))
            neck, eyes, fix = neck_next, eyes_next, fix_next
            k += 1
        return GazePlan(sol, np.array(ts), np.array(qs), np.array(qds), tuple(states))

    def update(self, plan: GazePlan, elapsed: float, target: np.ndarray,
               joints: Mapping[str, float]) -> GazePlan:
        """Tracking update: a new ``target`` while ``plan`` has run for ``elapsed`` [s];
        continues from the plan's state then (module doc)."""
        return self.plan(target, joints, start=plan.state_at(elapsed), previous=plan.solution)

    # ------------------------------------------------------------------ state
    def fixation_point(self, joints: Mapping[str, float]) -> np.ndarray | None:
        """The point (3,) [m] in root_link the eyes fixate at ``joints``; None when the
        optical axes are parallel or diverge."""
        q, eyes = self.configuration(joints)
        return self.fixation.fixation_point(self.neck.head_pose(q), eyes)

    def fixation_errors(self, joints: Mapping[str, float], target: np.ndarray) -> np.ndarray:
        """Angles [rad] (2,) between each optical axis at ``joints`` and the direction to
        ``target`` (3,) [m] in root_link."""
        q, eyes = self.configuration(joints)
        return self.fixation.errors(self.neck.head_pose(q), eyes, np.asarray(target, float))

    def head_joints(self, joints: Mapping[str, float]) -> np.ndarray:
        """The six head joints (6,) [rad] of ``joints`` (missing ones are 0)."""
        q, eyes = self.configuration(joints)
        return np.concatenate((q[self._neck_idx], eyes))
