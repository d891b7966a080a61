"""MinJerkLoop: the minimum-jerk velocity controller closed on an ideal plant, advanced exactly.

iKinGazeCtrl drives the neck and the eyes with the feedback minimum-jerk velocity controllers
of Pattacini et al. (2010) (``minJerkVelCtrlForIdealPlant``, iCub ctrlLib): per axis
``u = F(s) e`` with ``F(s) = -a / (s^2 - c s - b)``, ``a = -150.766/T^3``, ``b = -84.981/T^2``,
``c = -15.967/T`` (the coefficients of :class:`~icub_pmp.cartesian.MinJerkFilter`), and the
joint integrates ``u``. Closed on that ideal plant, the error ``e = r - y`` to a constant
reference follows the third-order system

    e' = -u,  u' = u_dot,  u_dot' = b u + c u_dot - a e

(90 % of a step at t = T, transient extinct after 1.5 T). This class advances it by its exact
transition matrix ``expm(A Ts)``: a sampled rollout then has the continuous response at every
sample, whatever T / Ts (a sample-delayed discrete loop overshoots by 0.7 % at T = 25 Ts, the
eyes' 0.25 s at the 10 ms period). A reference that moves (the eyes' fixation angles while the
neck turns) is followed exactly when its rate is fed forward, which leaves the error dynamics
unchanged.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm

from icub_pmp.cartesian.min_jerk_filter import min_jerk_system

__all__ = ["MinJerkLoop"]


class MinJerkLoop:
    """``n`` independent closed min-jerk loops (module doc).

    Args:
        n: number of axes.
        T: trajectory time [s] (>= 10 Ts; else :class:`~icub_pmp.errors.InvalidInput`).
        Ts: sample period [s].

    State ``x`` (2, n): per axis the velocity command u [unit/s] and its rate [unit/s^2]
    (the state of :class:`~icub_pmp.cartesian.MinJerkFilter`).
    """

    def __init__(self, n: int, T: float, Ts: float):
        A, B = min_jerk_system(T, Ts)  # validates T and Ts
        self.n, self.T, self.Ts = int(n), float(T), float(Ts)
        A_cl = np.zeros((3, 3))  # z = (e, u, u_dot): e' = -u, (u, u_dot)' = A (u, u_dot) + B e
        A_cl[0, 1] = -1.0
        A_cl[1:, 1:] = A
        A_cl[1:, :1] = B
        self._Phi = expm(A_cl * Ts)
        self.x = np.zeros((2, self.n))

    @property
    def velocity(self) -> np.ndarray:
        """The current velocity command u (n,)."""
        return self.x[0].copy()

    def step(self, error: np.ndarray) -> np.ndarray:
        """Advance one period from the error ``e = r - y`` (n,); returns the error after it
        (for a reference held constant, or moving with its rate fed forward)."""
        z = self._Phi @ np.vstack((np.asarray(error, dtype=float).reshape(1, self.n), self.x))
        self.x = z[1:]
        return z[0]
