"""SampledTrajectory: a joint trajectory produced by a generator, with the generator's state.

The generator state at every sample is kept so that a new target given mid-motion continues
from the exact state the executing trajectory is in (position, velocity and the filters).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["SampledTrajectory", "GeneratorState"]


@dataclasses.dataclass(frozen=True)
class GeneratorState:
    """State of :class:`~icub_pmp.cartesian.min_jerk_generator.MinJerkGenerator`.

    Attributes:
        q: joints (n,) [rad]; joint_filter (2, n); task_filter (2, 6).
    """

    q: np.ndarray
    joint_filter: np.ndarray
    task_filter: np.ndarray

    def __post_init__(self) -> None:
        for name in ("q", "joint_filter", "task_filter"):
            a = np.array(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)


@dataclasses.dataclass(frozen=True)
class SampledTrajectory:
    """Joint trajectory sampled every ``period``.

    Attributes:
        joint_names: URDF joint names, columns of ``q`` and ``qd``.
        t: sample times from the start (N,) [s], t[0] = 0.
        q: positions (N, n) [rad]; qd: velocities (N, n) [rad/s].
        hand_position: hand frame origin (N, 3) [m] in root_link.
        states: generator state at each sample (N,).
    """

    joint_names: tuple[str, ...]
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    hand_position: np.ndarray
    states: tuple[GeneratorState, ...]

    def __post_init__(self) -> None:
        for name in ("t", "q", "qd", "hand_position"):
            a = np.array(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        n = len(self.t)
        if self.q.shape != (n, len(self.joint_names)) or len(self.states) != n:
            raise InvalidInput("SampledTrajectory: inconsistent sample counts")

    @property
    def duration(self) -> float:
        """Time of the last sample [s]."""
        return float(self.t[-1])

    def index_at(self, t: float) -> int:
        """Index of the last sample at or before ``t`` [s] (clamped to the ends)."""
        return int(np.clip(np.searchsorted(self.t, t, side="right") - 1, 0, len(self.t) - 1))

    def state_at(self, t: float) -> GeneratorState:
        """Generator state at time ``t`` [s] from the start (the sample at or before it)."""
        return self.states[self.index_at(t)]
