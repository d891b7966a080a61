"""ReachGoal: what a PMP network is asked to do (targets, constraints, network shape)."""

from __future__ import annotations

import dataclasses
import math
from types import MappingProxyType
from typing import Mapping

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.pmp.held_object import HeldObject
from icub_pmp.pmp.obstacle_field import ObstacleField

__all__ = ["ReachGoal", "MAX_TARGET_DISTANCE"]

#: targets with a coordinate beyond this [m] are rejected (numerically meaningless)
MAX_TARGET_DISTANCE = 1.0e6


def _frozen_vectors(name: str, d: Mapping[str, object] | None, shape: tuple[int, ...]):
    out = {}
    for key, v in (d or {}).items():
        a = np.array(v, dtype=float)
        if a.shape != shape:
            raise InvalidInput(f"{name}[{key!r}]: expected shape {shape}, got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise InvalidInput(f"{name}[{key!r}]: contains NaN or infinite values")
        a.setflags(write=False)
        out[str(key)] = a
    return MappingProxyType(out)


@dataclasses.dataclass(frozen=True)
class ReachGoal:
    """A reach (or transport) task for the PMP planner. Positions in the base frame
    (root_link) [m], rotations ``R_base_hand``.

    Attributes:
        targets: hand -> target position (3,). The hands taking part are the keys (plus the
            grasping hands of ``held_object``).
        orientations: hand -> target rotation (3, 3); hands absent are position-only.
        use_torso: the trunk joins the network through the sum node (Sect. 3.1).
        tau: TBG duration [s]; None = the planner's default.
        obstacles: repulsive fields acting on the hands.
        frozen_joints: joints whose admittance is set to zero (they do not move).
        joint_limits: joint -> (lower, upper) [rad] replacing the model's range (e.g. a
            narrowed wrist, Fig 2).
        target_forces: hand -> force (3,) [N] the hand must exert on the world at the target;
            triggers the torque-limit settling of Sect. 2.3.
        held_object: an object carried by its grasping hands (Sect. 3.2).
        trunk_admittance_scale: multiplies A_trunk (0 = grounded shoulders, Fig 7).
        torque_limits: joint -> limit [N m] replacing the model's rating in the torque-limit
            settling of Sect. 2.3 (settling runs when this or ``target_forces`` is given).
        admittance_scales: joint -> factor >= 0 on its admittance (0 = frozen).
    """

    targets: Mapping[str, np.ndarray] = dataclasses.field(default_factory=dict)
    orientations: Mapping[str, np.ndarray] = dataclasses.field(default_factory=dict)
    use_torso: bool = True
    tau: float | None = None
    obstacles: tuple[ObstacleField, ...] = ()
    frozen_joints: tuple[str, ...] = ()
    joint_limits: Mapping[str, tuple[float, float]] = dataclasses.field(default_factory=dict)
    target_forces: Mapping[str, np.ndarray] = dataclasses.field(default_factory=dict)
    held_object: HeldObject | None = None
    trunk_admittance_scale: float = 1.0
    torque_limits: Mapping[str, float] = dataclasses.field(default_factory=dict)
    admittance_scales: Mapping[str, float] = dataclasses.field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "targets", _frozen_vectors("targets", self.targets, (3,)))
        for h, p in self.targets.items():
            if float(np.max(np.abs(p))) > MAX_TARGET_DISTANCE:
                raise InvalidInput(f"targets[{h!r}]: {p.tolist()} is farther than "
                                   f"{MAX_TARGET_DISTANCE:g} m from the base frame")
        object.__setattr__(
            self, "orientations", _frozen_vectors("orientations", self.orientations, (3, 3))
        )
        object.__setattr__(
            self, "target_forces", _frozen_vectors("target_forces", self.target_forces, (3,))
        )
        limits = {}
        for j, lim in dict(self.joint_limits).items():
            try:
                lo, hi = (float(v) for v in lim)
            except (TypeError, ValueError):
                raise InvalidInput(f"joint_limits[{j!r}]: expected (lower, upper)") from None
            if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
                raise InvalidInput(f"joint_limits[{j!r}]: need finite lower < upper, got {lim}")
            limits[j] = (lo, hi)
        object.__setattr__(self, "joint_limits", MappingProxyType(limits))
        for name, lowest in (("torque_limits", 0.0), ("admittance_scales", None)):
            checked = {}
            for j, v in dict(getattr(self, name)).items():
                v = float(v)
                if not math.isfinite(v) or v < 0 or (lowest is not None and v <= lowest):
                    bound = "> 0" if lowest is not None else ">= 0"
                    raise InvalidInput(f"{name}[{j!r}]: expected a finite value {bound}, "
                                       f"got {v}")
                checked[str(j)] = v
            object.__setattr__(self, name, MappingProxyType(checked))
        object.__setattr__(self, "obstacles", tuple(self.obstacles))
        object.__setattr__(self, "frozen_joints", tuple(self.frozen_joints))
        if self.tau is not None and (not math.isfinite(self.tau) or self.tau <= 0):
            raise InvalidInput(f"tau: expected a finite duration > 0 s, got {self.tau}")
        if not math.isfinite(self.trunk_admittance_scale) or self.trunk_admittance_scale < 0:
            raise InvalidInput(
                f"trunk_admittance_scale: expected >= 0, got {self.trunk_admittance_scale}"
            )
        if not self.hands:
            raise InvalidInput("reach goal: no hand has a target (targets and held_object empty)")
        if self.held_object is not None:
            both = sorted(set(self.held_object.hands) & set(self.targets))
            if both:
                raise InvalidInput(f"hand(s) {both} both grasp the held object and have a target")
        extra = sorted(set(self.orientations) - set(self.hands))
        extra += sorted(set(self.target_forces) - set(self.hands))
        if extra:
            raise InvalidInput(f"orientation/force given for hand(s) {extra} without a target")

    @property
    def hands(self) -> tuple[str, ...]:
        """Hands taking part (targets first, then grasping hands), ordered left before right."""
        hs = set(self.targets) | (set(self.held_object.hands) if self.held_object else set())
        return tuple(sorted(hs))
