"""ViteFilter: the VITE (Vector-Integration-To-Endpoint) velocity dynamics per axis, as the
iCub's earlier multi-referential reaching used them (Hersch and Billard 2008, ref [14] of the
reaching paper; Metta et al. 2011, Sect. 4.1, Fig 9 and Table 2):

    v_dot = alpha (-v + beta (x_T - x)),    x_dot = v

so ``x_ddot + alpha x_dot + alpha beta x = alpha beta x_T``: a second-order system with
natural frequency sqrt(alpha beta) and damping alpha / (2 sqrt(alpha beta)). The paper's
settings are alpha = 0.008 and beta = 0.002 per millisecond (Hersch's controller runs on a
1 ms step): alpha = 8 1/s and beta = 2 1/s, i.e. critically damped with a natural frequency of
4 rad/s (90 % of a step after about 0.97 s). Same interface as
:class:`~icub_pmp.cartesian.min_jerk_filter.MinJerkFilter` (state ``x`` (2, n), ``reset``,
``step(error) -> velocity``), so it can replace the min-jerk filters of
:class:`~icub_pmp.cartesian.min_jerk_generator.MinJerkGenerator`.
"""

from __future__ import annotations

import math

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["ViteFilter", "VITE_ALPHA", "VITE_BETA"]

#: the paper's settings (0.008 and 0.002 per ms) [1/s]
VITE_ALPHA = 8.0
VITE_BETA = 2.0


class ViteFilter:
    """Vector of independent VITE velocity controllers (module doc).

    Args:
        n: number of axes.
        Ts: sample period [s].
        alpha: velocity relaxation rate [1/s].
        beta: error-to-velocity gain [1/s].

    State ``x`` (2, n): row 0 the velocity command v per axis, row 1 unused (zero; kept so a
    generator can store either filter's state the same way).
    """

    def __init__(self, n: int, Ts: float, alpha: float = VITE_ALPHA, beta: float = VITE_BETA):
        for name, v in (("Ts", Ts), ("alpha", alpha), ("beta", beta)):
            if not (math.isfinite(v) and v > 0):
                raise InvalidInput(f"{name}: expected a finite value > 0, got {v}")
        if alpha * Ts >= 1.0:
            raise InvalidInput(f"alpha * Ts = {alpha * Ts:g}: expected < 1 (stable Euler step)")
        self.n, self.Ts, self.alpha, self.beta = int(n), float(Ts), float(alpha), float(beta)
        self.x = np.zeros((2, self.n))

    def reset(self, velocity: np.ndarray | None = None) -> None:
        """Zero the state, or start from a velocity (n,)."""
        self.x = np.zeros((2, self.n))
        if velocity is not None:
            self.x[0] = np.asarray(velocity, dtype=float)

    def step(self, error: np.ndarray) -> np.ndarray:
        """Advance one period with the error x_T - x (n,); returns the velocity command (n,)."""
        e = np.asarray(error, dtype=float).reshape(self.n)
        u = self.x[0].copy()
        self.x[0] = u + self.Ts * self.alpha * (self.beta * e - u)
        return u
