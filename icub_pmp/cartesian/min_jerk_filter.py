"""MinJerkFilter: the feedback minimum-jerk velocity controller of Pattacini et al. (2010).

Per axis, the controller maps the position error e = x_d - x_fb to a velocity command u with
the LTI filter ``F(s) = -a / (s^2 - c s - b)``, ``a = -150.766/T^3``, ``b = -84.981/T^2``,
``c = -15.967/T`` (icub-main ctrlLib minJerkCtrl.cpp). Closed on an ideal plant 1/s
it gives the third-order approximation of a minimum-jerk point-to-point motion of duration T:
90 % of a step at t = T, transient extinct for t >= 1.5 T. Because it acts on the *measured*
error, a new target can be given at any time and the motion joins it smoothly (velocity and
acceleration stay continuous). Discretised exactly with the error held over each period ``Ts``
(zero-order hold; iKin uses Tustin's method, which differs by O(Ts^2)), so the state keeps its
physical meaning.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import cont2discrete

from icub_pmp.errors import InvalidInput

__all__ = ["MinJerkFilter", "MIN_JERK_COEFFS", "min_jerk_system"]

MIN_JERK_COEFFS = (150.766, 84.981, 15.967)  # -a T^3, -b T^2, -c T


def min_jerk_system(T: float, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    """Continuous state space ``(A (2, 2), B (2, 1))`` of ``F(s)`` for the trajectory time
    ``T`` [s]: state (u, u_dot), input the error e, ``x' = A x + B e``. Raises
    :class:`InvalidInput` unless ``Ts`` > 0 [s] and ``T`` >= 10 Ts (iKin's lower bound)."""
    if not (Ts > 0 and np.isfinite(Ts)):
        raise InvalidInput(f"Ts: expected a period > 0 [s], got {Ts}")
    if not (np.isfinite(T) and T >= 10 * Ts):
        raise InvalidInput(f"T: expected a trajectory time >= 10 Ts = {10 * Ts} s, got {T}")
    ka, kb, kc = MIN_JERK_COEFFS
    a, b, c = -ka / T**3, -kb / T**2, -kc / T
    return np.array([[0.0, 1.0], [b, c]]), np.array([[0.0], [-a]])


class MinJerkFilter:
    """Vector of independent min-jerk velocity controllers (one per axis).

    Args:
        n: number of axes.
        T: trajectory time [s] (>= 10 Ts, as iKin's lower bound).
        Ts: sample period [s].

    State ``x`` (2, n): per axis the velocity command u [unit/s] and its rate [unit/s^2].
    """

    def __init__(self, n: int, T: float, Ts: float):
        A, B = min_jerk_system(T, Ts)
        self.n, self.T, self.Ts = int(n), float(T), float(Ts)
        C = np.array([[1.0, 0.0]])
        Ad, Bd, _, _, _ = cont2discrete((A, B, C, np.zeros((1, 1))), Ts, method="zoh")
        self._Ad, self._Bd = np.asarray(Ad), np.asarray(Bd).reshape(2, 1)
        self.x = np.zeros((2, self.n))

    def reset(self, velocity: np.ndarray | None = None) -> None:
        """Zero the state, or start from a velocity command (n,) with zero derivative."""
        self.x = np.zeros((2, self.n))
        if velocity is not None:
            self.x[0] = np.asarray(velocity, dtype=float)

    def step(self, error: np.ndarray) -> np.ndarray:
        """Advance one period with the error (n,) and return the velocity command (n,)."""
        e = np.asarray(error, dtype=float).reshape(1, self.n)
        u = self.x[0].copy()
        self.x = self._Ad @ self.x + self._Bd @ e
        return u
