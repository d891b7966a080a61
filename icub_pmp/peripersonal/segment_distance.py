"""Distance between line segments, vectorised (the core of capsule-capsule clearance).

The closest points of segments ``p(s) = p0 + s (p1 - p0)`` and ``q(t) = q0 + t (q1 - q0)``,
s, t in [0, 1], by the clamped solution of the 2x2 normal equations (Ericson, "Real-Time
Collision Detection", 2005, sect. 5.1.9), with degenerate (point) segments handled. Two
capsules of radii r_a, r_b around such segments are ``segment_distance - r_a - r_b`` apart.
"""

from __future__ import annotations

import numpy as np

__all__ = ["segment_distance"]

_EPS = 1e-12


def segment_distance(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray
                     ) -> np.ndarray:
    """Smallest distance [m] between segments [p0, p1] and [q0, q1].

    All four arguments are (..., 3) arrays [m] broadcast against each other; the result has
    the broadcast leading shape.
    """
    p0, p1, q0, q1 = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (p0, p1, q0, q1)))
    d1 = p1 - p0
    d2 = q1 - q0
    r = p0 - q0
    a = np.einsum("...i,...i->...", d1, d1)
    e = np.einsum("...i,...i->...", d2, d2)
    f = np.einsum("...i,...i->...", d2, r)
    c = np.einsum("...i,...i->...", d1, r)
    b = np.einsum("...i,...i->...", d1, d2)
    denom = a * e - b * b
    a_ok = a > _EPS
    e_ok = e > _EPS
    with np.errstate(divide="ignore", invalid="ignore"):
        # general case: s on the infinite lines' closest points, clamped
        s = np.where(denom > _EPS * np.maximum(a * e, _EPS), (b * f - c * e) / denom, 0.0)
        s = np.clip(s, 0.0, 1.0)
        t = np.where(e_ok, (b * s + f) / np.where(e_ok, e, 1.0), 0.0)
        # t outside [0, 1]: clamp it and recompute s for the clamped t
        s_lo = np.clip(np.where(a_ok, -c / np.where(a_ok, a, 1.0), 0.0), 0.0, 1.0)
        s_hi = np.clip(np.where(a_ok, (b - c) / np.where(a_ok, a, 1.0), 0.0), 0.0, 1.0)
        s = np.where(t < 0.0, s_lo, np.where(t > 1.0, s_hi, s))
        t = np.clip(t, 0.0, 1.0)
        # a point segment q: t = 0, s from the projection onto p
        s = np.where(e_ok, s, s_lo)
        # a point segment p: s = 0, t from the projection onto q
        s = np.where(a_ok, s, 0.0)
        t = np.where(a_ok, t, np.clip(np.where(e_ok, f / np.where(e_ok, e, 1.0), 0.0), 0.0, 1.0))
    diff = (p0 + s[..., None] * d1) - (q0 + t[..., None] * d2)
    return np.sqrt(np.einsum("...i,...i->...", diff, diff))
