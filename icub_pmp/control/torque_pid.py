"""TorquePid: the joint torque loop of the iCub controller boards (eqs 4-5).

With the torque error ``e = tau_hat - tau_d`` (eq 4, ``tau_hat`` estimated from the FT sensors)
the boards compute ``u = k_p e + k_d e_dot + k_i int(e)`` (eq 5) and drive the motor with a
feed-forward of the desired torque. Here the actuator takes a torque, so the command is

    tau_cmd = k_ff tau_d - u

(per joint, vectorised; joints without a valid estimate get ``tau_d``). The integral is
clamped to +- ``integral_limit`` [N m] of output (anti-windup) and frozen while the command
saturates; ``e_dot`` is the backward difference of ``e`` through a first-order low-pass at
``derivative_cutoff_hz``.
"""

from __future__ import annotations

import math

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["TorquePid"]


class TorquePid:
    """Per-joint torque PID on ``n`` joints (gains dimensionless [N m / N m], ki [1/s],
    kd [s])."""

    def __init__(
        self,
        n: int,
        kp: float = 0.0,
        ki: float = 0.0,
        kd: float = 0.0,
        kff: float = 1.0,
        integral_limit: float = 1.0,
        derivative_cutoff_hz: float = 50.0,
    ):
        self.n = n
        self.set_gains(kp, ki, kd, kff, integral_limit, derivative_cutoff_hz)
        self.reset()

    def set_gains(
        self, kp: float, ki: float, kd: float, kff: float, integral_limit: float,
        derivative_cutoff_hz: float,
    ) -> None:
        """Change the gains (the integral state is kept, clamped to the new limit)."""
        vals = dict(kp=kp, ki=ki, kd=kd, kff=kff, integral_limit=integral_limit,
                    derivative_cutoff_hz=derivative_cutoff_hz)
        for k, v in vals.items():
            if not (math.isfinite(v) and v >= 0):
                raise InvalidInput(f"TorquePid.{k} must be a finite number >= 0, got {v}")
        self.kp, self.ki, self.kd, self.kff = float(kp), float(ki), float(kd), float(kff)
        self.integral_limit = float(integral_limit)
        self.derivative_cutoff_hz = float(derivative_cutoff_hz)
        if hasattr(self, "_i"):
            np.clip(self._i, -self.integral_limit, self.integral_limit, out=self._i)

    def reset(self) -> None:
        """Zero the integral and derivative states."""
        self._i = np.zeros(self.n)  # integral term of the output, k_i int(e) [N m]
        self._e_prev: np.ndarray | None = None
        self._de = np.zeros(self.n)

    @property
    def integral(self) -> np.ndarray:
        """The integral term k_i int(e) (n,) [N m] (a copy)."""
        return self._i.copy()

    def __call__(
        self,
        tau_d: np.ndarray,
        tau_hat: np.ndarray,
        dt: float,
        mask: np.ndarray,
        saturated: np.ndarray | None = None,
    ) -> np.ndarray:
        """Command (n,) [N m] from desired ``tau_d`` and estimated ``tau_hat`` torques (n,).

        ``dt`` [s] since the previous call; ``mask`` (n,) bool: joints with a valid estimate;
        ``saturated`` (n,) bool: joints whose previous command saturated (integral frozen).
        """
        e = np.where(mask, tau_hat - tau_d, 0.0)
        if dt > 0 and self._e_prev is not None:
            if self.kd > 0:
                alpha = 1.0 - math.exp(-2 * math.pi * self.derivative_cutoff_hz * dt)
                self._de += alpha * ((e - self._e_prev) / dt - self._de)
            if self.ki > 0:
                grow = self.ki * e * dt
                if saturated is not None:
                    grow = np.where(saturated, 0.0, grow)
                self._i += grow
                np.clip(self._i, -self.integral_limit, self.integral_limit, out=self._i)
        self._e_prev = e
        u = self.kp * e + self.kd * self._de + self._i
        return np.where(mask, self.kff * tau_d - u, tau_d)
