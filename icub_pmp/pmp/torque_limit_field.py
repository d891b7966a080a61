"""TorqueLimitField: the saturation block of Fig 3 (Sect. 2.3, torque-limit avoidance).

"For a given force vector delivered at the end-effector, the actuator torques depend on the arm
configuration via the transpose Jacobian. The solution is given by operating the PMP model,
after x has converged to x_T, with the target force F_T applied as an additional input in the
extrinsic space. A saturation block, inserted after the mapping from the extrinsic to the
intrinsic space, allows the virtual motion in the null space to settle in a configuration that
satisfies the torque limits." (Mohan et al. 2009, Sect. 2.3)

Here the target forces ``F_T`` (the forces the hands must exert on the world) are mapped to the
required joint torques ``tau(q) = J^T F_T`` (+ the gravity torques ``g(q)`` if asked), the
saturation block clips them to ``+- margin * tau_max`` and the *excess* ``eps = tau - sat(tau)``
is what the motors cannot deliver. The field drives the virtual motion down the excess
(normalised by the ratings, ``W = diag(1/tau_max^2)``)::

    T_sat = -(d tau / dq)^T W eps

while the target field keeps the hand at x_T, so the chain settles in the null space of the
kinematic transformation into a configuration whose torques are within the limits (if the
self-motion manifold contains one). Its stiffness for the implicit step is the diagonal of the
Gauss-Newton Hessian ``S^T W S`` restricted to the saturated joints.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.pmp.jacobian_provider import JacobianProvider

__all__ = ["TorqueLimitField"]


class TorqueLimitField:
    """Excess-torque field over the network joints ``joint_index`` (indices into the
    provider's q) for ``frames`` pushing with ``forces`` (k, 3) [N]; ``limits`` (nq,) [N m]."""

    def __init__(
        self,
        provider: JacobianProvider,
        frames: Sequence[str],
        forces,
        limits,
        joint_index: np.ndarray,
        gravity: bool = False,
        margin: float = 0.95,
    ):
        self.provider = provider
        self.frames = tuple(frames)
        self.forces = np.array(forces, dtype=float).reshape(len(self.frames), 3)
        if not np.all(np.isfinite(self.forces)):
            raise InvalidInput("target forces: contain NaN or infinite values")
        lim = np.array(limits, dtype=float).reshape(-1)
        if lim.shape != (provider.nq,) or np.any(lim <= 0) or not np.all(np.isfinite(lim)):
            raise InvalidInput(f"torque limits: expected {provider.nq} finite values > 0 N m")
        if not 0.0 < margin <= 1.0:
            raise InvalidInput(f"torque limit margin: expected in (0, 1], got {margin}")
        self.limits = lim
        self.joint_index = np.asarray(joint_index, dtype=int)
        self.gravity = bool(gravity)
        self.margin = float(margin)
        self._w = 1.0 / lim**2

    def required_torques(self, q_full: np.ndarray) -> np.ndarray:
        """tau(q) (nq,) [N m]: torques needed to exert the target forces (and hold gravity)."""
        return self.provider.static_torques(q_full, self.frames, self.forces, self.gravity)

    def excess(self, q_full: np.ndarray) -> np.ndarray:
        """eps (nq,) [N m]: the part of tau beyond +- margin * tau_max (0 where within)."""
        tau = self.required_torques(q_full)
        cap = self.margin * self.limits
        return tau - np.clip(tau, -cap, cap)

    def violation(self, q_full: np.ndarray) -> float:
        """max_i |tau_i| / tau_max_i over the network joints (<= 1: all limits respected)."""
        tau = self.required_torques(q_full)
        return float(np.max(np.abs(tau[self.joint_index]) / self.limits[self.joint_index]))

    def torques_and_stiffness(
        self, q_full: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, float]:
        """(T_sat, diag stiffness) over the network joints, both (n,), and the largest
        excess relative to its rating, max |eps_i| / tau_max_i (0 when all are within)."""
        eps = self.excess(q_full)
        eps_net = np.zeros_like(eps)
        eps_net[self.joint_index] = eps[self.joint_index]
        eps = eps_net  # only the network's motors are rated here; the others do not move
        if not np.any(eps):
            n = len(self.joint_index)
            return np.zeros(n), np.zeros(n), 0.0
        sens = self.provider.static_torque_jacobian(
            q_full, self.frames, self.forces, self.gravity, self.joint_index
        )  # (nq, n): d tau / d q_network
        active = eps != 0.0
        ws = sens[active] * self._w[active, None]
        t_sat = -(ws.T @ eps[active])
        stiff = np.einsum("ij,ij->j", ws, sens[active])
        return t_sat, stiff, float(np.max(np.abs(eps) / self.limits))
