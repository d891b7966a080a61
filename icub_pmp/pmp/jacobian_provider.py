"""JacobianProvider: the body model a PMP network relaxes on (forward kinematics + Jacobians).

PMP needs only the forward map x = f(q) and its Jacobian J(q) (eqs 2 and 4 of Mohan et al.
2009): no inverse. This interface is what the planner asks of a body model, so the iCub URDF
through pinocchio (:class:`~icub_pmp.pmp.pinocchio_provider.PinocchioJacobianProvider`) and a
learned body schema (the neural PMP of the body-schema paper, whose Jacobian is read off a
trained network) are interchangeable.

Conventions: ``q`` is the full configuration (nq,) [rad] in :attr:`joint_names` order; frames
are named end effectors (e.g. ``r_hand_dh_frame``); positions are in the provider's base frame
(``root_link`` for the iCub) [m]; Jacobians are (6, nq): linear velocity [m/s] then angular
velocity [rad/s] of the frame origin, in base-frame axes.
"""

from __future__ import annotations

import abc
from typing import NamedTuple, Sequence

import numpy as np

from icub_pmp.errors import ModelError

__all__ = ["JacobianProvider", "FrameKinematics"]


class FrameKinematics(NamedTuple):
    """Kinematics of k frames at one configuration."""

    positions: np.ndarray  # (k, 3) [m] in the base frame
    rotations: np.ndarray  # (k, 3, 3) R_base_frame
    jacobians: np.ndarray  # (k, 6, nq): [linear; angular] in base-frame axes


class JacobianProvider(abc.ABC):
    """Forward kinematics and Jacobians of a body model (abstract)."""

    #: joint names, the order of ``q``
    joint_names: tuple[str, ...]
    #: joint limits (nq,) [rad]
    lower: np.ndarray
    upper: np.ndarray

    @property
    def nq(self) -> int:
        """Number of joints in ``q``."""
        return len(self.joint_names)

    @abc.abstractmethod
    def frame_names(self) -> tuple[str, ...]:
        """The frames this model can evaluate."""

    @abc.abstractmethod
    def kinematics(self, q: np.ndarray, frames: Sequence[str]) -> FrameKinematics:
        """Positions, orientations and Jacobians of ``frames`` at ``q`` (one model pass)."""

    def positions(self, q: np.ndarray, frames: Sequence[str]) -> np.ndarray:
        """Positions (k, 3) [m] of ``frames`` at ``q`` (default: from :meth:`kinematics`)."""
        return self.kinematics(q, frames).positions

    def ancestors(self, frame: str) -> tuple[str, ...]:
        """Joints whose motion moves ``frame`` (default: all joints, always safe)."""
        return self.joint_names

    def static_torques(
        self, q: np.ndarray, frames: Sequence[str], forces: np.ndarray, gravity: bool
    ) -> np.ndarray:
        """Joint torques (nq,) [N m] that hold ``q`` while each frame pushes on the world with
        the force ``forces[i]`` (3,) [N, base axes]: ``sum_i J_i^T f_i`` (+ gravity ``g(q)``).

        The default uses :meth:`kinematics` only and cannot add gravity (a learned body
        schema has no masses).
        """
        if gravity:
            raise ModelError(f"{type(self).__name__} has no dynamics: gravity torques unavailable")
        kin = self.kinematics(q, frames)
        return np.einsum("kiq,ki->q", kin.jacobians[:, :3, :], np.asarray(forces, dtype=float))

    def static_torque_jacobian(
        self,
        q: np.ndarray,
        frames: Sequence[str],
        forces: np.ndarray,
        gravity: bool,
        joints: Sequence[int] | np.ndarray | None = None,
    ) -> np.ndarray:
        """d(static_torques)/dq_j (nq, len(joints)) [N m/rad] for the joint indices ``joints``
        (default all); central finite differences of :meth:`static_torques`."""
        q = np.asarray(q, dtype=float)
        cols = range(self.nq) if joints is None else list(joints)
        out = np.empty((self.nq, len(cols)))
        eps = 1e-6
        for c, j in enumerate(cols):
            dq = np.zeros(self.nq)
            dq[j] = eps
            out[:, c] = (
                self.static_torques(q + dq, frames, forces, gravity)
                - self.static_torques(q - dq, frames, forces, gravity)
            ) / (2 * eps)
        return out
