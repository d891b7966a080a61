"""Sensor imperfections of the real iCub: FT noise/offset/drift/bandwidth, encoders, IMU.

Plain numpy, seeded (:class:`numpy.random.Generator`); figures in
:class:`~icub_sim_bridge.realism_config.RealismSettings` (sources in that module's doc).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from icub_sim_bridge.realism_config import RealismSettings

__all__ = ["FtSensorModel", "EncoderModel", "ImuModel", "ImuErrors"]


class FtSensorModel:
    """``n`` six-axis FT sensors as the STRAIN boards measure them.

    measured = low_pass(true) + offset + drift(t) + white noise, per axis (force rows
    ``[:3]`` [N], torque rows ``[3:]`` [N m]):

    - ``offset`` (n, 6): drawn once, uniform in +-``ft_force_offset`` / ``ft_torque_offset``;
    - ``drift(t) = amplitude (1 - exp(-t / ft_drift_time_constant))``, ``amplitude`` (n, 6)
      drawn once, uniform in +-``ft_force_drift`` / ``ft_torque_drift`` (a warm-up);
    - ``low_pass``: first-order at ``ft_bandwidth_hz`` (exact discretisation at ``dt``);
    - noise: N(0, ``ft_force_noise_std`` / ``ft_torque_noise_std``), new every sample.

    The noise is added after the low-pass, so its standard deviation is the configured one.
    """

    def __init__(self, n: int, settings: RealismSettings, rng: np.random.Generator,
                 dt: float):
        s = settings
        half = lambda f, t: np.tile(np.r_[np.full(3, f), np.full(3, t)], (n, 1))  # noqa: E731
        self.noise_std = half(s.ft_force_noise_std, s.ft_torque_noise_std)[0]
        self.offset = rng.uniform(-1.0, 1.0, (n, 6)) * half(s.ft_force_offset,
                                                            s.ft_torque_offset)
        self.drift_amplitude = rng.uniform(-1.0, 1.0, (n, 6)) * half(s.ft_force_drift,
                                                                     s.ft_torque_drift)
        self.drift_time_constant = s.ft_drift_time_constant
        self.alpha = (1.0 - math.exp(-2.0 * math.pi * s.ft_bandwidth_hz * dt)
                      if s.ft_bandwidth_hz > 0 else 1.0)
        self._rng = rng
        self._filtered: np.ndarray | None = None
        for a in (self.offset, self.drift_amplitude, self.noise_std):
            a.setflags(write=False)

    def bias(self, t: float) -> np.ndarray:
        """Offset + drift at time ``t`` [s], (n, 6)."""
        return self.offset + self.drift_amplitude * (1.0 - math.exp(-t / self.drift_time_constant))

    def measure(self, t: float, true: np.ndarray) -> np.ndarray:
        """One sample at ``t`` [s] of the true wrenches ``true`` (n, 6) -> measured (n, 6)."""
        if self._filtered is None or self.alpha >= 1.0:
            self._filtered = np.array(true, dtype=float)
        else:
            self._filtered += self.alpha * (true - self._filtered)
        noise = self._rng.standard_normal(self._filtered.shape) * self.noise_std
        return self._filtered + self.bias(t) + noise

    def reset_filter(self) -> None:
        """Forget the low-pass state (the next sample starts it afresh)."""
        self._filtered = None


class EncoderModel:
    """Joint encoders: positions quantised to ``encoder_resolution`` [rad], velocities with
    white noise ``velocity_noise_std`` [rad/s] (the firmware differentiates positions)."""

    def __init__(self, settings: RealismSettings, rng: np.random.Generator):
        self.resolution = settings.encoder_resolution
        self.velocity_noise_std = settings.velocity_noise_std
        self._rng = rng

    def position(self, q: np.ndarray) -> np.ndarray:
        """Quantised positions (same shape) [rad]."""
        if self.resolution <= 0.0:
            return q
        return np.round(q / self.resolution) * self.resolution

    def velocity(self, v: np.ndarray) -> np.ndarray:
        """Noisy velocities (same shape) [rad/s]."""
        if self.velocity_noise_std <= 0.0:
            return v
        return v + self._rng.standard_normal(v.shape) * self.velocity_noise_std


class ImuErrors(NamedTuple):
    """Constant biases of the IMU drawn at start-up, (3,) each."""

    acc_bias: np.ndarray  # [m/s^2]
    gyro_bias: np.ndarray  # [rad/s]


class ImuModel:
    """Head IMU: a constant bias per axis (drawn once, uniform in +-``imu_*_bias``) plus white
    noise (``imu_*_noise_std``) on the accelerometer and the gyro; orientation as given."""

    def __init__(self, settings: RealismSettings, rng: np.random.Generator):
        s = settings
        self.errors = ImuErrors(rng.uniform(-1.0, 1.0, 3) * s.imu_acc_bias,
                                rng.uniform(-1.0, 1.0, 3) * s.imu_gyro_bias)
        self.acc_noise_std = s.imu_acc_noise_std
        self.gyro_noise_std = s.imu_gyro_noise_std
        self._rng = rng

    def accelerometer(self, acc: np.ndarray) -> np.ndarray:
        """Measured proper acceleration (3,) [m/s^2]."""
        return acc + self.errors.acc_bias + self._rng.standard_normal(3) * self.acc_noise_std

    def gyro(self, omega: np.ndarray) -> np.ndarray:
        """Measured angular velocity (3,) [rad/s]."""
        return omega + self.errors.gyro_bias + self._rng.standard_normal(3) * self.gyro_noise_std
