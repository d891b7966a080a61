"""PairPlan: two imagined reaches, the collision verdict and the resulting schedule."""

from __future__ import annotations

from typing import Mapping, NamedTuple

import numpy as np

from icub_pmp.peripersonal.collision_verdict import CollisionVerdict
from icub_pmp.pmp.reach_plan import ReachPlan

__all__ = ["ScheduleStep", "PairSchedule", "PairPlan", "ACTIONS", "MODES"]

#: what an arm does in a step: reach its target, or move to / from the safe posture
ACTIONS = ("reach", "park")
#: parallel: both reaches start together; serial: one after the other
MODES = ("parallel", "serial")


class ScheduleStep(NamedTuple):
    """One arm motion of a schedule.

    Attributes:
        arm: 'left' | 'right'.
        action: one of :data:`ACTIONS`.
        start: start time [s] from the beginning of the schedule.
        joint_names: the arm's joints (the columns of ``positions``).
        t: (N,) sample times [s] from ``start``.
        positions: (N, n) joint angles [rad]; velocities (N, n) [rad/s].
        clearance: the imagined verdict of this motion against the other arm.
    """

    arm: str
    action: str
    start: float
    joint_names: tuple[str, ...]
    t: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    clearance: CollisionVerdict

    @property
    def end(self) -> float:
        """End time [s] from the beginning of the schedule."""
        return self.start + float(self.t[-1])


class PairSchedule(NamedTuple):
    """How the pair is executed: ``mode`` (:data:`MODES`), the steps in start order, the
    total duration [s] and whether every step was imagined free of collisions."""

    mode: str
    steps: tuple[ScheduleStep, ...]
    duration: float
    safe: bool


class PairPlan(NamedTuple):
    """The result of :meth:`ImaginedCollisionCheck.plan_pair`.

    Attributes:
        plans: arm -> the imagined PMP reach from the start posture.
        verdict: the two reaches executed in parallel, compared.
        schedule: parallel if the verdict is clear, else serial (one arm goes, the other
            waits, at the safe posture when it is in the way).
        planning_time: wall time of the whole call [s].
    """

    plans: Mapping[str, ReachPlan]
    verdict: CollisionVerdict
    schedule: PairSchedule
    planning_time: float
