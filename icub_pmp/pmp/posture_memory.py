"""PostureMemory: babbled postures of the network's joints, recalled by hand positions.

The body-schema paper builds its internal model from random motor babbling: joint angles and
the resulting end-effector positions. This memory keeps such a babbling sample (drawn
uniformly within the joint limits, hand positions from the body model) and recalls, for given
hand targets, the posture whose hands came nearest (k-d tree, scipy).

Role in planning (Sect. 4, mental simulation): when the relaxation from the start posture
ends with a residual above tolerance although the memory holds a posture with its hands
nearer the targets, the target is not out of reach: the relaxation got caught (joint limits,
a local minimum of the fields). The planner then relaxes again from the same start with an
extra intrinsic field pulling toward the recalled posture (the DARWIN PMP's
``K_int (q_ref - q)``), fading with relaxation time so the final posture is the task's own.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import numpy as np
from scipy.spatial import cKDTree

from icub_pmp.errors import InvalidInput
from icub_pmp.pmp.jacobian_provider import JacobianProvider

__all__ = ["PostureMemory", "Recall"]


class Recall(NamedTuple):
    """A remembered posture and how far its hands were from the query."""

    q: np.ndarray  # (n,) [rad] over the memory's joints
    distance: float  # [m] Euclidean norm of the stacked hand-position differences
    hand_positions: np.ndarray  # (k, 3) [m]


class PostureMemory:
    """``size`` postures of ``joint_index`` joints (others held at ``q_base``) within
    ``lower``/``upper`` (n,) [rad], and the positions of ``frames`` they produce."""

    def __init__(
        self,
        provider: JacobianProvider,
        joint_index: Sequence[int] | np.ndarray,
        frames: Sequence[str],
        q_base: np.ndarray,
        lower: np.ndarray,
        upper: np.ndarray,
        size: int,
        seed: int = 0,
    ):
        if size < 1:
            raise InvalidInput(f"posture memory size: expected >= 1, got {size}")
        idx = np.asarray(joint_index, dtype=int)
        rng = np.random.default_rng(seed)
        self.postures = rng.uniform(lower, upper, size=(size, len(idx)))
        q = np.array(q_base, dtype=float)
        pos = np.empty((size, 3 * len(frames)))
        for i, qi in enumerate(self.postures):
            q[idx] = qi
            pos[i] = provider.positions(q, frames).reshape(-1)
        self.hand_positions = pos.reshape(size, len(frames), 3)
        self.frames = tuple(frames)
        self._tree = cKDTree(pos)

    def __len__(self) -> int:
        return len(self.postures)

    def recall(self, targets: np.ndarray, count: int = 1) -> list[Recall]:
        """The ``count`` postures whose hands were nearest ``targets`` (k, 3) [m], nearest
        first."""
        t = np.asarray(targets, dtype=float).reshape(-1)
        count = max(1, min(int(count), len(self)))
        dist, idx = self._tree.query(t, k=count)
        dist, idx = np.atleast_1d(dist), np.atleast_1d(idx)
        return [Recall(self.postures[i].copy(), float(d), self.hand_positions[i].copy())
                for d, i in zip(dist, idx)]
