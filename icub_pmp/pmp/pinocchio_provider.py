"""PinocchioJacobianProvider: the iCub URDF body model (pinocchio) behind the PMP interface.

One ``computeJointJacobians`` pass (forward kinematics + all joint Jacobians) per relaxation
step gives every hand's pose and Jacobian; frames are then read from that pass. Static torques
(for the torque-limit settling of Sect. 2.3) use pinocchio's ``computeStaticTorque``, their
derivative by central differences (pinocchio's ``computeStaticTorqueDerivatives`` holds the
external forces fixed in the joint frames, not in the world as a target force is).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import pinocchio as pin

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_model import IcubModel
from icub_pmp.pmp.jacobian_provider import FrameKinematics, JacobianProvider

__all__ = ["PinocchioJacobianProvider"]

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


class PinocchioJacobianProvider(JacobianProvider):
    """Kinematics of :class:`~icub_pmp.kinematics.IcubModel` (20-DoF upper body, root_link)."""

    def __init__(self, model: IcubModel | None = None):
        self.icub = model or IcubModel()
        self._model = self.icub.model
        self._data = self._model.createData()  # own data: thread-safe w.r.t. IcubModel users
        self.joint_names = self.icub.joint_names
        self.lower = self.icub.lower
        self.upper = self.icub.upper
        self._frames = tuple(f.name for f in self._model.frames)
        self._fid: dict[str, int] = {}
        self._ids_cache: dict[tuple[str, ...], tuple[int, ...]] = {}

    def frame_names(self) -> tuple[str, ...]:
        """Every frame of the pinocchio model."""
        return self._frames

    def frame_id(self, frame: str) -> int:
        """pinocchio id of ``frame`` (raises :class:`UnknownName`)."""
        fid = self._fid.get(frame)
        if fid is None:
            if not self._model.existFrame(frame):
                raise UnknownName("frame", frame, self._frames)
            fid = self._fid[frame] = self._model.getFrameId(frame)
        return fid

    def _check(self, q: np.ndarray) -> np.ndarray:
        if type(q) is not np.ndarray or q.dtype != np.float64:
            q = np.asarray(q, dtype=float)
        if q.shape != (self.nq,):
            raise InvalidInput(f"q: expected shape ({self.nq},), got {q.shape}")
        return q

    def _ids(self, frames: Sequence[str]) -> tuple[int, ...]:
        key = tuple(frames)
        ids = self._ids_cache.get(key)
        if ids is None:
            ids = self._ids_cache[key] = tuple(self.frame_id(f) for f in key)
        return ids

    def kinematics(self, q: np.ndarray, frames: Sequence[str]) -> FrameKinematics:
        """One pinocchio pass: positions (k,3), rotations (k,3,3), Jacobians (k,6,nq)."""
        q = self._check(q)
        ids = self._ids(frames)
        model, data = self._model, self._data
        pin.computeJointJacobians(model, data, q)
        h = np.array([pin.updateFramePlacement(model, data, i).homogeneous for i in ids])
        return FrameKinematics(
            positions=h[:, :3, 3],
            rotations=h[:, :3, :3],
            jacobians=np.array([pin.getFrameJacobian(model, data, i, _LWA) for i in ids]),
        )

    def positions(self, q: np.ndarray, frames: Sequence[str]) -> np.ndarray:
        """Frame positions only (forward kinematics without Jacobians), (k, 3) [m]."""
        q = self._check(q)
        ids = self._ids(frames)
        model, data = self._model, self._data
        pin.forwardKinematics(model, data, q)
        return np.array([pin.updateFramePlacement(model, data, i).translation for i in ids])

    def ancestors(self, frame: str) -> tuple[str, ...]:
        """Joints on the path from the root to ``frame``."""
        joint = self._model.frames[self.frame_id(frame)].parentJoint
        return tuple(self._model.names[j] for j in self._model.supports[joint] if j > 0)

    def _fext(self, frames: Sequence[str], forces: np.ndarray) -> pin.StdVec_Force:
        """Forces the world exerts on the robot (``-forces``) at the frame origins, expressed
        in the local frame of each frame's parent joint (pinocchio's ``fext`` convention)."""
        data = self._data
        fext = pin.StdVec_Force()
        for _ in range(self._model.njoints):
            fext.append(pin.Force.Zero())
        for name, f in zip(frames, np.asarray(forces, dtype=float)):
            fid = self.frame_id(name)
            joint = self._model.frames[fid].parentJoint
            p = pin.updateFramePlacement(self._model, data, fid).translation
            world = pin.Force(-f, np.cross(p, -f))  # about the world origin, world axes
            fext[joint] = fext[joint] + data.oMi[joint].actInv(world)
        return fext

    def _gravity_model(self, gravity: bool) -> pin.Model:
        if gravity:
            return self._model
        if not hasattr(self, "_model_no_g"):
            self._model_no_g = self._model.copy()
            self._model_no_g.gravity = pin.Motion.Zero()
            self._data_no_g = self._model_no_g.createData()
        return self._model_no_g

    def static_torques(
        self, q: np.ndarray, frames: Sequence[str], forces: np.ndarray, gravity: bool
    ) -> np.ndarray:
        """``g(q) + sum_i J_i^T f_i`` (nq,) [N m]: torques holding ``q`` while the frames push
        on the world with ``forces`` (k,3) [N] (gravity term only if ``gravity``)."""
        q = self._check(q)
        pin.forwardKinematics(self._model, self._data, q)
        fext = self._fext(frames, forces)
        model = self._gravity_model(gravity)
        data = self._data if gravity else self._data_no_g
        return pin.computeStaticTorque(model, data, q, fext).copy()
