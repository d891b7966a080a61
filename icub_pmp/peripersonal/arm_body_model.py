"""ArmBodyModel: where each arm's body is, for the imagined collision check.

Three descriptions of an arm, all posed by the body model the reaches are imagined on (a
:class:`~icub_pmp.pmp.JacobianProvider`: the URDF now, a learned body schema later):

- the distal joints (wrist and hand), the paper's collision test (Bhat and Mohan 2018,
  "Coupled interaction between internal models": "the 3D locations of the two distal joints
  (nearest to the end-effector) of both the robots are computed at multiple points along the
  two anticipated motion trajectories");
- the convex hulls of the links that collide in the physics (upper arm, elbow, forearm,
  wrist, hand) as surface samples (:class:`LinkHull`), fixed in the link frames, for the check
  of one arm against the other arm's body (the iCub's arms can hit each other);
- one to a few capsules per hull (:func:`fit_capsules`), a cheap conservative bound used to
  find the few link pairs and instants where the hulls need to be compared.

:meth:`ArmBodyModel.from_urdf` builds the hulls from the URDF's collision meshes (MuJoCo
collides the convex hulls of the same meshes). Positions are in the base frame (root_link)
[m]; ``q`` are full configurations (K, nq) in the provider's joint order.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.geometry import Capsule, LinkHull, arm_prefix, fit_capsules, urdf_link_hulls
from icub_pmp.kinematics.robot_spec import HANDS, RobotSpec
from icub_pmp.pmp.jacobian_provider import JacobianProvider

__all__ = ["ArmBodyModel", "arm_prefix", "DEFAULT_CAPSULE_LINKS", "DEFAULT_DISTAL_FRAMES"]

#: links with collision geometry in the simulator (icub_sim_bridge.model_builder), per arm
DEFAULT_CAPSULE_LINKS = ("upper_arm", "elbow_1", "forearm", "wrist_1", "hand")
#: the paper's distal joints: wrist and hand (frame names after the l_/r_ prefix)
DEFAULT_DISTAL_FRAMES = ("wrist_pitch", "hand_dh_frame")


class ArmBodyModel:
    """Distal points, link hulls and their capsules for both arms (module doc).

    Args:
        provider: the body model (forward kinematics with frame rotations).
        hulls: arm -> the hulls of its links (frames of the provider).
        distal_frames: arm -> frames whose origins are the distal joints (wrist, hand).
        max_pieces: capsules per hull at most (:func:`fit_capsules`).
    """

    def __init__(self, provider: JacobianProvider, hulls: Mapping[str, Sequence[LinkHull]],
                 distal_frames: Mapping[str, Sequence[str]], max_pieces: int = 4):
        self.provider = provider
        frames = set(provider.frame_names())
        self.hulls: dict[str, tuple[LinkHull, ...]] = {}
        self.capsules: dict[str, tuple[Capsule, ...]] = {}
        self.distal_frames: dict[str, tuple[str, ...]] = {}
        self._cap_link: dict[str, np.ndarray] = {}
        for arm in HANDS:
            if arm not in hulls or arm not in distal_frames:
                raise InvalidInput(f"ArmBodyModel: hulls and distal frames are needed for both "
                                   f"arms {HANDS}, got {sorted(hulls)} / {sorted(distal_frames)}")
            hs = tuple(hulls[arm])
            dist = tuple(distal_frames[arm])
            for f in [h.frame for h in hs] + list(dist):
                if f not in frames:
                    raise UnknownName("frame of the body model", f, frames)
            caps, owner = [], []
            for i, h in enumerate(hs):
                pieces = fit_capsules(h.frame, h.points, max_pieces)
                caps.extend(pieces)
                owner.extend([i] * len(pieces))
            self.hulls[arm] = hs
            self.capsules[arm] = tuple(caps)
            self.distal_frames[arm] = dist
            self._cap_link[arm] = np.array(owner)
        self._a = {a: np.array([c.a for c in self.capsules[a]]) for a in HANDS}
        self._b = {a: np.array([c.b for c in self.capsules[a]]) for a in HANDS}
        self._r = {a: np.array([c.radius for c in self.capsules[a]]) for a in HANDS}
        for d in (self._a, self._b, self._r, self._cap_link):
            for v in d.values():
                v.setflags(write=False)

    @classmethod
    def from_urdf(cls, provider: JacobianProvider, spec: RobotSpec | None = None,
                  links: Sequence[str] = DEFAULT_CAPSULE_LINKS,
                  distal: Sequence[str] = DEFAULT_DISTAL_FRAMES, spacing: float = 0.006
                  ) -> "ArmBodyModel":
        """Hulls of the URDF collision meshes of ``links`` (prefixed l_/r_), sampled every
        ``spacing`` [m], and the distal frames ``distal`` (prefixed), for ``provider``."""
        spec = spec or RobotSpec.load()
        hulls, dist = {}, {}
        for arm in HANDS:
            hulls[arm] = urdf_link_hulls(spec, arm, links, spacing)
            dist[arm] = tuple(arm_prefix(spec, arm) + f for f in distal)
        return cls(provider, hulls, dist)

    # ------------------------------------------------------------------ names
    def _arm(self, arm: str) -> str:
        if arm not in HANDS:
            raise UnknownName("arm", arm, HANDS)
        return arm

    def link_names(self, arm: str) -> tuple[str, ...]:
        """The frames of ``arm``'s hulls, in order."""
        return tuple(h.frame for h in self.hulls[self._arm(arm)])

    def capsule_names(self, arm: str) -> tuple[str, ...]:
        """The frame of each of ``arm``'s capsules, in order."""
        return tuple(c.frame for c in self.capsules[self._arm(arm)])

    def capsule_links(self, arm: str) -> np.ndarray:
        """Index (into :meth:`link_names`) of the hull each capsule bounds, (C,)."""
        return self._cap_link[self._arm(arm)]

    def radii(self, arm: str) -> np.ndarray:
        """Capsule radii (C,) [m] of ``arm``."""
        return self._r[self._arm(arm)]

    # ------------------------------------------------------------------ geometry
    def _q(self, q: np.ndarray) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.ndim == 1:
            q = q[None]
        if q.ndim != 2 or q.shape[1] != self.provider.nq or not np.all(np.isfinite(q)):
            raise InvalidInput(f"q: expected finite (K, {self.provider.nq}) [rad], got "
                               f"{q.shape}")
        return q

    def poses(self, arm: str, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rotations (K, L, 3, 3) and positions (K, L, 3) [m] of ``arm``'s links at q (K, nq)."""
        q = self._q(q)
        frames = self.link_names(arm)
        R = np.empty((len(q), len(frames), 3, 3))
        p = np.empty((len(q), len(frames), 3))
        for k, qk in enumerate(q):
            kin = self.provider.kinematics(qk, frames)
            R[k], p[k] = kin.rotations, kin.positions
        return R, p

    def capsules_at(self, arm: str, q: np.ndarray, poses: tuple[np.ndarray, np.ndarray] | None
                    = None) -> np.ndarray:
        """End points (K, C, 2, 3) [m, base frame] of ``arm``'s capsules at q (K, nq) (or at
        the link ``poses`` from :meth:`poses`)."""
        arm = self._arm(arm)
        R, p = poses if poses is not None else self.poses(arm, q)
        link = self._cap_link[arm]
        Rc, pc = R[:, link], p[:, link]
        out = np.empty(Rc.shape[:2] + (2, 3))
        out[:, :, 0] = np.einsum("kcij,cj->kci", Rc, self._a[arm]) + pc
        out[:, :, 1] = np.einsum("kcij,cj->kci", Rc, self._b[arm]) + pc
        return out

    def distal_points(self, arm: str, q: np.ndarray) -> np.ndarray:
        """Positions (K, D, 3) [m, base frame] of ``arm``'s distal joints at each q (K, nq)."""
        arm = self._arm(arm)
        q = self._q(q)
        frames = self.distal_frames[arm]
        return np.array([self.provider.positions(qk, frames) for qk in q])
