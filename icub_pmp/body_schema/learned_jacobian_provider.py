"""LearnedJacobianProvider: PMP's body model from learned body networks (neural PMP).

The body-schema paper plans with PMP on the Jacobian read off the trained network ("Internal
Body Model", eqs 1-2) instead of an analytic model. This provider answers PMP's questions
(:class:`~icub_pmp.pmp.JacobianProvider`) from one :class:`BodyNetwork` per arm: the hand
position is the network's output, the hand's linear Jacobian is eq 2 scattered into the
columns of the network's input joints (7 arm joints, or torso + arm for a 10-input model);
every other column is zero, so joints a model did not learn do not move that hand.

A learned position model knows no orientation: frame rotations are the identity and the
angular rows of the Jacobians are zero (orientation goals need the analytic model). Joint
limits of the learned joints are the babbling ranges stored in the models; the other joints'
limits (not learned: a robot's joint ranges are known to it) come from ``joint_limits`` or,
by default, the URDF.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from icub_pmp.body_schema.body_network import BodyNetwork
from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_spec import RobotSpec
from icub_pmp.pmp.jacobian_provider import FrameKinematics, JacobianProvider

__all__ = ["LearnedJacobianProvider"]


class LearnedJacobianProvider(JacobianProvider):
    """Hand kinematics of learned body networks, one per arm (module doc).

    Args:
        models: the body networks (their ``frame`` names the hand frame each one answers).
        joint_names: the configuration's joints (default the spec's upper body, 20 DoF).
        joint_limits: {joint: (lower, upper)} [rad] for joints no model learned (default
            the URDF's).
        spec: robot facts (default ``config/robot.yaml``).
    """

    def __init__(self, models: Sequence[BodyNetwork], joint_names: Sequence[str] | None = None,
                 joint_limits: Mapping[str, tuple[float, float]] | None = None,
                 spec: RobotSpec | None = None):
        if not models:
            raise InvalidInput("learned provider: at least one body network is needed")
        spec = spec or RobotSpec.load()
        self.joint_names = tuple(joint_names or spec.upper_body_joints)
        index = {n: i for i, n in enumerate(self.joint_names)}
        self.models: dict[str, BodyNetwork] = {}
        self._cols: dict[str, np.ndarray] = {}
        for m in models:
            if m.frame in self.models:
                raise InvalidInput(f"learned provider: two models for frame {m.frame!r}")
            for j in m.joint_names:
                if j not in index:
                    raise UnknownName("joint of the configuration", j, self.joint_names)
            self.models[m.frame] = m
            self._cols[m.frame] = np.array([index[j] for j in m.joint_names], dtype=int)
        lower = np.full(len(self.joint_names), np.nan)
        upper = np.full(len(self.joint_names), np.nan)
        for m in models:
            cols = self._cols[m.frame]
            lower[cols], upper[cols] = m.lower, m.upper
        missing = [n for i, n in enumerate(self.joint_names) if np.isnan(lower[i])]
        if missing:
            limits = dict(joint_limits) if joint_limits is not None else self._urdf_limits()
            for n in missing:
                if n not in limits:
                    raise InvalidInput(f"learned provider: no joint limits for {n!r}")
                lower[index[n]], upper[index[n]] = limits[n]
        self.lower, self.upper = lower, upper
        self.lower.setflags(write=False)
        self.upper.setflags(write=False)

    def _urdf_limits(self) -> dict[str, tuple[float, float]]:
        from icub_pmp.kinematics.robot_model import IcubModel

        urdf = IcubModel()
        return {n: (float(lo), float(hi))
                for n, lo, hi in zip(urdf.joint_names, urdf.lower, urdf.upper)}

    @classmethod
    def from_files(cls, paths: Mapping[str, str | Path], **kwargs) -> "LearnedJacobianProvider":
        """Load {arm: model file} (each file must hold a model of that arm)."""
        return cls([BodyNetwork.load(p, arm=a) for a, p in paths.items()], **kwargs)

    def frame_names(self) -> tuple[str, ...]:
        """The hand frames the models answer."""
        return tuple(self.models)

    def _model(self, frame: str) -> BodyNetwork:
        m = self.models.get(frame)
        if m is None:
            raise UnknownName("frame of the learned body model", frame, self.models)
        return m

    def _check(self, q: np.ndarray) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape != (self.nq,):
            raise InvalidInput(f"q: expected shape ({self.nq},), got {q.shape}")
        return q

    def kinematics(self, q: np.ndarray, frames: Sequence[str]) -> FrameKinematics:
        """Learned positions (k, 3), identity rotations, Jacobians (k, 6, nq) with eq 2's
        linear rows in the model's joint columns."""
        q = self._check(q)
        k = len(frames)
        pos = np.empty((k, 3))
        jac = np.zeros((k, 6, self.nq))
        for i, f in enumerate(frames):
            m = self._model(f)
            cols = self._cols[f]
            pred = m.jacobian(q[cols][None])
            pos[i] = pred.positions[0]
            jac[i, :3, cols] = pred.jacobians[0].T
        return FrameKinematics(pos, np.broadcast_to(np.eye(3), (k, 3, 3)).copy(), jac)

    def positions(self, q: np.ndarray, frames: Sequence[str]) -> np.ndarray:
        """Learned hand positions (k, 3) [m] (no Jacobians)."""
        q = self._check(q)
        return np.array([self._model(f).position(q[self._cols[f]]) for f in frames])

    def ancestors(self, frame: str) -> tuple[str, ...]:
        """The joints the frame's model takes as inputs."""
        return self._model(frame).joint_names
