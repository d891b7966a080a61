"""OrientationField: a rotational attractive field on the hand frame (eq 1 for orientation).

The extrinsic space of eq 1 may include the pose of the end effector. For orientation the
"force" is a torque on the hand frame, proportional to the rotation vector that takes the
current orientation R to the target R_T::

    M = k_rot * log(R_T R^T)        [N m], rotation vector in base-frame axes

mapped to joint torques by the angular rows of the Jacobian (``T = J_w^T M``, eq 2).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from icub_pmp.errors import InvalidInput

__all__ = ["OrientationField"]


class OrientationField:
    """Attractive field toward the orientation ``target`` (3x3 rotation, ``R_base_hand``)."""

    def __init__(self, target, stiffness: float = 10.0):
        r = np.array(target, dtype=float)
        if r.shape != (3, 3) or not np.all(np.isfinite(r)):
            raise InvalidInput(f"orientation target: expected a 3x3 rotation, got shape {r.shape}")
        if not np.allclose(r.T @ r, np.eye(3), atol=1e-6) or np.linalg.det(r) < 0:
            raise InvalidInput("orientation target: not a rotation matrix (R^T R != I or det < 0)")
        if not np.isfinite(stiffness) or stiffness <= 0:
            raise InvalidInput(f"rotational stiffness: expected > 0 N m/rad, got {stiffness}")
        self.target = r
        self.target.setflags(write=False)
        self.stiffness = float(stiffness)

    def error(self, rotation: np.ndarray) -> np.ndarray:
        """Rotation vector (3,) [rad] from ``rotation`` to the target, base-frame axes."""
        return pin.log3(self.target @ np.asarray(rotation, dtype=float).T)

    def torque(self, rotation: np.ndarray) -> np.ndarray:
        """M (3,) [N m] on the hand frame."""
        return self.stiffness * self.error(rotation)
