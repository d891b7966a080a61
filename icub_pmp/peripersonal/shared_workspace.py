"""SharedWorkspace: the part of the peripersonal space both arms reach.

Bhat and Mohan 2018 (Fig. 3d): "There is an overlap between the networks representing the
intersecting peripersonal areas where both the robots can operate". Here a neuron of one
arm's map belongs to the shared workspace when the other arm's map has a neuron within
``reach_radius`` of it (the other arm reaches that place too).
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS
from icub_pmp.peripersonal.growing_neural_gas import GrowingNeuralGas, as_points

__all__ = ["SharedWorkspace"]


class SharedWorkspace:
    """The overlap of the two arms' maps.

    Args:
        maps: arm -> its trained :class:`GrowingNeuralGas` ('left' and 'right').
        reach_radius: a point within this distance [m] of a neuron is inside a map.
    """

    def __init__(self, maps: Mapping[str, GrowingNeuralGas], reach_radius: float):
        if not (math.isfinite(reach_radius) and reach_radius > 0):
            raise InvalidInput(f"reach_radius: expected a distance > 0 m, got {reach_radius}")
        for a in maps:
            if a not in HANDS:
                raise UnknownName("arm", a, HANDS)
        for a in HANDS:
            if a not in maps:
                raise InvalidInput(f"maps: both arms' maps are needed, missing {a!r}")
            maps[a].require_trained()
        self.maps = dict(maps)
        self.reach_radius = float(reach_radius)
        self._idx: dict[str, np.ndarray] = {}
        for a in HANDS:
            other = "right" if a == "left" else "left"
            _, d = self.maps[other].nearest(self.maps[a].neurons)
            idx = np.flatnonzero(d <= self.reach_radius)
            idx.setflags(write=False)
            self._idx[a] = idx

    def _arm(self, arm: str) -> str:
        if arm not in HANDS:
            raise UnknownName("arm", arm, HANDS)
        return arm

    def neurons(self, arm: str) -> np.ndarray:
        """Indices of ``arm``'s neurons that the other arm also reaches."""
        return self._idx[self._arm(arm)]

    def points(self, arm: str) -> np.ndarray:
        """Positions (n, 3) [m] of :meth:`neurons`."""
        return self.maps[self._arm(arm)].neurons[self._idx[arm]]

    def size(self, arm: str) -> int:
        """Number of ``arm``'s neurons in the shared workspace."""
        return int(len(self.neurons(arm)))

    def inside(self, arm: str, points: object) -> np.ndarray:
        """(m,) bool: which points (m, 3) [m] are inside ``arm``'s map."""
        _, d = self.maps[self._arm(arm)].nearest(points)
        return d <= self.reach_radius

    def contains(self, points: object) -> np.ndarray:
        """(m,) bool: which points (m, 3) [m] both arms reach."""
        pts = as_points(points)
        return self.inside("left", pts) & self.inside("right", pts)
