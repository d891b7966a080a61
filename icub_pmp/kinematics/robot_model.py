"""IcubModel: pinocchio kinematics and dynamics of the iCub upper body on a fixed mainstay.

Built from the icub-models URDF named in ``config/robot.yaml``; every joint outside the
actuated upper body (legs) is locked at 0 with ``pinocchio.buildReducedModel``. All frames are
expressed in ``root_link`` (the URDF root, x backward, z up). Units: m, rad, N, N m.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Iterable, Sequence

import numpy as np
import pinocchio as pin

from icub_pmp.errors import InvalidInput, ModelError, UnknownName
from icub_pmp.kinematics.name_index import name_indices
from icub_pmp.kinematics.robot_spec import RobotSpec, urdf_path

__all__ = ["IcubModel"]


class IcubModel:
    """Reduced pinocchio model of the actuated upper body (torso, arms, neck: 20 DoF).

    ``q`` vectors follow :attr:`joint_names` (pinocchio order). Use :meth:`indices` to map
    URDF joint names to positions in ``q``.
    """

    def __init__(self, spec: RobotSpec | None = None, joints: Sequence[str] | None = None):
        self.spec = spec or RobotSpec.load()
        self.urdf = urdf_path(self.spec.model_name)
        try:
            full = pin.buildModelFromUrdf(str(self.urdf))
        except Exception as exc:  # pinocchio raises plain RuntimeError/ValueError
            raise ModelError(f"pinocchio cannot load {self.urdf}: {exc}") from exc
        keep = list(joints) if joints is not None else list(self.spec.upper_body_joints)
        valid = [n for n in full.names[1:]]
        for j in keep:
            if j not in valid:
                raise UnknownName("joint", j, valid)
        lock_ids = [full.getJointId(n) for n in valid if n not in keep]
        self.model: pin.Model = pin.buildReducedModel(full, lock_ids, pin.neutral(full))
        self.data: pin.Data = self.model.createData()
        self.joint_names: tuple[str, ...] = tuple(self.model.names[1:])
        self.nq: int = self.model.nq
        self._index = {n: i for i, n in enumerate(self.joint_names)}
        self.lower = np.array(self.model.lowerPositionLimit, dtype=float)
        self.upper = np.array(self.model.upperPositionLimit, dtype=float)
        self.lower.setflags(write=False)
        self.upper.setflags(write=False)
        self.torque_limits = np.array([self.spec.torque_limit(j) for j in self.joint_names])
        self.torque_limits.setflags(write=False)

    # ------------------------------------------------------------------ names and indices
    def indices(self, names: Iterable[str]) -> np.ndarray:
        """Positions in ``q`` of the URDF joints ``names`` (raises :class:`UnknownName`)."""
        return name_indices(names, self._index, self.joint_names)

    def frame_id(self, frame: str) -> int:
        """pinocchio id of ``frame`` (raises :class:`UnknownName` listing the frames)."""
        if not self.model.existFrame(frame):
            raise UnknownName("frame", frame, [f.name for f in self.model.frames])
        return self.model.getFrameId(frame)

    def q_from_dict(
        self, values: dict[str, float], default: np.ndarray | None = None
    ) -> np.ndarray:
        """Build ``q`` from {joint: value}; names outside the model are ignored (eyes)."""
        q = np.zeros(self.nq) if default is None else np.array(default, dtype=float)
        for n, v in values.items():
            i = self._index.get(n)
            if i is not None:
                q[i] = v
        return q

    def posture(self, name: str) -> np.ndarray:
        """Named posture of ``config/robot.yaml`` as ``q`` (nq,) [rad]."""
        return self.q_from_dict(self.spec.posture(name))

    def check_q(self, q: np.ndarray) -> np.ndarray:
        """Validate a configuration: shape (nq,), finite. Returns it as float array."""
        q = np.asarray(q, dtype=float)
        if q.shape != (self.nq,):
            raise InvalidInput(f"q: expected shape ({self.nq},), got {q.shape}")
        if not np.all(np.isfinite(q)):
            raise InvalidInput("q: contains NaN or infinite values")
        return q

    def clip(self, q: np.ndarray) -> np.ndarray:
        """``q`` clipped into the URDF joint limits."""
        return np.clip(q, self.lower, self.upper)

    def random_q(self, rng: np.random.Generator) -> np.ndarray:
        """A configuration drawn uniformly within the joint limits."""
        return rng.uniform(self.lower, self.upper)

    # ------------------------------------------------------------------ kinematics
    def forward(self, q: np.ndarray) -> None:
        """Forward kinematics of all joints and frames into :attr:`data`."""
        pin.forwardKinematics(self.model, self.data, q)
        pin.updateFramePlacements(self.model, self.data)

    def frame_pose(self, q: np.ndarray, frame: str | int) -> pin.SE3:
        """Pose of ``frame`` in root_link (``T_root_frame``)."""
        fid = frame if isinstance(frame, int) else self.frame_id(frame)
        self.forward(q)
        return self.data.oMf[fid].copy()

    def frame_position(self, q: np.ndarray, frame: str | int) -> np.ndarray:
        """Position of ``frame`` in root_link, (3,) [m]."""
        return self.frame_pose(q, frame).translation.copy()

    def frame_jacobian(self, q: np.ndarray, frame: str | int) -> np.ndarray:
        """Jacobian (6, nq) of ``frame``: linear then angular velocity, in root_link axes
        (pinocchio LOCAL_WORLD_ALIGNED), so ``x_dot = J q_dot`` for the frame origin."""
        fid = frame if isinstance(frame, int) else self.frame_id(frame)
        return pin.computeFrameJacobian(
            self.model, self.data, q, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )

    # ------------------------------------------------------------------ dynamics
    def gravity_torques(self, q: np.ndarray) -> np.ndarray:
        """Joint torques (nq,) [N m] that hold ``q`` against gravity (RNEA with zero v, a)."""
        return pin.computeGeneralizedGravity(self.model, self.data, q).copy()

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Recursive Newton-Euler: joint torques (nq,) [N m] for (q, v, a)."""
        return pin.rnea(self.model, self.data, q, v, a).copy()


@lru_cache(maxsize=4)
def _shared(model_name: str) -> IcubModel:  # pragma: no cover - convenience cache
    spec = RobotSpec.load()
    if spec.model_name != model_name:
        raise ModelError(f"robot.yaml names {spec.model_name}, asked for {model_name}")
    return IcubModel(spec)
