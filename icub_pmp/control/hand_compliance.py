"""hand_compliance: the translational compliance of a hand held by joint springs.

A joint controller with stiffness ``K`` (position or impedance mode, ``tau = -K (q - q_d) +
g(q)``) whose hand presses on a rigid surface is in equilibrium when ``K (q_d - q) = J^T F``,
``F`` the force the hand exerts on the surface and ``J`` the hand's translational Jacobian
(3, n) over the sprung joints. For a set-point posture found by a Cartesian target (so that
``q_d - q`` has no component the surface cannot resist), the target lies ``C F`` beyond the
contact point, with the compliance ``C = J K^-1 J^T`` (3, 3) [m/N]: to press with ``F``, aim
at ``x_contact + C F``. No ROS.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.robot_model import IcubModel

__all__ = ["hand_compliance"]


def hand_compliance(model: IcubModel, q: np.ndarray, frame: str,
                    joint_stiffness: Mapping[str, float]) -> np.ndarray:
    """Compliance ``C = J K^-1 J^T`` (3, 3) [m/N] of ``frame``'s origin (root_link axes).

    Args:
        model: the robot's kinematics.
        q: (model.nq,) posture [rad] (the measured contact posture).
        frame: the hand frame, e.g. ``r_hand_dh_frame``.
        joint_stiffness: URDF joint name -> stiffness [N m/rad] (> 0) of every joint that
            yields under the load (the others are taken as rigid).

    Raises:
        InvalidInput: a non-finite or non-positive stiffness, or no joint given.
        UnknownName: a joint or frame the model does not have.
    """
    if not joint_stiffness:
        raise InvalidInput("hand_compliance: joint_stiffness names no joint")
    names = list(joint_stiffness)
    k = np.array([joint_stiffness[n] for n in names], dtype=float)
    if not np.all(np.isfinite(k)) or np.any(k <= 0.0):
        bad = {n: v for n, v in zip(names, k) if not (np.isfinite(v) and v > 0.0)}
        raise InvalidInput(f"hand_compliance: stiffness must be finite and > 0 [N m/rad], got "
                           f"{bad}")
    q = model.check_q(q)
    J = model.frame_jacobian(q, frame)[:3, model.indices(names)]
    return (J / k) @ J.T
