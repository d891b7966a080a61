"""LinkTransforms: the URDF link tree as parent -> child transforms, from pinocchio.

What ROS's ``robot_state_publisher`` computes: for every URDF joint, the pose of its child link
in its parent link, ``T_parent_child`` [m]. Joints of the actuated upper body (the joints of
:class:`~icub_pmp.kinematics.IcubModel`) move with ``q``; every other joint (fixed joints and
the locked legs) gives a static transform. Poses come from pinocchio forward kinematics of the
same icub-models URDF (link frames are pinocchio BODY frames); the parent/child structure is
read from the URDF's ``<joint>`` elements. No ROS import.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, NamedTuple

import numpy as np
import pinocchio as pin

from icub_pmp.errors import ModelError
from icub_pmp.kinematics.robot_model import IcubModel

__all__ = ["LinkTransforms", "LinkTransform", "UrdfJointLink"]


class UrdfJointLink(NamedTuple):
    """A URDF joint: name, type ('revolute', 'fixed', ...), parent link, child link."""

    name: str
    type: str
    parent: str
    child: str


@dataclass(frozen=True)
class LinkTransform:
    """``T_parent_child``: translation (3,) [m] and unit quaternion (x, y, z, w)."""

    parent: str
    child: str
    translation: np.ndarray
    quat_xyzw: np.ndarray


class LinkTransforms:
    """Parent -> child link transforms of the iCub URDF for a configuration ``q``.

    ``model``: the pinocchio model (default: a new :class:`IcubModel`). :attr:`moving_joints`
    are the joints that depend on ``q``; :meth:`static` gives all the others once.
    """

    def __init__(self, model: IcubModel | None = None):
        self.model = model or IcubModel()
        self.urdf_file = Path(self.model.urdf)
        joints = parse_urdf_joints(self.urdf_file.read_text(encoding="utf-8"))
        frames = self.model.model
        body = {
            f.name: i for i, f in enumerate(frames.frames) if f.type == pin.FrameType.BODY
        }
        missing = [j.name for j in joints if j.parent not in body or j.child not in body]
        if missing:
            raise ModelError(
                f"links of URDF joints {missing[:5]} are not pinocchio body frames of "
                f"{self.urdf_file.name}"
            )
        active = set(self.model.joint_names)
        self._moving = [(j, body[j.parent], body[j.child]) for j in joints if j.name in active]
        self._fixed = [(j, body[j.parent], body[j.child]) for j in joints if j.name not in active]
        self.moving_joints: tuple[str, ...] = tuple(j.name for j, _, _ in self._moving)
        self.links: tuple[str, ...] = tuple(sorted({j.child for j in joints} |
                                                   {j.parent for j in joints}))
        self._q_neutral = pin.neutral(frames)

    # ------------------------------------------------------------------ transforms
    def static(self) -> list[LinkTransform]:
        """Transforms of every joint that does not move with ``q`` (fixed and locked)."""
        self.model.forward(self._q_neutral)
        return [self._relative(j, p, c) for j, p, c in self._fixed]

    def moving(self, q: np.ndarray) -> list[LinkTransform]:
        """Transforms of the joints of :attr:`moving_joints` at ``q`` (nq,) [rad]."""
        self.model.forward(self.model.check_q(q))
        return [self._relative(j, p, c) for j, p, c in self._moving]

    def q_from_positions(
        self, positions: Mapping[str, float], previous: np.ndarray | None = None
    ) -> np.ndarray:
        """``q`` from {joint: position [rad]}; joints not given keep ``previous`` (or 0)."""
        return self.model.q_from_dict(dict(positions), default=previous)

    def _relative(self, joint: UrdfJointLink, parent: int, child: int) -> LinkTransform:
        oMf = self.model.data.oMf
        T = oMf[parent].actInv(oMf[child])
        quat = pin.Quaternion(T.rotation).normalized()
        return LinkTransform(
            joint.parent,
            joint.child,
            np.array(T.translation, dtype=float),
            np.array([quat.x, quat.y, quat.z, quat.w], dtype=float),
        )

    # ------------------------------------------------------------------ description
    def urdf_text(self, mesh_prefix: str | None = None) -> str:
        """The URDF as text; ``mesh_prefix`` replaces the ``package://iCub/`` of mesh URIs
        (e.g. ``file:///.../share/iCub/`` so a viewer on this machine finds the meshes)."""
        text = self.urdf_file.read_text(encoding="utf-8")
        if mesh_prefix:
            text = text.replace("package://iCub/", mesh_prefix)
        return text

    def mesh_file_prefix(self) -> str:
        """``file://`` URI of the directory that ``package://iCub/`` stands for here."""
        # model.urdf lives in <share>/iCub/robots/<model>/model.urdf
        share = self.urdf_file.resolve().parents[2]
        return share.as_uri().rstrip("/") + "/"


def parse_urdf_joints(urdf: str) -> list[UrdfJointLink]:
    """The ``<joint>`` elements of a URDF text (raises ModelError on a malformed file)."""
    try:
        root = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise ModelError(f"the URDF is not valid XML: {exc}") from None
    out = []
    for j in root.findall("joint"):
        parent, child = j.find("parent"), j.find("child")
        if parent is None or child is None:
            raise ModelError(f"URDF joint {j.get('name')!r} has no parent or child link")
        out.append(UrdfJointLink(j.get("name", ""), j.get("type", ""), parent.get("link", ""),
                                 child.get("link", "")))
    return out
