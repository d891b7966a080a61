"""Capsule: part of a link's collision volume, a segment with a radius in the link's frame.

The imagined collision check compares the two arms' bodies as capsules (the iCub's arms can
hit each other, which the paper's two separate robots could not).

:func:`fit_capsule` builds the capsule that bounds a point set: the segment lies on the
points' principal axis through their centroid, the radius is the largest distance of a point
from that axis, and the end points are pulled in as far as every point stays inside.
:func:`fit_capsules` covers a link's collision mesh with one to ``max_pieces`` such
capsules: the points of the mesh's convex hull (:class:`~icub_pmp.geometry.LinkHull`;
the physics collides the hull) are cut into equal slabs across the second principal axis,
one capsule per slab, and the number of slabs with the smallest total capsule volume wins
(one capsule for a long link such as the forearm, a few for a flat one such as the palm).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["Capsule", "fit_capsule", "fit_capsules"]


class Capsule(NamedTuple):
    """A capsule fixed to ``frame``: segment ``a`` - ``b`` (3,) [m] in that frame, ``radius``
    [m]."""

    frame: str
    a: np.ndarray
    b: np.ndarray
    radius: float

    @property
    def volume(self) -> float:
        """Volume [m^3]."""
        r = self.radius
        return math.pi * r * r * float(np.linalg.norm(self.b - self.a)) + 4.0 / 3.0 * math.pi * r**3


def _check(frame: str, points: np.ndarray) -> np.ndarray:
    v = np.asarray(points, dtype=float)
    if v.ndim != 2 or v.shape[1] != 3 or len(v) < 2 or not np.all(np.isfinite(v)):
        raise InvalidInput(f"points of {frame}: expected finite (n >= 2, 3) [m], got {v.shape}")
    return v


def fit_capsule(frame: str, points: np.ndarray, axis: np.ndarray | None = None) -> Capsule:
    """The bounding capsule of ``points`` (n, 3) [m] given in ``frame`` (module doc); its
    axis is ``axis`` (3,) when given, else the points' principal axis."""
    v = _check(frame, points)
    c = v.mean(axis=0)
    if axis is None:
        _, _, vt = np.linalg.svd(v - c, full_matrices=False)
        u = vt[0]
    else:
        u = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    t = (v - c) @ u
    rho = np.linalg.norm((v - c) - t[:, None] * u, axis=1)
    r = float(rho.max())
    half = np.sqrt(np.maximum(r * r - rho * rho, 0.0))
    t_lo = float(np.max(t - half))  # the segment must meet every point's cover interval
    t_hi = float(np.min(t + half))
    if t_lo <= t_hi:  # one point meets them all: a sphere, centred
        t0 = t1 = 0.5 * (t_lo + t_hi)
    else:
        t0, t1 = t_hi, t_lo
    return Capsule(frame, c + t0 * u, c + t1 * u, r)


def fit_capsules(frame: str, points: np.ndarray, max_pieces: int = 4) -> tuple[Capsule, ...]:
    """One to ``max_pieces`` capsules covering ``points`` (n, 3) [m] (module doc), the set
    with the smallest total volume."""
    v = _check(frame, points)
    if max_pieces < 1:
        raise InvalidInput(f"max_pieces: expected >= 1, got {max_pieces}")
    c = v.mean(axis=0)
    _, _, vt = np.linalg.svd(v - c, full_matrices=False)
    s = (v - c) @ vt[1]
    best: tuple[Capsule, ...] = (fit_capsule(frame, v),)
    best_vol = best[0].volume
    for n in range(2, max_pieces + 1):
        edges = np.linspace(s.min(), s.max(), n + 1)
        caps = []
        for k in range(n):
            m = (s >= edges[k]) & (s <= edges[k + 1])
            if m.sum() >= 2:
                caps.append(fit_capsule(frame, v[m], vt[0]))
        vol = sum(cp.volume for cp in caps)
        if vol < best_vol:
            best, best_vol = tuple(caps), vol
    return best
