"""HeadCameras: poses of the two eye cameras in root_link from joint positions.

Torso and neck through the pinocchio model (:class:`~icub_pmp.kinematics.IcubModel`, URDF
``head`` frame), eyes through :class:`~icub_pmp.kinematics.eye_kinematics.EyeKinematics`
(iKin DH: tilt, version, vergence). The same chain the simulator mounts its cameras on.
"""

from __future__ import annotations

from typing import Mapping, NamedTuple

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.eye_kinematics import EyeKinematics
from icub_pmp.kinematics.robot_model import IcubModel

__all__ = ["HeadCameras", "CameraPoses", "HEAD_JOINTS"]

#: joints that move the cameras (torso and neck from the URDF, eyes from iKin).
HEAD_JOINTS = (
    "torso_pitch", "torso_roll", "torso_yaw", "neck_pitch", "neck_roll", "neck_yaw",
    "eyes_tilt", "eyes_version", "eyes_vergence",
)
_EYES = ("eyes_tilt", "eyes_version", "eyes_vergence")


class CameraPoses(NamedTuple):
    """(4, 4) REP-103 optical frames of the left and right eye cameras in root_link."""

    T_root_left: np.ndarray
    T_root_right: np.ndarray


class HeadCameras:
    """Camera poses from joint positions [rad]."""

    def __init__(self, model: IcubModel | None = None):
        self.model = model or IcubModel()
        self.eyes = EyeKinematics.from_model(self.model)
        self._q0 = np.zeros(self.model.nq)

    def poses(self, joints: Mapping[str, float]) -> CameraPoses:
        """Camera poses for ``joints`` (name -> position [rad]); torso and neck joints that
        are missing are taken as 0, the three eye joints are required.

        Raises:
            InvalidInput: an eye joint is missing or a value is not finite.
        """
        missing = [j for j in _EYES if j not in joints]
        if missing:
            raise InvalidInput(f"joints: missing eye joint(s) {missing}; have {sorted(joints)}")
        vals = np.array([float(joints.get(j, 0.0)) for j in HEAD_JOINTS])
        if not np.all(np.isfinite(vals)):
            raise InvalidInput(f"joints: non-finite head/eye position in {dict(joints)}")
        T_head = self.head_pose(joints)
        tilt, version, vergence = (float(joints[j]) for j in _EYES)
        return CameraPoses(
            self.eyes.T_root_camera(T_head, "left", tilt, version, vergence),
            self.eyes.T_root_camera(T_head, "right", tilt, version, vergence),
        )

    def head_pose(self, joints: Mapping[str, float]) -> np.ndarray:
        """T_root_head (4, 4): the URDF ``head`` frame for the torso and neck joints of
        ``joints`` (missing ones 0)."""
        q = self.model.q_from_dict({j: float(joints[j]) for j in HEAD_JOINTS[:6] if j in joints},
                                   self._q0)
        return self.model.frame_pose(q, "head").homogeneous
