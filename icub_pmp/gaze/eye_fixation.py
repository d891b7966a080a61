"""EyeFixation: the eye angles (tilt, version, vergence) that fixate a point, in closed form.

Geometry (iKin ``iCubEye`` v2.x, :mod:`icub_pmp.kinematics.eye_kinematics`): both eye centres
lie on the tilt axis (z of the DH frame 5, ``T_head_eyes``), at ``D = -+0.034 m``; each pan
axis is perpendicular to it, so for any pans the two optical axes stay in one plane through
the baseline, which the tilt rotates. Hence, with ``p5 = (x, y, z)`` the point in frame 5:

    tilt = atan2(-y, -x)                     (the plane that contains the point)
    pan_side = atan2(z - D_side, hypot(x, y))  (the direction to it within that plane)
    version = (pan_l + pan_r) / 2, vergence = pan_l - pan_r

exact for any point in front of the eyes. This is the geometric estimate iKinGazeCtrl makes for
its saccades (``EyePinvRefGen::run`` in ``src/modules/iKinGazeCtrl/src/solver.cpp``:
``ang[0] = -atan2(y, |z|)``, ``ang[1] = atan2(x, z)`` and the vergence ``L - R`` from the half
baseline), written in the DH frame where it needs no further iteration. The fixation point of
given eye angles is the midpoint of the common perpendicular of the two optical axes
(iKin ``CartesianHelper::computeFixationPointData``, ``src/libraries/iKin/src/iKinHlp.cpp``).

The head centre (iKin ``iCubHeadCenter``: the eye chain with the tilt link's ``D`` set to 0 and
the eyes at zero) is the eyes' midpoint with the optical frame of zero eye angles: the frame
the neck solver points at a target.
"""

from __future__ import annotations

import math

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.eye_kinematics import EYE_LIMITS, EYE_SIDES, EyeKinematics

__all__ = ["EyeFixation", "EYE_JOINTS"]

#: the three iCub eye joints, in the order of the angle vectors of this module.
EYE_JOINTS = ("eyes_tilt", "eyes_version", "eyes_vergence")


class EyeFixation:
    """Closed-form fixation of the iCub eyes (module doc).

    Args:
        eyes: the eye kinematics (the simulator's camera mounting).
        margin: joint targets stay this far inside the eye limits [rad].

    Angle vectors are ``(tilt, version, vergence)`` (3,) [rad]; head poses ``T_root_head``
    (4, 4) are the URDF ``head`` frame in root_link.
    """

    def __init__(self, eyes: EyeKinematics, margin: float = 0.0):
        self.eyes = eyes
        self.margin = float(margin)
        T5 = eyes.T_head_eyes
        self._T5_inv = np.linalg.inv(T5)
        #: eye centres on the tilt axis: z [m] in frame 5 (left -0.034, right +0.034)
        self._d = {s: float((self._T5_inv @ eyes.T_head_camera(s, 0.0, 0.0, 0.0))[2, 3])
                   for s in EYE_SIDES}
        zero = {s: eyes.T_head_camera(s, 0.0, 0.0, 0.0) for s in EYE_SIDES}
        T = zero["left"].copy()
        T[:3, 3] = 0.5 * (zero["left"][:3, 3] + zero["right"][:3, 3])
        #: head-centre frame (4, 4) in the URDF head frame (module doc)
        self.T_head_center = T
        self.T_head_center.setflags(write=False)
        #: (lower, upper) [rad] of tilt, version, vergence and each pan, without and with the
        #: margin
        self.limits = {m: {n: (EYE_LIMITS[n][0] + m, EYE_LIMITS[n][1] - m)
                           for n in (*EYE_JOINTS, "pan")} for m in (0.0, self.margin)}

    # ------------------------------------------------------------------ solve
    def angles(self, T_root_head: np.ndarray, p_root: np.ndarray) -> np.ndarray:
        """Exact fixation angles (3,) [rad] of the point ``p_root`` (3,) [m], unclipped."""
        p = np.asarray(p_root, dtype=float)
        T5 = np.asarray(T_root_head, dtype=float) @ self.eyes.T_head_eyes
        p5 = T5[:3, :3].T @ (p - T5[:3, 3])
        rho = math.hypot(p5[0], p5[1])
        tilt = math.atan2(-p5[1], -p5[0])
        pan_l = math.atan2(p5[2] - self._d["left"], rho)
        pan_r = math.atan2(p5[2] - self._d["right"], rho)
        version, vergence = EyeKinematics.version_vergence(pan_l, pan_r)
        return np.array([tilt, version, vergence])

    def clip(self, angles: np.ndarray, margin: bool = True
             ) -> tuple[np.ndarray, tuple[str, ...]]:
        """``angles`` (3,) clipped into the eye limits (shrunk by the margin unless ``margin``
        is False): tilt, vergence, then version so that both pans stay inside theirs.
        Returns the angles and the names of the joints clipped (by more than 1e-9 rad)."""
        a = np.asarray(angles, dtype=float)
        lim = self.limits[self.margin if margin else 0.0]
        tilt = min(max(a[0], lim["eyes_tilt"][0]), lim["eyes_tilt"][1])
        verg = min(max(a[2], lim["eyes_vergence"][0]), lim["eyes_vergence"][1])
        lo = max(lim["eyes_version"][0], lim["pan"][0] + 0.5 * verg)
        hi = min(lim["eyes_version"][1], lim["pan"][1] - 0.5 * verg)
        ver = min(max(a[1], lo), hi)
        out = np.array([tilt, ver, verg])
        clipped = tuple(n for n, x, y in zip(EYE_JOINTS, a, out) if abs(x - y) > 1e-9)
        return out, clipped

    # ------------------------------------------------------------------ evaluate
    def camera_poses(self, T_root_head: np.ndarray, angles: np.ndarray
                     ) -> dict[str, np.ndarray]:
        """REP-103 optical frames (4, 4) of both cameras in root_link, {side: T}."""
        tilt, ver, verg = (float(x) for x in angles)
        return {s: self.eyes.T_root_camera(T_root_head, s, tilt, ver, verg) for s in EYE_SIDES}

    def errors(self, T_root_head: np.ndarray, angles: np.ndarray, p_root: np.ndarray
               ) -> np.ndarray:
        """Angle [rad] between each optical axis and the direction to ``p_root``: (2,) left,
        right (pi for a point behind a camera's centre)."""
        p = np.asarray(p_root, dtype=float)
        out = np.empty(2)
        for k, T in enumerate(self.camera_poses(T_root_head, angles).values()):
            v = p - T[:3, 3]
            z = T[:3, 2]
            out[k] = math.atan2(float(np.linalg.norm(np.cross(z, v))), float(z @ v))
        return out

    def fixation_point(self, T_root_head: np.ndarray, angles: np.ndarray) -> np.ndarray | None:
        """Point (3,) [m] the eyes fixate: the midpoint of the common perpendicular of the two
        optical axes; None when they are parallel or meet behind the eyes."""
        poses = self.camera_poses(T_root_head, angles)
        oL, zL = poses["left"][:3, 3], poses["left"][:3, 2]
        oR, zR = poses["right"][:3, 3], poses["right"][:3, 2]
        b = float(zL @ zR)
        den = 1.0 - b * b
        if den < 1e-10:
            return None
        w = oL - oR
        d, e = float(zL @ w), float(zR @ w)
        tL = (b * e - d) / den
        tR = (e - b * d) / den
        if tL <= 0.0 or tR <= 0.0:
            return None
        return 0.5 * (oL + tL * zL + oR + tR * zR)

    def head_center(self, T_root_head: np.ndarray) -> np.ndarray:
        """Head-centre frame (4, 4) in root_link for a head pose."""
        T = np.asarray(T_root_head, dtype=float)
        if T.shape != (4, 4) or not np.all(np.isfinite(T)):
            raise InvalidInput(f"T_root_head: expected a finite (4, 4), got {T.shape}")
        return T @ self.T_head_center
