"""JointLimitField: the repulsive intrinsic field that keeps joints inside their range (eq 6).

    lambda_i = (q_i - q_i_min) / (q_i_max - q_i_min)
    T_i      = alpha * ln((1 - lambda_i) / lambda_i)          (eq 6 of Mohan et al. 2009)

an inverted sigmoid: zero at mid-range, diverging at both limits (Fig 2). Superposed on the
torques mapped from the extrinsic field, it selects, among the configurations compatible with
the target, ones away from the limits; a narrowed range (e.g. of the wrist, Fig 2 bottom)
changes the posture the relaxation settles into.

Numerical soundness: lambda is clamped to [eps, 1 - eps] so T stays finite; the relaxation
additionally keeps every joint strictly inside its range (a per-joint fraction-to-the-boundary
rule, :mod:`relaxation`), so the limits are never crossed whatever the step.
"""

from __future__ import annotations

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["JointLimitField"]


class JointLimitField:
    """Eq 6 on n joints with limits ``lower``/``upper`` (n,) [rad] and scale ``alpha`` [N m]."""

    def __init__(self, lower, upper, alpha: float, eps: float = 1e-9):
        lo = np.array(lower, dtype=float).reshape(-1)
        hi = np.array(upper, dtype=float).reshape(-1)
        if lo.shape != hi.shape or not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise InvalidInput("joint limits: lower and upper must be finite and of equal length")
        if np.any(hi <= lo):
            bad = np.flatnonzero(hi <= lo)
            raise InvalidInput(f"joint limits: upper <= lower at joint index(es) {bad.tolist()}")
        if not np.isfinite(alpha) or alpha < 0:
            raise InvalidInput(f"joint limit field scale alpha: expected >= 0 N m, got {alpha}")
        self.lower, self.upper = lo, hi
        self.range = hi - lo
        for a in (self.lower, self.upper, self.range):
            a.setflags(write=False)
        self.alpha = float(alpha)
        self.eps = float(eps)
        self._inv_range = 1.0 / self.range
        self._alpha_inv_range = self.alpha * self._inv_range

    def normalised(self, q: np.ndarray) -> np.ndarray:
        """lambda (n,) in [eps, 1 - eps]: the normalised joint angle of eq 6."""
        return np.minimum(np.maximum((q - self.lower) / self.range, self.eps), 1.0 - self.eps)

    def torques(self, q: np.ndarray) -> np.ndarray:
        """T (n,) [N m] of eq 6 (positive near the lower limit, negative near the upper)."""
        lam = self.normalised(q)
        return self.alpha * np.log((1.0 - lam) / lam)

    def stiffness(self, q: np.ndarray) -> np.ndarray:
        """-dT/dq (n,) [N m/rad] (the field is diagonal, positive: it stabilises)."""
        lam = self.normalised(q)
        return self.alpha * (1.0 / lam + 1.0 / (1.0 - lam)) / self.range

    def torques_and_stiffness(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(:meth:`torques`, :meth:`stiffness`) with one evaluation of lambda."""
        lam = np.minimum(np.maximum((q - self.lower) * self._inv_range, self.eps), 1.0 - self.eps)
        mu = 1.0 - lam
        return self.alpha * np.log(mu / lam), self._alpha_inv_range / (lam * mu)

    def potential(self, q: np.ndarray) -> float:
        """Potential U with T = -dU/dq [J] (convex; minimum at mid-range)."""
        lam = self.normalised(q)
        u = lam * np.log(lam) + (1.0 - lam) * np.log(1.0 - lam)
        return float(np.sum(self.alpha * self.range * u))
