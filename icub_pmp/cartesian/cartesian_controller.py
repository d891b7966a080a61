"""CartesianController: go to a hand pose, the cartesianController role (Sect. 4 of the reaching
paper): solve eq 11 (:class:`~icub_pmp.cartesian.IkSolver`), then roll out the
multi-referential minimum-jerk trajectory toward the answer
(:class:`~icub_pmp.cartesian.MinJerkGenerator`).

A goal given while the previous trajectory of the same chain is still running starts from that
trajectory's generator state at the current time (position, velocity and filters), so the
motion bends smoothly toward the new target instead of restarting from rest; a goal with an
explicit start configuration, for another chain, or after the trajectory ended starts from the
given or the measured joints. Times are the node clock's [s] (simulated time with
``use_sim_time``).

With ``rate_limits`` (:class:`~icub_pmp.control.trajectory_limits.JointRateLimits`), a
trajectory that would ask a joint for more than its velocity or acceleration limit is stretched
in time to them (same path: times * s, velocities / s); such a motion is not continued by the
next goal (its generator states belong to the nominal timing), it starts from the measured
joints.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Mapping

import numpy as np

from icub_pmp.cartesian.ik_solution import IkSolution
from icub_pmp.cartesian.ik_solver import IkSolver
from icub_pmp.cartesian.min_jerk_config import MinJerkConfig
from icub_pmp.cartesian.min_jerk_generator import MinJerkGenerator
from icub_pmp.cartesian.sampled_trajectory import SampledTrajectory
from icub_pmp.control.joint_trajectory import JointTrajectory
from icub_pmp.control.trajectory_limits import JointRateLimits
from icub_pmp.errors import InvalidInput

__all__ = ["CartesianController", "CartesianMotion"]


@dataclasses.dataclass(frozen=True)
class CartesianMotion:
    """The answer to a go-to goal.

    Attributes:
        solution: the eq 11 solution (``success`` False: nothing to execute).
        trajectory: the min-jerk joint trajectory toward it (None when the solve failed).
        start_time: when the trajectory starts [s] (the goal's time).
        continued: the trajectory continues the running one (same chain, not finished).
        q_start: the full configuration (nq,) [rad] the motion starts from.
        time_scale: >= 1, how much the trajectory was stretched to the joint rate limits.
        slowdown: one line saying which joint's limit set ``time_scale`` ("" when 1).
    """

    solution: IkSolution
    trajectory: SampledTrajectory | None
    start_time: float
    continued: bool
    q_start: np.ndarray
    time_scale: float = 1.0
    slowdown: str = ""


class CartesianController:
    """Solve and roll out go-to goals, continuing the running trajectory (module doc).

    Args:
        solver: the eq 11 solver (its model is used for configurations and kinematics).
        config: min-jerk settings (``period``, default ``trajectory_time``).
    """

    def __init__(self, solver: IkSolver, config: MinJerkConfig | None = None,
                 rate_limits: JointRateLimits | None = None) -> None:
        self.solver = solver
        self.model = solver.model
        self.config = config or MinJerkConfig()
        self.rate_limits = rate_limits
        self.active: CartesianMotion | None = None

    def start_configuration(
        self,
        measured: Mapping[str, float] | None,
        start_state: Mapping[str, float] | None = None,
    ) -> np.ndarray:
        """The full configuration (nq,) [rad] a goal starts from: the joints of
        ``start_state`` over the ``measured`` ones over the rest posture. Raises
        :class:`InvalidInput` when neither ``start_state`` nor ``measured`` is given."""
        base = self.model.posture("rest")
        if measured is not None:
            base = self.model.q_from_dict(measured, default=base)
        if start_state:
            return self.model.q_from_dict(start_state, default=base)
        if measured is None:
            raise InvalidInput("no /joint_states received yet and the request has no start_state")
        return base

    def trajectory_time(self, requested: float) -> float:
        """The duration T [s] of a goal: ``requested`` or the default when 0; at least 10
        generator periods, at most ``max_trajectory_time`` (raises :class:`InvalidInput`)."""
        T = float(requested) or self.config.trajectory_time
        T_max = self.config.max_trajectory_time
        if not (math.isfinite(T) and 10 * self.config.period <= T <= T_max):
            raise InvalidInput(
                f"trajectory_time: expected 0 (default) or {10 * self.config.period:g} to "
                f"{T_max:g} s (max_trajectory_time), got {requested}")
        return T

    def go_to(
        self,
        chain: str,
        position: np.ndarray,
        rotation: np.ndarray | None,
        now: float,
        *,
        trajectory_time: float = 0.0,
        measured: Mapping[str, float] | None = None,
        start_state: Mapping[str, float] | None = None,
    ) -> CartesianMotion:
        """Solve for the hand of ``chain`` at ``position`` (3,) [m] (and ``rotation`` (3, 3),
        root_link) and roll out the trajectory starting at ``now`` [s]; see the module doc for
        where it starts. The motion becomes the running one when the solve succeeds."""
        T = self.trajectory_time(trajectory_time)
        state = None
        act = self.active
        if act is not None and act.trajectory is not None and act.solution.chain == chain \
                and not start_state:
            elapsed = now - act.start_time
            if 0.0 <= elapsed < act.trajectory.duration:
                state = act.trajectory.state_at(elapsed)
        if state is not None:
            q_start = act.q_start.copy()
            q_start[self.model.indices(act.trajectory.joint_names)] = state.q
        else:
            q_start = self.start_configuration(measured, start_state)
        solution = self.solver.solve(chain, position, rotation, q_start)
        if not solution.success:
            return CartesianMotion(solution, None, now, False, q_start)
        gen = MinJerkGenerator(self.model, self.solver.problem(chain).chain, self.config, T)
        gen.reset(q_start)
        if state is not None:
            gen.restore(state)
        gen.set_target(solution.q)
        traj = gen.rollout()
        scale, note = 1.0, ""
        if self.rate_limits is not None and len(traj.t) > 1:
            rep = self.rate_limits.report(
                JointTrajectory(traj.joint_names, traj.t, traj.q, traj.qd))
            if rep.time_scale > 1.0 + 1e-3:
                scale = rep.time_scale * 1.01  # a margin over the sampled peak
                note = (f"slowed down to the joint limits: {traj.duration:.2f} -> "
                        f"{traj.duration * scale:.2f} s ({rep.describe()})")
                traj = dataclasses.replace(traj, t=traj.t * scale, qd=traj.qd / scale)
        motion = CartesianMotion(solution, traj, now, state is not None, q_start, scale, note)
        self.active = motion if scale == 1.0 else None
        return motion
