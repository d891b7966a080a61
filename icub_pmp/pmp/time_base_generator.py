"""TimeBaseGenerator: the minimum-jerk time base xi(t) and the terminal-attractor gain Gamma(t).

Mohan, Morasso, Metta, Sandini (2009), Sect. 2.4, eq 7::

    xi(t)    = 6 (t/tau)^5 - 15 (t/tau)^4 + 10 (t/tau)^3
    Gamma(t) = xi_dot(t) / (1 - xi(t))

Inserting Gamma in the PMP dynamics (eq 4a, Appendix A eq A1) makes the relaxation reach its
equilibrium at t = tau. Gamma diverges at t -> tau (a simple pole, ``Gamma ~ 3 / (tau - t)``),
so it is never integrated directly here. Instead every PMP relaxation runs in the TBG's
*relaxation time*

    s(t) = integral_0^t Gamma dt' = -ln(1 - xi(t)),       ds = Gamma dt,

in which eq A1 becomes the autonomous basic PMP (eqs 1-5): ``dq/ds = A_int J^T F``. The
interval ``t in [0, tau)`` maps one-to-one onto ``s in [0, inf)``: the divergence of Gamma
is the infinite horizon of the basic relaxation, and ``t = tau`` is its equilibrium (the
limit ``s -> inf``), which the relaxation reaches numerically (see :mod:`relaxation`).
Appendix A's solution ``z = z0 (1 - xi)^gamma`` is ``z = z0 exp(-gamma s)``.

``1 - xi(t)`` is evaluated as ``xi(tau - t)`` (the polynomial is point-symmetric,
``xi(u) + xi(1 - u) = 1``), so s(t) has no cancellation error near tau.
"""

from __future__ import annotations

import math

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["TimeBaseGenerator"]


def _xi_unit(u: np.ndarray) -> np.ndarray:
    """Minimum-jerk polynomial of eq 7 on normalised time u in [0, 1]."""
    return u * u * u * (10.0 + u * (-15.0 + 6.0 * u))


class TimeBaseGenerator:
    """Minimum-jerk TBG of duration ``tau`` [s] (eq 7).

    All methods accept scalars or arrays of times ``t`` [s]; times are clipped into [0, tau].
    """

    def __init__(self, tau: float):
        tau = float(tau)
        if not math.isfinite(tau) or tau <= 0.0:
            raise InvalidInput(f"tau: expected a finite duration > 0 s, got {tau}")
        self.tau = tau

    def _u(self, t) -> np.ndarray:
        return np.clip(np.asarray(t, dtype=float) / self.tau, 0.0, 1.0)

    def xi(self, t) -> np.ndarray:
        """Time base xi(t) in [0, 1] (eq 7)."""
        return _xi_unit(self._u(t))

    def one_minus_xi(self, t) -> np.ndarray:
        """1 - xi(t), computed as xi(tau - t) to stay accurate near t = tau."""
        return _xi_unit(1.0 - self._u(t))

    def xi_dot(self, t) -> np.ndarray:
        """d xi / dt [1/s]: the bell-shaped speed profile of the TBG, peak 1.875/tau at tau/2."""
        u = self._u(t)
        return 30.0 * u * u * (1.0 - u) ** 2 / self.tau

    def gamma(self, t) -> np.ndarray:
        """Gamma(t) = xi_dot / (1 - xi) [1/s] (eq 7); ``inf`` at t >= tau (simple pole)."""
        u = self._u(t)
        v = 1.0 - u
        with np.errstate(divide="ignore", invalid="ignore"):
            # xi_dot/(1-xi) = 30 u^2 v^2 / (tau v^3 (10 - 15 v + 6 v^2)), simplified by v^2
            g = 30.0 * u * u / (self.tau * v * (10.0 + v * (-15.0 + 6.0 * v)))
        return np.where(v > 0.0, g, np.inf)

    def relaxation_time(self, t) -> np.ndarray:
        """s(t) = -ln(1 - xi(t)) = integral of Gamma (dimensionless); ``inf`` at t = tau."""
        with np.errstate(divide="ignore"):
            return -np.log(self.one_minus_xi(t))

    def time_of_relaxation(self, s) -> np.ndarray:
        """Inverse of :meth:`relaxation_time`: the time t [s] at which s(t) = ``s``."""
        s = np.asarray(s, dtype=float)
        target = np.exp(-np.clip(s, 0.0, None))  # = 1 - xi(t), decreasing in t
        # bisection on u (xi is monotone): 60 halvings reach double precision
        lo = np.zeros_like(target)
        hi = np.ones_like(target)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            above = _xi_unit(1.0 - mid) > target
            lo = np.where(above, mid, lo)
            hi = np.where(above, hi, mid)
        return 0.5 * (lo + hi) * self.tau

    def sample_times(self, period: float) -> np.ndarray:
        """Uniform times from 0 to tau inclusive with at most ``period`` [s] between samples."""
        if not math.isfinite(period) or period <= 0.0:
            raise InvalidInput(f"sample period: expected > 0 s, got {period}")
        n = max(2, int(math.ceil(self.tau / period - 1e-9)) + 1)
        return np.linspace(0.0, self.tau, n)
