"""JointStateFilter: joint velocities and accelerations for the dynamics, from sampled joint
states.

How (the brief asks to say it): velocity = the measured joint velocity (the simulator reports
it; on the robot it is the differentiated encoder) through a 2nd-order Butterworth low-pass at
``velocity_cutoff_hz`` (0 = as measured), or, when no velocity is given, the backward
difference of the positions through the same filter. Acceleration = the backward difference of
the *filtered* velocity over the sample interval, through a 2nd-order Butterworth at
``acceleration_cutoff_hz``. wholeBodyDynamics uses adaptive-window polynomial fits
(icub-main wholeBodyDynamics observerThread.cpp); a Butterworth pair is cheaper at 1 kHz and
its delay is known:
about 0.225 / fc [s] per stage.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from icub_pmp.dynamics.butterworth_low_pass import ButterworthLowPass
from icub_pmp.errors import InvalidInput

__all__ = ["JointStateFilter", "FilteredState"]


class FilteredState(NamedTuple):
    """Filtered joint state: positions (n,) [rad], velocities (n,) [rad/s], accelerations (n,)
    [rad/s^2]."""

    q: np.ndarray
    v: np.ndarray
    a: np.ndarray


class JointStateFilter:
    """Velocity/acceleration estimator for ``n`` joints sampled at about ``rate_hz``."""

    def __init__(
        self, n: int, rate_hz: float, velocity_cutoff_hz: float, acceleration_cutoff_hz: float
    ):
        self.n = n
        self.rate_hz = rate_hz
        self._fv = ButterworthLowPass(n, velocity_cutoff_hz, rate_hz)
        self._fa = ButterworthLowPass(n, acceleration_cutoff_hz, rate_hz)
        self._t: float | None = None
        self._q = np.zeros(n)
        self._v = np.zeros(n)
        self._a = np.zeros(n)

    def reset(self) -> None:
        """Forget the history (next sample starts from rest)."""
        self._t = None
        self._fv.reset()
        self._fa.reset()

    def update(self, t: float, q: np.ndarray, v: np.ndarray | None = None) -> FilteredState:
        """Add a sample at time ``t`` [s]; returns the filtered state (read it, do not modify
        it).

        A sample not later than the previous one is ignored (the last state is returned).
        """
        q = np.asarray(q, dtype=float)
        if q.shape != (self.n,):
            raise InvalidInput(f"q: expected shape ({self.n},), got {q.shape}")
        if self._t is None:
            v0 = np.zeros(self.n) if v is None else np.asarray(v, dtype=float)
            self._v = self._fv(v0)
            self._a = self._fa(np.zeros(self.n))
            self._q, self._t = q.copy(), float(t)
            return FilteredState(self._q.copy(), self._v.copy(), self._a.copy())
        dt = float(t) - self._t
        if dt <= 0.0:
            return FilteredState(self._q.copy(), self._v.copy(), self._a.copy())
        inv_dt = 1.0 / dt
        if v is None:
            raw_v = q - self._q
            raw_v *= inv_dt
        else:
            raw_v = np.array(v, dtype=float)  # a copy: kept as the state
        v_f = self._fv(raw_v) if self._fv.enabled else raw_v
        dv = v_f - self._v
        dv *= inv_dt
        self._a = self._fa(dv)
        self._v = v_f
        self._q, self._t = q.copy(), float(t)
        return FilteredState(self._q, v_f, self._a)
