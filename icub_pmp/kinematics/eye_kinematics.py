"""EyeKinematics: the iCub eyes (tilt, version, vergence) and their cameras, pure numpy.

The icub-models URDFs have no eyes. Their geometry comes from the iKin ``iCubEye`` DH table
for iCub v2.x (icub-main ``iKinFwd.cpp``, ``iCubEye``): links 0-5 are
torso and neck, link 6 is the eye tilt ``(A=0, D=+-0.034 [right +, left -], alpha=-pi/2,
offset=0)`` and link 7 the eye pan ``(0, 0, pi/2, -pi/2)``. The two eyes share the tilt axis
and are 0.068 m apart (the stereo baseline).

The torso and neck come from the URDF (so the head pose ``T_root_head`` is pinocchio's, the
same kinematics as everything else); only the part from the head on is DH. The fixed transform
``T_head_eyes`` from the URDF ``head`` frame to the DH frame 5 (the tilt axis) is taken at the
zero configuration: ``T_head_eyes = inv(T_root_head(0)) @ T_root_dh5(0)``. Away from zero the
iKin v2.x DH neck and the v2.7 URDF neck differ by about 1-2 mm; the simulator mounts its eyes
with exactly this ``T_head_eyes``, so ``T_root_camera`` here is the simulator's camera pose.

The DH end frame is a REP-103 optical frame: +z along the optical axis, +x to the image right
(the robot's right, +y of root_link at zero), +y down. Positive tilt looks up, positive pan
turns to the robot's right. iCub's head joints 3-5 couple the pans (iKin gaze convention):
``pan_left = version + vergence / 2``, ``pan_right = version - vergence / 2``.

Main API::

    eyes = EyeKinematics.from_model(icub_model)         # or EyeKinematics(T_root_head_zero)
    T_root_cam = eyes.T_root_camera(T_root_head, "left", tilt, version, vergence)
    uv = project_point(T_root_cam, p_root, camera)      # pixel (u, v), CameraIntrinsics
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName

if TYPE_CHECKING:  # pragma: no cover
    from icub_pmp.kinematics.robot_model import IcubModel

__all__ = [
    "EyeKinematics",
    "CameraIntrinsics",
    "EyeAngles",
    "dh_transform",
    "project_point",
    "EYE_SIDES",
    "EYE_BASELINE",
    "EYE_LIMITS",
]

EYE_SIDES = ("left", "right")
#: distance between the eye centres [m] (2 x |D| of DH link 6).
EYE_BASELINE = 0.068
#: iKin H0 of iCub v2.x: root_link -> DH frame of link 0.
_H0 = np.array([[0.0, -1.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [1.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 1.0]])
_P = math.pi / 2
#: iCubEye v2.x links 0..5 (A [m], D [m], alpha [rad], offset [rad]): torso pitch/roll/yaw,
#: neck pitch/roll/yaw (only used at zero to locate the eyes on the head).
_DH_TORSO_NECK = (
    (0.032, 0.0, _P, 0.0),
    (0.0, -0.0055, _P, -_P),
    (0.0, -0.2233, -_P, -_P),
    (0.0095, 0.0, _P, _P),
    (0.0, 0.0, -_P, -_P),
    (-0.0509, 0.08205, -_P, _P),
)
#: link 6 (tilt) D per side [m] and link 7 (pan) parameters.
_DH_TILT_D = {"left": -0.034, "right": 0.034}
_DH_TILT = (0.0, -_P, 0.0)  # A, alpha, offset
_DH_PAN = (0.0, 0.0, _P, -_P)  # A, D, alpha, offset
#: joint limits [rad] (iKin iCubEye v2.x table: tilt -35..15 deg, pan -50..50 deg); version
#: keeps both pans inside +-50 deg at zero vergence; vergence 0..50 deg (chosen: converging
#: only, down to a fixation distance of about 0.08 m).
EYE_LIMITS = {
    "eyes_tilt": (math.radians(-35.0), math.radians(15.0)),
    "eyes_version": (math.radians(-50.0), math.radians(50.0)),
    "eyes_vergence": (0.0, math.radians(50.0)),
    "pan": (math.radians(-50.0), math.radians(50.0)),
}


def dh_transform(a: float, d: float, alpha: float, theta: float) -> np.ndarray:
    """Standard DH link transform (4, 4): ``Rz(theta) Tz(d) Tx(a) Rx(alpha)`` [m, rad]."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


class EyeAngles(NamedTuple):
    """Per-eye angles [rad]: the shared tilt and the two pans."""

    tilt: float
    pan_left: float
    pan_right: float


@dataclasses.dataclass(frozen=True)
class CameraIntrinsics:
    """Pinhole intrinsics [px] of a ``width`` x ``height`` image (iCub simulator defaults:
    320x240, 50 deg horizontal field of view, icub-models iCubGazeboV2_5_visuomanip)."""

    width: int = 320
    height: int = 240
    fx: float = 343.12
    fy: float = 343.12
    cx: float = 160.0
    cy: float = 120.0

    @property
    def K(self) -> np.ndarray:
        """Camera matrix (3, 3)."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def fovy_deg(self) -> float:
        """Vertical field of view [deg] (what MuJoCo's ``fovy`` takes)."""
        return math.degrees(2.0 * math.atan(self.height / 2.0 / self.fy))


def project_point(T_root_camera: np.ndarray, p_root: np.ndarray,
                  camera: CameraIntrinsics) -> np.ndarray:
    """Pixel ``(u, v)`` (2,) of the point ``p_root`` (3,) [m] seen from an optical frame.

    Raises :class:`InvalidInput` when the point is behind the camera (z <= 0).
    """
    p = np.asarray(p_root, dtype=float)
    R, t = T_root_camera[:3, :3], T_root_camera[:3, 3]
    pc = R.T @ (p - t)
    if pc[2] <= 0.0:
        raise InvalidInput(f"p_root {p.tolist()} is behind the camera (z = {pc[2]:.3f} m)")
    return np.array([camera.fx * pc[0] / pc[2] + camera.cx, camera.fy * pc[1] / pc[2] + camera.cy])


class EyeKinematics:
    """Camera poses of the iCub eyes from the head pose and the eye joints (module doc)."""

    def __init__(self, T_root_head_zero: np.ndarray):
        """``T_root_head_zero`` (4, 4): the URDF ``head`` frame at the zero configuration."""
        T = np.asarray(T_root_head_zero, dtype=float)
        if T.shape != (4, 4) or not np.all(np.isfinite(T)):
            raise InvalidInput(f"T_root_head_zero: expected a finite (4, 4), got {T.shape}")
        H = _H0.copy()
        for a, d, alpha, offset in _DH_TORSO_NECK:
            H = H @ dh_transform(a, d, alpha, offset)
        T_head_eyes = np.linalg.inv(T) @ H
        T_head_eyes[:3, :3] = _orthonormalize(T_head_eyes[:3, :3])
        self.T_head_eyes = T_head_eyes
        self.T_head_eyes.setflags(write=False)

    @classmethod
    def from_model(cls, model: "IcubModel") -> "EyeKinematics":
        """Locate the eyes on the URDF head of ``model`` (an :class:`IcubModel`)."""
        return cls(model.frame_pose(np.zeros(model.nq), "head").homogeneous)

    # ------------------------------------------------------------------ joint coupling
    @staticmethod
    def pans(version: float, vergence: float) -> tuple[float, float]:
        """``(pan_left, pan_right)`` [rad] of ``version`` and ``vergence`` [rad]."""
        return version + 0.5 * vergence, version - 0.5 * vergence

    @staticmethod
    def version_vergence(pan_left: float, pan_right: float) -> tuple[float, float]:
        """``(version, vergence)`` [rad] of the two pans [rad] (inverse of :meth:`pans`)."""
        return 0.5 * (pan_left + pan_right), pan_left - pan_right

    # ------------------------------------------------------------------ fixed geometry
    @staticmethod
    def T_eyes_eye(side: str) -> np.ndarray:
        """Pose (4, 4) of ``side``'s eye centre (pan axis = its z) in the tilt frame at zero
        tilt: DH link 6 at theta = 0."""
        if side not in _DH_TILT_D:
            raise UnknownName("eye side", side, EYE_SIDES)
        a, alpha, offset = _DH_TILT
        return dh_transform(a, _DH_TILT_D[side], alpha, offset)

    @staticmethod
    def T_eye_camera(pan: float) -> np.ndarray:
        """Optical frame (4, 4) in the eye frame for a pan angle [rad]: DH link 7."""
        a, d, alpha, offset = _DH_PAN
        return dh_transform(a, d, alpha, pan + offset)

    # ------------------------------------------------------------------ full chain
    def T_head_camera(self, side: str, tilt: float, version: float, vergence: float
                      ) -> np.ndarray:
        """Optical frame (4, 4) of ``side``'s camera in the URDF ``head`` frame."""
        if side not in EYE_SIDES:
            raise UnknownName("eye side", side, EYE_SIDES)
        vals = np.array([tilt, version, vergence], dtype=float)
        if not np.all(np.isfinite(vals)):
            raise InvalidInput(f"eye angles must be finite, got {vals.tolist()}")
        pl, pr = self.pans(version, vergence)
        pan = pl if side == "left" else pr
        a, alpha, offset = _DH_TILT
        T6 = dh_transform(a, _DH_TILT_D[side], alpha, tilt + offset)
        return self.T_head_eyes @ T6 @ self.T_eye_camera(pan)

    def T_root_camera(self, T_root_head: np.ndarray, side: str, tilt: float, version: float,
                      vergence: float) -> np.ndarray:
        """Optical frame (4, 4) of ``side``'s camera in root_link, given the head pose
        ``T_root_head`` (4, 4) (e.g. ``IcubModel.frame_pose(q, 'head').homogeneous``)."""
        return np.asarray(T_root_head, dtype=float) @ self.T_head_camera(
            side, tilt, version, vergence)


def _orthonormalize(R: np.ndarray) -> np.ndarray:
    """Nearest rotation matrix (SVD) to remove round-off."""
    u, _, vt = np.linalg.svd(R)
    return u @ vt
