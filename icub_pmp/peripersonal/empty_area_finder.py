"""EmptyAreaFinder: where in the shared workspace an object can be put down (Bhat and Mohan
2018, "Localization of an empty area in the workspace").

The scene drives the activity of the shared workspace's neurons; each neuron counts only the
objects within the threshold T (the gripper's width) of its weights:
``x_i = sum_{j: ||s_i - S_j|| < T} exp(-||s_i - S_j||^2 / 2 sigma_s^2) / (sqrt(2 pi) sigma_s)``.
The least active neuron marks the empty area. Optionally the area must have a radius: no
object within ``radius`` of the neuron ("empty areas of specific radii are localized").

Among equally inactive neurons (every neuron with no object within T has x_i = 0) the one
nearest the centroid of the shared workspace wins: well inside both arms' reach. A height
band can restrict the candidates (e.g. just above a table). When no candidate is clear of
every object by ``max(T, radius)`` the search fails with :class:`NoEmptyArea`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.peripersonal.exceptions import NoEmptyArea
from icub_pmp.peripersonal.growing_neural_gas import as_points
from icub_pmp.peripersonal.neural_activity import neural_activity
from icub_pmp.peripersonal.shared_workspace import SharedWorkspace

__all__ = ["EmptyAreaFinder", "EmptyArea"]


class EmptyArea(NamedTuple):
    """An empty area: the neuron's position ``point`` (3,) [m], which map (``arm``) and
    neuron it is, its activity [1/m] (0 when clear) and its ``clearance`` [m] (distance to
    the nearest object; inf without objects)."""

    point: np.ndarray
    arm: str
    neuron: int
    activity: float
    clearance: float


class EmptyAreaFinder:
    """Empty-area search over a :class:`SharedWorkspace` (module doc).

    Args:
        shared: the shared workspace; threshold: T [m]; sigma_s: activity kernel width [m].
    """

    def __init__(self, shared: SharedWorkspace, threshold: float, sigma_s: float):
        for name, v in (("threshold", threshold), ("sigma_s", sigma_s)):
            if not (math.isfinite(v) and v > 0):
                raise InvalidInput(f"{name}: expected a distance > 0 m, got {v}")
        self.shared, self.threshold, self.sigma_s = shared, float(threshold), float(sigma_s)

    def find(self, objects: object, arm: str = "left", radius: float | None = None,
             z_range: tuple[float, float] | None = None,
             x_range: tuple[float, float] | None = None) -> EmptyArea:
        """The empty area of ``arm``'s shared neurons for ``objects`` (m, 3) [m] (m may be
        0), at least ``radius`` [m] (default T) from every object, optionally with the
        neuron's z within ``z_range`` and its x within ``x_range`` (low, high) [m] (e.g.
        over a table)."""
        pts = as_points(objects, "objects") if len(np.atleast_1d(objects)) else np.zeros((0, 3))
        if radius is not None and not (math.isfinite(radius) and radius > 0):
            raise InvalidInput(f"radius: expected a distance > 0 m, got {radius}")
        idx = self.shared.neurons(arm)
        cand = self.shared.points(arm)
        for axis, name, band in ((2, "z_range", z_range), (0, "x_range", x_range)):
            if band is None:
                continue
            lo, hi = (float(v) for v in band)
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise InvalidInput(f"{name}: expected finite low < high [m], got {band}")
            keep = (cand[:, axis] >= lo) & (cand[:, axis] <= hi)
            idx, cand = idx[keep], cand[keep]
        need = max(self.threshold, radius or 0.0)
        if len(cand) == 0:
            raise NoEmptyArea(f"no neuron of the {arm} arm's shared workspace"
                              f"{' in z_range ' + str(z_range) if z_range else ''}: nowhere to "
                              f"put an object", 0.0, need)
        x = neural_activity(cand, pts, self.sigma_s, self.threshold)
        if len(pts):
            clear = np.sqrt(np.min(np.sum((cand[:, None] - pts[None]) ** 2, axis=2), axis=1))
        else:
            clear = np.full(len(cand), np.inf)
        ok = clear >= need
        if not ok.any():
            raise NoEmptyArea(f"no empty area of radius {need:.3f} m in the shared workspace of "
                              f"the {arm} arm: the clearest neuron is {clear.max():.3f} m from "
                              f"an object", float(clear.max()), need)
        centre = self.shared.points(arm).mean(axis=0)
        central = np.linalg.norm(cand - centre, axis=1)
        order = np.lexsort((central, x))  # least active, then most central
        best = int(order[np.argmax(ok[order])])
        return EmptyArea(cand[best].copy(), arm, int(idx[best]), float(x[best]),
                         float(clear[best]))
