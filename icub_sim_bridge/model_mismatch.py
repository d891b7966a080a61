"""ModelMismatch: the simulated robot's inertial parameters, perturbed from the URDF.

The estimator and the controller keep the URDF (pinocchio); the simulator steps a model whose
link masses, centres of mass and inertias differ from it, the way a CAD model differs from
the robot it describes (issue 17: masses +-10 %, COM +-1 cm, seeded). Per link ``b`` of the
robot with a mass: ``m_b' = s_b m_b`` with ``s_b`` uniform in ``1 +- mass_error``; the COM
``c_b' = c_b + d_b`` with ``d_b`` uniform in ``+-com_error`` per axis (body frame); the
principal inertia about the COM scaled by ``s_b`` (the same shape, the new mass).
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["ModelMismatch", "robot_bodies"]


def robot_bodies(model: mujoco.MjModel, root_body: str) -> np.ndarray:
    """Ids of the bodies of the tree rooted at ``root_body`` that have a mass (> 0)."""
    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, root_body)
    if root < 0:
        raise InvalidInput(f"robot_bodies: no body {root_body!r} in the model")
    tree = model.body_rootid[root]
    return np.array([b for b in range(1, model.nbody)
                     if model.body_rootid[b] == tree and model.body_mass[b] > 0.0], dtype=int)


class ModelMismatch(NamedTuple):
    """The drawn perturbation: per body id, the mass scale and the COM shift [m]."""

    bodies: np.ndarray  # (k,) body ids
    mass_scale: np.ndarray  # (k,) [-]
    com_shift: np.ndarray  # (k, 3) [m], body frame

    @classmethod
    def draw(cls, bodies: np.ndarray, mass_error: float, com_error: float,
             rng: np.random.Generator) -> ModelMismatch:
        """Draw uniform errors within +-``mass_error`` (relative) and +-``com_error`` [m]."""
        k = len(bodies)
        return cls(np.array(bodies, dtype=int), 1.0 + rng.uniform(-1, 1, k) * mass_error,
                   rng.uniform(-1, 1, (k, 3)) * com_error)

    def apply(self, model: mujoco.MjModel) -> None:
        """Write the perturbation into ``model`` (in place) and recompute its constants."""
        b = self.bodies
        model.body_mass[b] = model.body_mass[b] * self.mass_scale
        model.body_inertia[b] = model.body_inertia[b] * self.mass_scale[:, None]
        model.body_ipos[b] = model.body_ipos[b] + self.com_shift
        mujoco.mj_setConst(model, mujoco.MjData(model))
