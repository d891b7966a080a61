"""KinematicChain: which joints the Cartesian solver moves, and toward which hand frame.

Four chains, selectable at run time (Sect. 4 of the reaching paper: "it is possible to change at
run time from the control of the 7-DoF iCub arm to the complete 10-DoF structure inclusive of
the waist"): ``left_arm`` / ``right_arm`` (7 arm joints, torso held at its current angles) and
``torso_left_arm`` / ``torso_right_arm`` (3 torso + 7 arm joints). The forward kinematics always
spans torso + arm (10 joints); in a 7-DoF chain the torso joints are fixed parameters.
"""

from __future__ import annotations

import dataclasses

from icub_pmp.errors import UnknownName
from icub_pmp.kinematics.robot_spec import RobotSpec

__all__ = ["KinematicChain", "CHAIN_NAMES"]

CHAIN_NAMES = ("left_arm", "right_arm", "torso_left_arm", "torso_right_arm")


@dataclasses.dataclass(frozen=True)
class KinematicChain:
    """A named torso/arm chain ending at a hand frame (URDF names, root_link base).

    Attributes:
        name: one of :data:`CHAIN_NAMES`.
        hand: ``'left'`` or ``'right'``.
        use_torso: whether the torso joints are optimised (10 DoF) or held (7 DoF).
        frame: end-effector frame (``l_hand_dh_frame`` / ``r_hand_dh_frame``).
        fk_joints: the 10 joints the hand pose depends on, torso first (pinocchio order).
        joints: the optimised joints (7 or 10), a suffix of ``fk_joints``.
    """

    name: str
    hand: str
    use_torso: bool
    frame: str
    fk_joints: tuple[str, ...]
    joints: tuple[str, ...]

    @classmethod
    def from_name(cls, name: str, spec: RobotSpec | None = None) -> "KinematicChain":
        """Build the chain ``name`` (raises :class:`UnknownName` listing the valid chains)."""
        if name not in CHAIN_NAMES:
            raise UnknownName("chain", name, CHAIN_NAMES)
        spec = spec or RobotSpec.load()
        hand = "left" if name.endswith("left_arm") else "right"
        use_torso = name.startswith("torso_")
        arm = spec.arm_joints(hand)
        fk = tuple(spec.torso_joints) + tuple(arm)
        return cls(
            name=name,
            hand=hand,
            use_torso=use_torso,
            frame=spec.hand_frame(hand),
            fk_joints=fk,
            joints=fk if use_torso else tuple(arm),
        )

    @classmethod
    def named(cls, hand: str, use_torso: bool) -> str:
        """Chain name for ``hand`` ('left'/'right') with or without the torso."""
        if hand not in ("left", "right"):
            raise UnknownName("hand", hand, ("left", "right"))
        return ("torso_" if use_torso else "") + f"{hand}_arm"

    @property
    def n(self) -> int:
        """Number of optimised joints (7 or 10)."""
        return len(self.joints)

    @property
    def fixed_joints(self) -> tuple[str, ...]:
        """Joints of ``fk_joints`` held at their current value (the torso in a 7-DoF chain)."""
        return tuple(j for j in self.fk_joints if j not in self.joints)
