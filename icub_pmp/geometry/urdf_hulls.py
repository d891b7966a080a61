"""The convex collision hulls of an arm's links, read from the icub-models URDF.

MuJoCo collides the convex hulls of the URDF's collision meshes; :func:`urdf_link_hulls`
samples them (:class:`~icub_pmp.geometry.LinkHull`, in the link frames). Shared by the
imagined collision check (:class:`~icub_pmp.peripersonal.ArmBodyModel`) and the planner's
arm volume (:class:`~icub_pmp.pmp.BodyVolume`), which sit in packages that must not import
each other.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Sequence

import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.geometry.link_hull import LinkHull
from icub_pmp.kinematics.robot_spec import HANDS, RobotSpec, urdf_path

__all__ = ["arm_prefix", "urdf_link_hulls"]


def arm_prefix(spec: RobotSpec, arm: str) -> str:
    """URDF name prefix of ``arm`` ('l_' or 'r_', from its first joint's name)."""
    if arm not in HANDS:
        raise UnknownName("arm", arm, HANDS)
    return spec.arm_joints(arm)[0][:2]


@lru_cache(maxsize=8)
def _urdf_hulls(model_name: str, prefix: str, links: tuple[str, ...], spacing: float
                ) -> tuple[LinkHull, ...]:
    """Hulls of the collision meshes of ``prefix + link`` in the URDF (link frames)."""
    from icub_pmp.kinematics.tri_mesh import TriMesh
    from icub_pmp.kinematics.urdf_robot import UrdfRobot

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
            raise InvalidInput(f"URDF link {name} has no collision mesh")
        out.append(LinkHull(name, np.vstack(verts), spacing))
    return tuple(out)


def urdf_link_hulls(spec: RobotSpec, arm: str, links: Sequence[str],
                    spacing: float = 0.006) -> tuple[LinkHull, ...]:
    """The hulls of ``arm``'s URDF collision meshes of ``links`` (names after the l_/r_
    prefix, e.g. ``hand``, ``forearm``), sampled every ``spacing`` [m]; cached."""
    return _urdf_hulls(spec.model_name, arm_prefix(spec, arm), tuple(links), float(spacing))
