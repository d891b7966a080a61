"""The robot's own arms as segments, for telling the robot's motion from an object's."""

from __future__ import annotations

from typing import Mapping

import numpy as np

from icub_pmp.kinematics import IcubModel

__all__ = ["arm_segments"]


def arm_segments(model: IcubModel, joints: Mapping[str, float]) -> np.ndarray:
    """(4, 2, 3) elbow-wrist and wrist-hand segments of the left then the right arm in
    root_link [m] at the posture ``joints`` (name -> rad; missing joints 0, unknown names
    ignored): what :class:`~icub_pmp.vision.stereo_target.StereoTarget` takes as
    ``self_segments``."""
    q = model.q_from_dict({j: float(v) for j, v in joints.items() if j in model.joint_names},
                          np.zeros(model.nq))
    out = []
    for p in ("l", "r"):
        e, w, h = (model.frame_position(q, f"{p}_{f}") for f in
                   ("elbow_1", "wrist_1", "hand_dh_frame"))
        out += [(e, w), (w, h)]
    return np.array(out)
