"""BodyVolume: spheres fixed to an arm's links that cover its collision hulls, for obstacles.

The obstacle fields of Sect. 2.3 act on the extrinsic space of the end effector; the iCub's
hand frame (``r_hand_dh_frame``) sits in the palm, while its fingers and thumb reach up to
10 cm beyond it and the forearm trails behind (the convex hulls the simulator collides). A
plan that keeps only the hand frame clear lets the fingers touch what it avoids. A
BodyVolume covers those hulls with spheres, each fixed in its link frame: the repulsive
fields act on every sphere (grown by its radius) and the clearance is judged on them.

Built from the capsules that bound the links' collision hulls
(:func:`~icub_pmp.geometry.fit_capsules`, the same hulls the imagined collision
check uses): a capsule of radius ``r`` and length ``L`` becomes ``ceil(L / (spacing r)) + 1``
spheres evenly along its segment, whose radius is grown so that their union covers the
capsule (between two centres ``d`` apart the capsule's surface lies at most
``r - sqrt(r^2 - d^2 / 4)`` outside the spheres).
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.pmp.jacobian_provider import FrameKinematics, JacobianProvider

__all__ = ["BodySphere", "BodyVolume", "hull_distances"]


class BodySphere(NamedTuple):
    """A sphere fixed to ``frame``: centre (3,) [m] in that frame, ``radius`` [m]."""

    frame: str
    center: np.ndarray
    radius: float


class BodyVolume:
    """Spheres fixed to link frames (module doc).

    Args:
        spheres: the spheres; their frames must be frames of the body model that poses them.
    """

    def __init__(self, spheres: Sequence[BodySphere]):
        spheres = tuple(spheres)
        if not spheres:
            raise InvalidInput("BodyVolume: expected at least one sphere, got none")
        frames: list[str] = []
        owner = []
        for s in spheres:
            c = np.asarray(s.center, dtype=float)
            if c.shape != (3,) or not np.all(np.isfinite(c)):
                raise InvalidInput(f"BodyVolume: sphere centre in {s.frame}: expected 3 finite "
                                   f"numbers, got {s.center!r}")
            if not (math.isfinite(s.radius) and s.radius > 0):
                raise InvalidInput(f"BodyVolume: sphere radius in {s.frame}: expected a "
                                   f"finite value > 0 m, got {s.radius}")
            if s.frame not in frames:
                frames.append(s.frame)
            owner.append(frames.index(s.frame))
        #: the link frames the spheres are fixed to
        self.frames: tuple[str, ...] = tuple(frames)
        self.owner = np.array(owner, dtype=int)
        self.centers = np.array([s.center for s in spheres], dtype=float)
        self.radii = np.array([s.radius for s in spheres], dtype=float)
        for a in (self.owner, self.centers, self.radii):
            a.setflags(write=False)

    def __len__(self) -> int:
        return len(self.radii)

    @classmethod
    def from_capsules(cls, capsules: Sequence, spacing: float = 1.0) -> "BodyVolume":
        """Spheres covering ``capsules`` (each with ``frame``, ``a``, ``b`` (3,) [m] and
        ``radius`` [m]); neighbouring centres at most ``spacing`` radii apart (module doc)."""
        if not (math.isfinite(spacing) and spacing > 0):
            raise InvalidInput(f"spacing: expected a value > 0 (in capsule radii), got {spacing}")
        spheres = []
        for c in capsules:
            a, b, r = np.asarray(c.a, float), np.asarray(c.b, float), float(c.radius)
            length = float(np.linalg.norm(b - a))
            n = int(math.ceil(length / (spacing * r))) + 1 if length > 0 else 1
            d = length / (n - 1) if n > 1 else 0.0
            grown = r + r - math.sqrt(max(r * r - 0.25 * d * d, 0.0))
            for t in np.linspace(0.0, 1.0, n):
                spheres.append(BodySphere(c.frame, a + t * (b - a), grown))
        return cls(spheres)

    @classmethod
    def from_urdf(cls, provider: JacobianProvider, hand: str, links: Sequence[str],
                  spec=None, spacing: float = 1.0,  # noqa: ANN001 - RobotSpec
                  max_pieces: int = 4) -> "BodyVolume":
        """The spheres covering the URDF collision hulls of ``hand``'s arm ``links`` (names
        after the l_/r_ prefix, e.g. ``hand``, ``wrist_1``, ``forearm``), for ``provider``
        (the hulls' capsules as the imagined collision check fits them: at most
        ``max_pieces`` per hull)."""
        from icub_pmp.geometry import fit_capsules, urdf_link_hulls
        from icub_pmp.kinematics.robot_spec import HANDS, RobotSpec

        if not links:
            raise InvalidInput("links: expected at least one link name, got none")
        if hand not in HANDS:
            raise UnknownName("hand", hand, HANDS)
        hulls = urdf_link_hulls(spec or RobotSpec.load(), hand, links)
        frames = set(provider.frame_names())
        capsules = []
        for h in hulls:
            if h.frame not in frames:
                raise UnknownName("frame of the body model", h.frame, frames)
            capsules.extend(fit_capsules(h.frame, h.points, max_pieces))
        return cls.from_capsules(capsules, spacing)

    def positions(self, kin: FrameKinematics) -> np.ndarray:
        """Sphere centres (n, 3) [m] in the base frame, from the kinematics of
        :attr:`frames` (in that order)."""
        return (np.einsum("nij,nj->ni", kin.rotations[self.owner], self.centers)
                + kin.positions[self.owner])

    def jacobians(self, kin: FrameKinematics) -> np.ndarray:
        """Translational Jacobians (n, 3, nq) of the sphere centres: ``J_v - [R c]x J_w``."""
        arm = np.einsum("nij,nj->ni", kin.rotations[self.owner], self.centers)
        jac = kin.jacobians[self.owner]
        return jac[:, :3] - np.cross(arm[:, :, None], jac[:, 3:], axis=1)

    def torques(self, kin: FrameKinematics, forces: np.ndarray) -> np.ndarray:
        """Joint torques (nq,) of ``forces`` (n, 3) [N] acting on the sphere centres:
        ``sum_i J_i^T f_i`` with ``J_i = J_v - [R c_i]x J_w`` of the sphere's frame."""
        arm = np.einsum("nij,nj->ni", kin.rotations[self.owner], self.centers)
        jac = kin.jacobians[self.owner]  # (n, 6, nq)
        moment = np.cross(arm, forces)
        return (np.einsum("nkq,nk->q", jac[:, :3], forces)
                + np.einsum("nkq,nk->q", jac[:, 3:], moment))


def hull_distances(provider: JacobianProvider, hulls: Sequence, q_samples: np.ndarray,
                   obstacle) -> np.ndarray:  # noqa: ANN001 - any ObstacleField
    """Smallest distance [m] of the surface samples of ``hulls`` (each with ``frame`` and
    ``points`` (n, 3) [m] in that frame, e.g. :class:`~icub_pmp.geometry.LinkHull`: the
    convex hulls the physics collides) to ``obstacle``'s real surface, at each configuration
    of ``q_samples`` (K, nq) (K,): an independent judge of a plan's clearance."""
    frames = [h.frame for h in hulls]
    out = np.empty(len(q_samples))
    for k, q in enumerate(np.asarray(q_samples, dtype=float)):
        kin = provider.kinematics(q, frames)
        pts = np.vstack([h.points @ kin.rotations[i].T + kin.positions[i]
                         for i, h in enumerate(hulls)])
        out[k] = float(np.min(obstacle.surface_distance(pts)))
    return out
