"""ArmBodyModel: where each arm's body is, for the imagined collision check.

Two kinds of points, both from the body model the reaches are imagined on
(a :class:`~icub_pmp.pmp.JacobianProvider`: the URDF now, a learned body schema later):

- the distal joints (wrist and hand) of each arm, the paper's collision test (Bhat and Mohan
  2018, "Coupled interaction between internal models": "the 3D locations of the two distal
  joints (nearest to the end-effector) of both the robots are computed at multiple points
  along the two anticipated motion trajectories");
- capsules around the arm links that collide in the physics (upper arm, elbow, forearm,
  wrist, hand), fixed in the link frames (:class:`Capsule`), for the check of one arm against
  the other arm's body. :meth:`ArmBodyModel.from_urdf` covers the convex hull of each URDF
  collision mesh with one or a few capsules (:func:`fit_capsules`; MuJoCo collides those
  hulls).

Frames are base-frame (root_link) positions [m]; ``q`` are full configurations (K, nq) in the
provider's joint order.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Mapping, Sequence

import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS, RobotSpec, urdf_path
from icub_pmp.peripersonal.capsule import Capsule, fit_capsules, hull_points
from icub_pmp.pmp.jacobian_provider import JacobianProvider

__all__ = ["ArmBodyModel", "arm_prefix", "DEFAULT_CAPSULE_LINKS", "DEFAULT_DISTAL_FRAMES"]

#: links with collision geometry in the simulator (icub_sim_bridge.model_builder), per arm
DEFAULT_CAPSULE_LINKS = ("upper_arm", "elbow_1", "forearm", "wrist_1", "hand")
#: the paper's distal joints: wrist and hand (frame names after the l_/r_ prefix)
DEFAULT_DISTAL_FRAMES = ("wrist_pitch", "hand_dh_frame")


def arm_prefix(spec: RobotSpec, arm: str) -> str:
    """URDF name prefix of ``arm`` ('l_' or 'r_', from its first joint's name)."""
    if arm not in HANDS:
        raise UnknownName("arm", arm, HANDS)
    return spec.arm_joints(arm)[0][:2]


@lru_cache(maxsize=4)
def _urdf_capsules(model_name: str, prefix: str, links: tuple[str, ...]) -> tuple[Capsule, ...]:
    """Capsules fitted to the collision meshes of ``prefix + link`` in the URDF."""
    from icub_sim_bridge.tri_mesh import TriMesh
    from icub_sim_bridge.urdf_robot import UrdfRobot

    path = urdf_path(model_name)
    urdf = UrdfRobot(path)
    meshes_root = path.parents[3]  # share/iCub/robots/<name>/model.urdf -> share/
    out = []
    for link in links:
        name = prefix + link
        if name not in urdf.links:
            raise UnknownName("URDF link", name, urdf.links)
        verts = []
        for c in urdf.links[name].collisions:
            if c.kind != "mesh":
                continue
            mesh = TriMesh.from_stl(urdf.resolve_mesh(c.mesh_file, meshes_root), c.scale)
            verts.append(mesh.transformed(c.T_link_geom).vertices)
        if not verts:
            raise InvalidInput(f"URDF link {name} has no collision mesh to fit a capsule to")
        out.extend(fit_capsules(name, hull_points(np.vstack(verts))))
    return tuple(out)


class ArmBodyModel:
    """Distal points and link capsules of both arms (module doc).

    Args:
        provider: the body model (forward kinematics with frame rotations).
        capsules: arm -> capsules fixed to frames of the provider.
        distal_frames: arm -> frames whose origins are the distal joints (wrist, hand).
    """

    def __init__(self, provider: JacobianProvider, capsules: Mapping[str, Sequence[Capsule]],
                 distal_frames: Mapping[str, Sequence[str]]):
        self.provider = provider
        frames = set(provider.frame_names())
        self.capsules: dict[str, tuple[Capsule, ...]] = {}
        self.distal_frames: dict[str, tuple[str, ...]] = {}
        for arm in HANDS:
            if arm not in capsules or arm not in distal_frames:
                raise InvalidInput(f"ArmBodyModel: capsules and distal frames needed for both "
                                   f"arms {HANDS}, got {sorted(capsules)} / "
                                   f"{sorted(distal_frames)}")
            caps = tuple(capsules[arm])
            dist = tuple(distal_frames[arm])
            for f in [c.frame for c in caps] + list(dist):
                if f not in frames:
                    raise UnknownName("frame of the body model", f, frames)
            self.capsules[arm] = caps
            self.distal_frames[arm] = dist
        self._a = {a: np.array([c.a for c in self.capsules[a]]) for a in HANDS}
        self._b = {a: np.array([c.b for c in self.capsules[a]]) for a in HANDS}
        self._r = {a: np.array([c.radius for c in self.capsules[a]]) for a in HANDS}
        for d in (self._a, self._b, self._r):
            for v in d.values():
                v.setflags(write=False)

    @classmethod
    def from_urdf(cls, provider: JacobianProvider, spec: RobotSpec | None = None,
                  links: Sequence[str] = DEFAULT_CAPSULE_LINKS,
                  distal: Sequence[str] = DEFAULT_DISTAL_FRAMES) -> "ArmBodyModel":
        """Capsules fitted to the URDF collision meshes of ``links`` (prefixed l_/r_) and the
        distal frames ``distal`` (prefixed), for ``provider``."""
        spec = spec or RobotSpec.load()
        caps, dist = {}, {}
        for arm in HANDS:
            p = arm_prefix(spec, arm)
            caps[arm] = _urdf_capsules(spec.model_name, p, tuple(links))
            dist[arm] = tuple(p + f for f in distal)
        return cls(provider, caps, dist)

    def radii(self, arm: str) -> np.ndarray:
        """Capsule radii (C,) [m] of ``arm``."""
        return self._r[self._arm(arm)]

    def capsule_names(self, arm: str) -> tuple[str, ...]:
        """The frames of ``arm``'s capsules, in order."""
        return tuple(c.frame for c in self.capsules[self._arm(arm)])

    def _arm(self, arm: str) -> str:
        if arm not in HANDS:
            raise UnknownName("arm", arm, HANDS)
        return arm

    def _q(self, q: np.ndarray) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.ndim == 1:
            q = q[None]
        if q.ndim != 2 or q.shape[1] != self.provider.nq or not np.all(np.isfinite(q)):
            raise InvalidInput(f"q: expected finite (K, {self.provider.nq}) [rad], got "
                               f"{q.shape}")
        return q

    def capsules_at(self, arm: str, q: np.ndarray) -> np.ndarray:
        """End points (K, C, 2, 3) [m, base frame] of ``arm``'s capsules at each q (K, nq)."""
        arm = self._arm(arm)
        q = self._q(q)
        frames = self.capsule_names(arm)
        out = np.empty((len(q), len(frames), 2, 3))
        for k, qk in enumerate(q):
            kin = self.provider.kinematics(qk, frames)
            R, p = kin.rotations, kin.positions
            out[k, :, 0] = np.einsum("cij,cj->ci", R, self._a[arm]) + p
            out[k, :, 1] = np.einsum("cij,cj->ci", R, self._b[arm]) + p
        return out

    def distal_points(self, arm: str, q: np.ndarray) -> np.ndarray:
        """Positions (K, D, 3) [m, base frame] of ``arm``'s distal joints at each q (K, nq)."""
        arm = self._arm(arm)
        q = self._q(q)
        frames = self.distal_frames[arm]
        return np.array([self.provider.positions(qk, frames) for qk in q])
