"""UrdfRobot: the parts of a URDF file the MuJoCo model builder needs (links, joints, meshes).

A small read-only parser (``xml.etree``) of the robot tree: link inertials, visual/collision
geometry, joints with origin, axis, limits and dynamics. Poses are 4x4 homogeneous matrices
``T_parent_child`` [m]. No ROS, no MuJoCo: the builder turns this into an ``MjSpec``.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from icub_pmp.errors import ModelError, UnknownName

__all__ = ["UrdfRobot", "UrdfLink", "UrdfJoint", "UrdfGeometry", "UrdfInertial", "rpy_matrix"]


def rpy_matrix(rpy: tuple[float, float, float]) -> np.ndarray:
    """Rotation (3, 3) of URDF roll-pitch-yaw [rad]: ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def _origin(elem: ET.Element | None) -> np.ndarray:
    """``T`` (4, 4) of an ``<origin xyz rpy>`` element (identity when absent)."""
    T = np.eye(4)
    if elem is None:
        return T
    xyz = [float(v) for v in elem.get("xyz", "0 0 0").split()]
    rpy = [float(v) for v in elem.get("rpy", "0 0 0").split()]
    T[:3, :3] = rpy_matrix((rpy[0], rpy[1], rpy[2]))
    T[:3, 3] = xyz
    return T


@dataclasses.dataclass(frozen=True)
class UrdfInertial:
    """Mass [kg], centre of mass pose ``T_link_com`` (4, 4) and inertia (3, 3) [kg m^2] in the
    COM frame."""

    mass: float
    T_link_com: np.ndarray
    inertia: np.ndarray

    def inertia_in_link(self) -> np.ndarray:
        """Inertia (3, 3) about the COM, in the link's axes [kg m^2]."""
        R = self.T_link_com[:3, :3]
        return R @ self.inertia @ R.T


@dataclasses.dataclass(frozen=True)
class UrdfGeometry:
    """One visual or collision element: ``kind`` 'mesh' | 'box' | 'cylinder' | 'sphere'."""

    kind: str
    T_link_geom: np.ndarray
    mesh_file: str = ""
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    size: tuple[float, ...] = ()
    rgba: tuple[float, float, float, float] = (0.9, 0.9, 0.9, 1.0)


@dataclasses.dataclass(frozen=True)
class UrdfLink:
    """A link: optional inertial, visual and collision geometry."""

    name: str
    inertial: UrdfInertial | None
    visuals: tuple[UrdfGeometry, ...]
    collisions: tuple[UrdfGeometry, ...]

    @property
    def is_frame(self) -> bool:
        """True for a pure frame (no mass, no geometry), e.g. ``l_hand_dh_frame``."""
        return self.inertial is None and not self.visuals and not self.collisions


@dataclasses.dataclass(frozen=True)
class UrdfJoint:
    """A joint ``T_parent_child`` at zero angle, ``axis`` (3,) in the child frame, limits [rad],
    damping [N m s/rad] and friction [N m] from ``<dynamics>``."""

    name: str
    kind: str
    parent: str
    child: str
    T_parent_child: np.ndarray
    axis: np.ndarray
    lower: float
    upper: float
    damping: float
    friction: float


class UrdfRobot:
    """Links and joints of a URDF, with the tree navigation the builder needs."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        try:
            root = ET.parse(self.path).getroot()
        except (OSError, ET.ParseError) as exc:
            raise ModelError(f"cannot read URDF {self.path}: {exc}") from exc
        self.name = root.get("name", "robot")
        self.links: dict[str, UrdfLink] = {}
        self.joints: dict[str, UrdfJoint] = {}
        for le in root.findall("link"):
            self.links[le.get("name")] = self._link(le)
        for je in root.findall("joint"):
            j = self._joint(je)
            self.joints[j.name] = j
        self.child_joints: dict[str, list[UrdfJoint]] = {n: [] for n in self.links}
        children = set()
        for j in self.joints.values():
            if j.parent not in self.links or j.child not in self.links:
                raise ModelError(f"{self.path}: joint {j.name} links a missing link")
            self.child_joints[j.parent].append(j)
            children.add(j.child)
        roots = [n for n in self.links if n not in children]
        if len(roots) != 1:
            raise ModelError(f"{self.path}: expected one root link, found {roots}")
        self.root = roots[0]
        self.parent_joint: dict[str, UrdfJoint] = {j.child: j for j in self.joints.values()}

    # ------------------------------------------------------------------ parsing
    @staticmethod
    def _geometry(elem: ET.Element) -> UrdfGeometry | None:
        geom = elem.find("geometry")
        if geom is None or len(geom) == 0:
            return None
        g = geom[0]
        T = _origin(elem.find("origin"))
        rgba = (0.9, 0.9, 0.9, 1.0)
        color = elem.find("material/color")
        if color is not None:
            vals = [float(v) for v in color.get("rgba", "0.9 0.9 0.9 1").split()]
            rgba = (vals[0], vals[1], vals[2], vals[3])
        if g.tag == "mesh":
            scale = [float(v) for v in g.get("scale", "1 1 1").split()]
            return UrdfGeometry("mesh", T, g.get("filename", ""), (scale[0], scale[1], scale[2]),
                                rgba=rgba)
        if g.tag == "box":
            return UrdfGeometry("box", T, size=tuple(float(v) for v in g.get("size").split()),
                                rgba=rgba)
        if g.tag == "cylinder":
            return UrdfGeometry("cylinder", T, size=(float(g.get("radius")),
                                                     float(g.get("length"))), rgba=rgba)
        if g.tag == "sphere":
            return UrdfGeometry("sphere", T, size=(float(g.get("radius")),), rgba=rgba)
        return None

    def _link(self, le: ET.Element) -> UrdfLink:
        inertial = None
        ie = le.find("inertial")
        if ie is not None:
            m = float(ie.find("mass").get("value"))
            ia = ie.find("inertia")
            g = {k: float(ia.get(k, "0")) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
            inertia = np.array(
                [
                    [g["ixx"], g["ixy"], g["ixz"]],
                    [g["ixy"], g["iyy"], g["iyz"]],
                    [g["ixz"], g["iyz"], g["izz"]],
                ]
            )
            inertial = UrdfInertial(m, _origin(ie.find("origin")), inertia)
        visuals = tuple(g for g in map(self._geometry, le.findall("visual")) if g is not None)
        colls = tuple(g for g in map(self._geometry, le.findall("collision")) if g is not None)
        return UrdfLink(le.get("name"), inertial, visuals, colls)

    @staticmethod
    def _joint(je: ET.Element) -> UrdfJoint:
        axis_e = je.find("axis")
        axis = np.array([float(v) for v in axis_e.get("xyz").split()]) if axis_e is not None \
            else np.array([1.0, 0.0, 0.0])
        n = np.linalg.norm(axis)
        axis = axis / n if n > 0 else np.array([1.0, 0.0, 0.0])
        lim = je.find("limit")
        lower = float(lim.get("lower", "0")) if lim is not None else 0.0
        upper = float(lim.get("upper", "0")) if lim is not None else 0.0
        dyn = je.find("dynamics")
        damping = float(dyn.get("damping", "0")) if dyn is not None else 0.0
        friction = float(dyn.get("friction", "0")) if dyn is not None else 0.0
        return UrdfJoint(
            name=je.get("name"),
            kind=je.get("type"),
            parent=je.find("parent").get("link"),
            child=je.find("child").get("link"),
            T_parent_child=_origin(je.find("origin")),
            axis=axis,
            lower=lower,
            upper=upper,
            damping=damping,
            friction=friction,
        )

    # ------------------------------------------------------------------ queries
    def joint(self, name: str) -> UrdfJoint:
        """The joint ``name`` (raises :class:`UnknownName`)."""
        if name not in self.joints:
            raise UnknownName("URDF joint", name, self.joints)
        return self.joints[name]

    def subtree_links(self, link: str) -> list[str]:
        """``link`` and every link below it (depth first)."""
        if link not in self.links:
            raise UnknownName("URDF link", link, self.links)
        out, stack = [], [link]
        while stack:
            n = stack.pop()
            out.append(n)
            stack.extend(j.child for j in reversed(self.child_joints[n]))
        return out

    def resolve_mesh(self, filename: str, meshes_root: Path) -> Path:
        """File path of a ``package://iCub/meshes/...`` URI under ``meshes_root`` (the folder
        holding ``iCub/``)."""
        if filename.startswith("package://"):
            return meshes_root / filename[len("package://"):]
        return Path(filename)
