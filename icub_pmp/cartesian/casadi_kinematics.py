"""CasadiKinematics: hand forward kinematics as CasADi SX expressions (K_x, K_alpha of eq 11).

The PyPI ``pin`` wheel has no ``pinocchio.casadi``, so the expressions are generated here from
the very pinocchio model the rest of the project uses (the icub-models URDF, reduced to the
upper body): for every joint on the path root_link -> frame, the constant placement in its
parent (``model.jointPlacements``) and the revolute axis (angular part of the joint's motion
subspace), then the frame's placement in its parent joint. With pinocchio's convention
``T_root_i = T_root_parent * placement_i * Rot(axis_i, q_i)``.
"""

from __future__ import annotations

from typing import Sequence

import casadi as ca
import numpy as np
import pinocchio as pin

from icub_pmp.errors import InvalidInput, ModelError
from icub_pmp.kinematics.robot_model import IcubModel

__all__ = ["CasadiKinematics"]


class CasadiKinematics:
    """Position (3,) [m] and rotation (3, 3) of ``frame`` in root_link as functions of ``q``.

    Args:
        model: the pinocchio upper-body model.
        frame: end-effector frame name (e.g. ``r_hand_dh_frame``).
        joints: every joint on the path root_link -> frame, root first (the chain's
            ``fk_joints``); ``q`` of :attr:`function` follows this order.

    Attributes:
        q: the SX symbol (n,) [rad].
        position: SX (3,) position of the frame origin in root_link [m] (K_x).
        rotation: SX (3, 3) ``R_root_frame`` (K_alpha as a rotation matrix).
        function: ``ca.Function('fk', [q], [position, rotation])``.
    """

    def __init__(self, model: IcubModel, frame: str, joints: Sequence[str]):
        self.frame = frame
        self.joints = tuple(joints)
        pm = model.model
        fid = model.frame_id(frame)
        path = []
        j = pm.frames[fid].parentJoint
        while j > 0:
            path.append(j)
            j = pm.parents[j]
        path.reverse()
        names = tuple(pm.names[j] for j in path)
        if names != self.joints:
            raise ModelError(
                f"CasadiKinematics: joints {list(self.joints)} are not the path root_link -> "
                f"{frame}, which is {list(names)}"
            )
        n = len(path)
        self.q = ca.SX.sym("q", n)
        rot = ca.SX.eye(3)
        pos = ca.SX.zeros(3)
        for k, jid in enumerate(path):
            placement = pm.jointPlacements[jid]
            axis = _revolute_axis(pm, jid)
            pos = pos + rot @ ca.DM(placement.translation)
            rot = rot @ ca.DM(placement.rotation) @ _axis_rotation(axis, self.q[k])
        f_pl = pm.frames[fid].placement
        self.position = pos + rot @ ca.DM(f_pl.translation)
        self.rotation = rot @ ca.DM(f_pl.rotation)
        self.function = ca.Function(
            "fk", [self.q], [self.position, self.rotation], ["q"], ["position", "rotation"]
        )

    @property
    def n(self) -> int:
        """Number of joints of the chain."""
        return len(self.joints)

    def pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Numeric FK: position (3,) [m] and rotation (3, 3) of the frame for ``q`` (n,) [rad]."""
        q = np.asarray(q, dtype=float).reshape(-1)
        if q.shape != (self.n,) or not np.all(np.isfinite(q)):
            raise InvalidInput(f"q: expected {self.n} finite values, got shape {q.shape}")
        p, r = self.function(q)
        return np.array(p).reshape(3), np.array(r)


def _revolute_axis(pm: pin.Model, jid: int) -> np.ndarray:
    """Unit rotation axis (3,) of revolute joint ``jid`` in its own frame."""
    jm = pm.joints[jid]
    if jm.nq != 1 or jm.nv != 1:
        raise ModelError(f"joint {pm.names[jid]!r} ({jm.shortname()}) is not a 1-DoF joint")
    jd = jm.createData()
    jm.calc(jd, pin.neutral(pm))
    s = np.array(jd.S).reshape(6)
    if np.linalg.norm(s[:3]) > 1e-12:
        raise ModelError(f"joint {pm.names[jid]!r} ({jm.shortname()}) is not revolute")
    axis = s[3:]
    return axis / np.linalg.norm(axis)


def _axis_rotation(axis: np.ndarray, angle: ca.SX) -> ca.SX:
    """Rodrigues' rotation (3, 3) about the unit ``axis`` by ``angle`` [rad].

    Constant zero entries of the axis vanish from the SX graph, so aligned axes give the
    usual 4-term elementary rotations.
    """
    x, y, z = (float(v) for v in axis)
    k = ca.DM([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    k2 = k @ k
    return ca.DM.eye(3) + ca.sin(angle) * k + (1.0 - ca.cos(angle)) * k2
