"""GazePlan: the head trajectory of a gaze command, with the controllers' state at each sample.

The state is kept so that a new target given while a plan runs (tracking) continues from the
exact state the executing trajectory is in: positions and both minimum-jerk filters.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.gaze.gaze_solution import GAZE_JOINTS, GazeSolution

__all__ = ["GazePlan", "GazeState"]


@dataclasses.dataclass(frozen=True)
class GazeState:
    """State of the gaze controllers.

    Attributes:
        neck: neck pitch, roll, yaw (3,) [rad]; eyes: tilt, version, vergence (3,) [rad].
        neck_filter, eyes_filter: states (2, 3) of the two min-jerk controllers
            (:class:`~icub_pmp.gaze.min_jerk_loop.MinJerkLoop`: velocity command and its
            rate).
    """

    neck: np.ndarray
    eyes: np.ndarray
    neck_filter: np.ndarray
    eyes_filter: np.ndarray

    def __post_init__(self) -> None:
        for name in ("neck", "eyes", "neck_filter", "eyes_filter"):
            a = np.array(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)


@dataclasses.dataclass(frozen=True)
class GazePlan:
    """A head trajectory sampled every controller period.

    Attributes:
        solution: the posture it goes to.
        t: sample times from the start (N,) [s], t[0] = 0 (the start state).
        q: positions (N, 6) [rad]; qd: velocities (N, 6) [rad/s], in ``joint_names`` order.
        states: controller state at each sample (N,).
        joint_names: :data:`~icub_pmp.gaze.gaze_solution.GAZE_JOINTS`.
    """

    solution: GazeSolution
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    states: tuple[GazeState, ...]
    joint_names: tuple[str, ...] = GAZE_JOINTS

    def __post_init__(self) -> None:
        for name in ("t", "q", "qd"):
            a = np.array(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        n = len(self.t)
        if (n < 2 or self.q.shape != (n, len(self.joint_names)) or self.qd.shape != self.q.shape
                or len(self.states) != n):
            raise InvalidInput(f"GazePlan: inconsistent samples: t {self.t.shape}, q "
                               f"{self.q.shape}, qd {self.qd.shape}, {len(self.states)} states")

    @property
    def duration(self) -> float:
        """Time of the last sample [s]."""
        return float(self.t[-1])

    def index_at(self, t: float) -> int:
        """Index of the last sample at or before ``t`` [s] (clamped to the ends)."""
        return int(np.clip(np.searchsorted(self.t, t, side="right") - 1, 0, len(self.t) - 1))

    def state_at(self, t: float) -> GazeState:
        """Controller state at time ``t`` [s] from the start (the sample at or before it)."""
        return self.states[self.index_at(t)]
