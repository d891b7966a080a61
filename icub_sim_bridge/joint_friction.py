"""JointFriction: Coulomb + viscous friction with stiction, per joint group.

Friction torque on a joint of group g moving at speed v (opposing the motion):

    tau_f = (F_c + (F_s - F_c) exp(-(v / v_s)^2)) sign(v) + b v

(Coulomb ``F_c``, break-away / stiction ``F_s`` >= ``F_c`` below the Stribeck speed ``v_s``,
viscous ``b``). Realised in MuJoCo as the dof's dry-friction constraint (``dof_frictionloss``,
which holds a joint still until the applied torque exceeds it: stiction without chattering)
set each step to the speed-dependent dry term, plus ``b`` added to ``dof_damping`` (integrated
implicitly). Groups: torso, arm (shoulder to wrist), neck + eyes.
"""

from __future__ import annotations

import mujoco
import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["JointFriction", "GROUPS"]

GROUPS = ("torso", "arm", "neck")


def _group(joint: str) -> int:
    if "eye" in joint:
        return 2
    if joint.startswith("torso"):
        return 0
    if joint.startswith(("l_", "r_")):
        return 1
    return 2


class JointFriction:
    """Friction on the given MuJoCo dofs (module doc).

    Args:
        joints: joint names (group from the name: ``torso_*``, ``l_``/``r_`` arm, else neck).
        dofs: their dof addresses in the model, same order.
        coulomb, stiction, viscous: per group (torso, arm, neck) [N m], [N m], [N m s/rad].
        stribeck_velocity: [rad/s].
    """

    def __init__(self, joints: list[str], dofs: np.ndarray, coulomb: tuple[float, ...],
                 stiction: tuple[float, ...], viscous: tuple[float, ...],
                 stribeck_velocity: float):
        if len(joints) != len(dofs):
            raise InvalidInput(f"JointFriction: {len(joints)} joints for {len(dofs)} dofs")
        g = np.array([_group(j) for j in joints], dtype=int)
        self.dofs = np.asarray(dofs, dtype=int)
        self.coulomb = np.asarray(coulomb, dtype=float)[g]
        self.stiction = np.maximum(np.asarray(stiction, dtype=float)[g], self.coulomb)
        self.viscous = np.asarray(viscous, dtype=float)[g]
        self.stribeck_velocity = float(stribeck_velocity)

    def install(self, model: mujoco.MjModel) -> None:
        """Add the viscous term to the dofs' damping and set the break-away friction."""
        model.dof_damping[self.dofs] += self.viscous
        model.dof_frictionloss[self.dofs] = self.stiction

    def dry(self, v: np.ndarray) -> np.ndarray:
        """Dry-friction magnitude at speeds ``v`` (len(dofs),) [N m]."""
        return self.coulomb + (self.stiction - self.coulomb) * np.exp(
            -(v / self.stribeck_velocity) ** 2)

    def update(self, model: mujoco.MjModel, qvel: np.ndarray) -> None:
        """Set the dry-friction constraint for the current speeds (call before each step)."""
        model.dof_frictionloss[self.dofs] = self.dry(qvel[self.dofs])
