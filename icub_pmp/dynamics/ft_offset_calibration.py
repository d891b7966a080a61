"""FtOffsetCalibration: the FT sensors' offsets from the last samples of a still posture.

As wholeBodyDynamics's ``calib`` does (icub-main, docs/references.md): with no contact, the
measured FT wrench minus the wrench the model predicts is the sensor's offset (plus the
model's error in that posture); its mean over N samples is subtracted from every later
measurement. Here the N samples are the last N the estimator processed (a ring buffer), so a
calibration request is answered at once, and it is refused with the reason when the robot
moved during them: a joint's range of positions over the window beyond
``motion_tolerance`` [rad] (wholeBodyDynamics calls a robot still below 0.7 deg/s; a
position spread also passes encoder noise and catches slow drifts), or fewer than N samples
so far.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from icub_pmp.errors import IcubPmpError

__all__ = ["FtOffsetCalibration", "FtOffsets", "CalibrationError"]


class CalibrationError(IcubPmpError):
    """A calibration could not be made (the robot moved, too few samples); nothing changed."""


class FtOffsets(NamedTuple):
    """A calibration: offsets (k, 6) [N, N m] per sensor, over ``samples`` samples whose
    largest joint-position spread was ``spread`` [rad]."""

    offsets: np.ndarray
    samples: int
    spread: float


class FtOffsetCalibration:
    """Ring buffer of (joint positions, FT residuals) and the calibration from it.

    Args:
        n_samples: N, the samples averaged.
        n_joints: length of the joint-position vectors.
        n_sensors: number of 6-axis sensors (rows of the residual).
        motion_tolerance: largest joint-position spread over the window [rad].
        joint_names: names for the messages (optional).
    """

    def __init__(self, n_samples: int, n_joints: int, n_sensors: int,
                 motion_tolerance: float, joint_names: tuple[str, ...] = ()):
        if n_samples < 1:
            raise CalibrationError(f"calibration needs n_samples >= 1, got {n_samples}")
        self.n_samples = int(n_samples)
        self.motion_tolerance = float(motion_tolerance)
        self.joint_names = tuple(joint_names)
        self._q = np.zeros((self.n_samples, n_joints))
        self._r = np.zeros((self.n_samples, n_sensors, 6))
        self._count = 0

    def clear(self) -> None:
        """Forget the buffered samples."""
        self._count = 0

    @property
    def full(self) -> bool:
        """Whether N samples are buffered."""
        return self._count >= self.n_samples

    def add(self, q: np.ndarray, residual: np.ndarray) -> None:
        """Buffer one sample: joint positions (n_joints,) [rad], residual = measured -
        predicted FT (n_sensors, 6) [N, N m]."""
        k = self._count % self.n_samples
        self._q[k] = q
        self._r[k] = residual
        self._count += 1

    def calibrate(self) -> FtOffsets:
        """The mean residual of the last N samples (raises :class:`CalibrationError` if the
        robot moved during them or fewer were processed)."""
        if not self.full:
            raise CalibrationError(
                f"FT calibration: only {self._count} of the {self.n_samples} samples needed "
                "since the estimator started (wait, keeping the robot still)")
        spread = self._q.max(axis=0) - self._q.min(axis=0)
        j = int(np.argmax(spread))
        if spread[j] > self.motion_tolerance:
            name = self.joint_names[j] if j < len(self.joint_names) else f"#{j}"
            raise CalibrationError(
                f"FT calibration refused: the robot moved during the last {self.n_samples} "
                f"samples (joint {name} by {np.degrees(spread[j]):.2f} deg, more than "
                f"{np.degrees(self.motion_tolerance):.2f} deg); offsets unchanged: hold the "
                "robot still, without contact, and calibrate again")
        return FtOffsets(self._r.mean(axis=0), self.n_samples, float(spread[j]))
