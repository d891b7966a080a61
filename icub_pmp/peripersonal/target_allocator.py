"""TargetAllocator: which arm acts on which object, in which order (Bhat and Mohan 2018,
"Coupled interaction between internal models", item 1).

The scene (objects' centroids) excites each arm's map; the most active neuron of a map for
an object (its best-matching neuron, within ``reach_radius``: otherwise the arm does not
reach it) carries that arm's reward for the object (:class:`RewardField`). Objects fetching
the highest rewards are acted on first, so each arm starts in its own part of the space and
enters the shared part last ("objects in the peripheries of the overall workspace are
assembled first").

Parallel work is maximised over the whole scene: objects only one arm reaches go to it; the
objects both reach are split so that the number of rounds (``max`` of the two arms' loads,
one object per arm per round) is the smallest, and among such splits the total reward is the
largest (the shared objects whose reward difference favours the left arm most go left: an
exact solution, by sorting). Each arm then takes its objects by decreasing reward; round r
pairs the two arms' r-th objects.
"""

from __future__ import annotations

import math
from typing import Mapping, NamedTuple

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.robot_spec import HANDS
from icub_pmp.peripersonal.growing_neural_gas import GrowingNeuralGas, as_points
from icub_pmp.peripersonal.reward_field import RewardField

__all__ = ["TargetAllocator", "Allocation"]


class Allocation(NamedTuple):
    """The allocation of a scene's objects (indices into the given object list).

    Attributes:
        assignments: arm -> its objects in execution order (highest reward first).
        next: arm -> the object it acts on now (None when it has none).
        unreachable: objects neither arm reaches.
        rewards: (m, 2) each object's reward for (left, right) [-], 0 where not reached.
        reachable: (m, 2) bool, whether (left, right) reaches each object.
        rounds: parallel rounds needed (the larger of the two arms' loads).
    """

    assignments: Mapping[str, tuple[int, ...]]
    next: Mapping[str, int | None]
    unreachable: tuple[int, ...]
    rewards: np.ndarray
    reachable: np.ndarray
    rounds: int

    def pairs(self) -> list[tuple[int | None, int | None]]:
        """(left object, right object) of each round; None where that arm is idle."""
        left, right = self.assignments["left"], self.assignments["right"]
        return [(left[r] if r < len(left) else None, right[r] if r < len(right) else None)
                for r in range(self.rounds)]


class TargetAllocator:
    """Allocates objects to arms (module doc).

    Args:
        maps: arm -> trained map; rewards: arm -> its :class:`RewardField` over that map.
        reach_radius: objects farther than this [m] from every neuron are not reached.
    """

    def __init__(self, maps: Mapping[str, GrowingNeuralGas], rewards: Mapping[str, RewardField],
                 reach_radius: float):
        if not (math.isfinite(reach_radius) and reach_radius > 0):
            raise InvalidInput(f"reach_radius: expected a distance > 0 m, got {reach_radius}")
        for a in HANDS:
            if a not in maps or a not in rewards:
                raise InvalidInput(f"maps and rewards are needed for both arms, missing {a!r}")
            maps[a].require_trained()
        self.maps, self.rewards, self.reach_radius = dict(maps), dict(rewards), reach_radius

    def rewards_of(self, objects: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rewards (m, 2), reachable (m, 2)) of objects (m, 3) [m] for (left, right)."""
        r = np.zeros((len(objects), 2))
        ok = np.zeros((len(objects), 2), dtype=bool)
        for k, a in enumerate(HANDS):
            idx, d = self.maps[a].nearest(objects)
            ok[:, k] = d <= self.reach_radius
            r[:, k] = np.where(ok[:, k], self.rewards[a][idx], 0.0)
        return r, ok

    def allocate(self, objects: object) -> Allocation:
        """Allocate ``objects`` (m, 3) [m, root_link], m >= 1 (module doc)."""
        pts = as_points(objects, "objects")
        if len(pts) == 0:
            raise InvalidInput("objects: the scene has no objects to allocate (empty list)")
        r, ok = self.rewards_of(pts)
        left_only = [i for i in range(len(pts)) if ok[i, 0] and not ok[i, 1]]
        right_only = [i for i in range(len(pts)) if ok[i, 1] and not ok[i, 0]]
        shared = [i for i in range(len(pts)) if ok[i, 0] and ok[i, 1]]
        unreachable = tuple(i for i in range(len(pts)) if not ok[i].any())
        # shared objects by how much more they reward the left arm; the top k go left
        shared.sort(key=lambda i: (-(r[i, 0] - r[i, 1]), i))
        n_l, n_r, m = len(left_only), len(right_only), len(shared)
        best_k, best = 0, None
        for k in range(m + 1):
            key = (max(n_l + k, n_r + m - k), -sum(r[i, 0] for i in shared[:k])
                   - sum(r[i, 1] for i in shared[k:]))
            if best is None or key < best:
                best_k, best = k, key
        mine = {"left": left_only + shared[:best_k], "right": right_only + shared[best_k:]}
        assignments = {}
        for c, a in enumerate(HANDS):
            assignments[a] = tuple(sorted(mine[a], key=lambda i: (-r[i, c], i)))
        return Allocation(
            assignments=assignments,
            next={a: (assignments[a][0] if assignments[a] else None) for a in HANDS},
            unreachable=unreachable,
            rewards=r,
            reachable=ok,
            rounds=max(len(v) for v in assignments.values()),
        )
