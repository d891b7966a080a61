"""HeldObject: an external object coupled to the body network (Sect. 3.2, Fig 8).

For a bimanual transport "the goal pulls the external object that in turn pulls the body
(end-effectors) which in turn pulls the intrinsic elements in the body (joints)". The object
is a node of the network like a body segment: a position node ``x_o`` with its own virtual
admittance ``A_E`` (force -> motion in the tool space), linked to the hands by the device
Jacobian ``J_D`` (object motion -> hand motion). For a rigid object carried without rotation,
every grasp point moves with the object: ``x_i = x_o + r_i`` and ``J_D = [I; I]``.

The coupled relaxation (implemented by the network, :mod:`pmp_network`) has three fields:

- the goal field on the object: ``F_o = K_goal (x_goal - x_o)`` (eq 1 in the tool space);
- a stiff grasp coupling per hand: ``F_i = K_grasp (x_o + r_i - x_i)``, the object pulling the
  hand toward its grasp point (``T = J_i^T F_i`` into the joints, eq 2);
- the reaction of the hands on the object, ``-J_D^T [F_i]``;

so ``x_o_dot = A_E (F_o - sum_i F_i)`` and ``q_dot = A sum_i J_i^T F_i``, all under the same
TBG. With ``K_grasp >> K_goal`` the hands stay on their grasp points: the hand-to-hand vector
is kept during the transport.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["HeldObject"]


def _vec3(name: str, v) -> np.ndarray:
    a = np.array(v, dtype=float).reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise InvalidInput(f"{name}: expected 3 finite numbers, got {v!r}")
    return a


class HeldObject:
    """An object held by ``grasp_offsets`` hands, to be carried to ``goal``.

    Args:
        position: object reference point x_o at the start (3,) [m], base frame.
        goal: where x_o must go (3,) [m].
        grasp_offsets: hand -> r_i = (grasp point - x_o) (3,) [m], constant during transport.
        goal_stiffness: K_goal [N/m]. grasp_stiffness: K_grasp [N/m].
        admittance: A_E of the object node [m/(s N)] (relative to the joint admittances).
    """

    def __init__(
        self,
        position,
        goal,
        grasp_offsets: Mapping[str, object],
        goal_stiffness: float = 1000.0,
        grasp_stiffness: float = 1.0e5,
        admittance: float = 1.0,
    ):
        self.position = _vec3("object position", position)
        self.goal = _vec3("object goal", goal)
        if not grasp_offsets:
            raise InvalidInput("held object: at least one grasping hand is needed")
        self.grasp_offsets = {h: _vec3(f"grasp offset of {h}", r) for h, r in grasp_offsets.items()}
        for name, v in (("goal_stiffness", goal_stiffness), ("grasp_stiffness", grasp_stiffness),
                        ("admittance", admittance)):
            if not np.isfinite(v) or v <= 0:
                raise InvalidInput(f"held object {name}: expected a finite value > 0, got {v}")
        self.goal_stiffness = float(goal_stiffness)
        self.grasp_stiffness = float(grasp_stiffness)
        self.admittance = float(admittance)

    @classmethod
    def between_hands(cls, hand_positions: Mapping[str, np.ndarray], goal, **kw) -> "HeldObject":
        """Object whose reference point is the centroid of the grasping hands' positions."""
        p = np.mean([np.asarray(v, dtype=float) for v in hand_positions.values()], axis=0)
        return cls(p, goal, {h: np.asarray(v, dtype=float) - p
                             for h, v in hand_positions.items()}, **kw)

    @property
    def hands(self) -> tuple[str, ...]:
        """The grasping hands."""
        return tuple(self.grasp_offsets)

    def device_jacobian(self) -> np.ndarray:
        """J_D (3k, 3): object velocity -> grasp point velocities (pure translation)."""
        return np.vstack([np.eye(3)] * len(self.grasp_offsets))

    def hand_targets(self) -> dict[str, np.ndarray]:
        """Final hand positions when the object is at its goal: x_goal + r_i."""
        return {h: self.goal + r for h, r in self.grasp_offsets.items()}
