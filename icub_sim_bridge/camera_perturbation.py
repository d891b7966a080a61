"""CameraPerturbation: the eye cameras as really built, not as nominally calibrated.

The rendered cameras get a perturbed calibration while ``camera_info`` keeps the nominal one
(a method that trusts ``camera_info`` meets the calibration error a real robot has): focal
length scaled by ``1 + e`` (``e`` uniform in +-``camera_focal_error``), principal point shifted
by up to +-``camera_principal_error`` px per axis, and the camera rotated about a random axis
by an angle uniform in [0, ``camera_rotation_error_deg``]. Plus white pixel noise
(``camera_noise_std`` grey levels) on every image. One draw per camera, seeded.

MuJoCo realises a principal point through ``cam_sensorsize`` + ``cam_intrinsic`` (lengths;
here 1 px = 1 mm of sensor); a principal offset ``+p`` moves the image content by ``-p``
(measured), so a true principal point at ``c + d`` [px] is ``-d`` there.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import mujoco
import numpy as np

from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics

__all__ = ["CameraPerturbation", "add_image_noise"]

_PX = 1e-3  # sensor length of one pixel in MuJoCo's intrinsic units [m]


class CameraPerturbation(NamedTuple):
    """One camera's calibration error."""

    focal_scale: float  # [-]
    principal_shift: np.ndarray  # (2,) [px]: true (cx, cy) - nominal
    rotation_axis: np.ndarray  # (3,) unit, camera frame
    rotation_deg: float  # [deg]

    @classmethod
    def draw(cls, focal_error: float, principal_error: float, rotation_error_deg: float,
             rng: np.random.Generator) -> CameraPerturbation:
        """Draw the errors (module doc)."""
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        return cls(1.0 + rng.uniform(-1, 1) * focal_error,
                   rng.uniform(-1, 1, 2) * principal_error, axis,
                   float(rng.uniform(0, 1) * rotation_error_deg))

    def true_intrinsics(self, nominal: CameraIntrinsics) -> CameraIntrinsics:
        """The intrinsics the rendered images really have."""
        return CameraIntrinsics(nominal.width, nominal.height, nominal.fx * self.focal_scale,
                                nominal.fy * self.focal_scale,
                                nominal.cx + float(self.principal_shift[0]),
                                nominal.cy + float(self.principal_shift[1]))

    def apply(self, model: mujoco.MjModel, camera_id: int, nominal: CameraIntrinsics) -> None:
        """Write this error into ``model``'s camera ``camera_id`` (in place)."""
        true = self.true_intrinsics(nominal)
        model.cam_sensorsize[camera_id] = [nominal.width * _PX, nominal.height * _PX]
        model.cam_intrinsic[camera_id] = [true.fx * _PX, true.fy * _PX,
                                          -float(self.principal_shift[0]) * _PX,
                                          -float(self.principal_shift[1]) * _PX]
        dq = np.zeros(4)
        mujoco.mju_axisAngle2Quat(dq, self.rotation_axis, math.radians(self.rotation_deg))
        q = np.zeros(4)
        mujoco.mju_mulQuat(q, model.cam_quat[camera_id].copy(), dq)
        model.cam_quat[camera_id] = q


def add_image_noise(image: np.ndarray, std: float, rng: np.random.Generator) -> np.ndarray:
    """``image`` (h, w, 3) uint8 plus white noise of ``std`` grey levels (rounded, clipped,
    uint8). In float32 (a third of the float64 cost: two 320x240 images at 30 Hz run on the
    simulator's camera thread)."""
    noisy = rng.standard_normal(image.shape, dtype=np.float32)
    noisy *= np.float32(std)
    noisy += image
    np.rint(noisy, out=noisy)
    np.clip(noisy, 0, 255, out=noisy)
    return noisy.astype(np.uint8)
