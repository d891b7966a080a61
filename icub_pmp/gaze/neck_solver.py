"""NeckSolver: neck angles that point the head centre at a fixation point (iKinGazeCtrl).

iKinGazeCtrl's neck solver (``HeadCenter_NLP`` in ``src/modules/iKinGazeCtrl/src/gazeNlp.cpp``,
Roncone, Pattacini, Metta, Natale, RSS 2016) finds the neck angles closest to a rest posture
(head upright, roll 0) such that the z axis of the head-centre frame points at the target,
within the joint limits:

    min_q  1/2 ||q - q_rest||^2   s.t.  z_hc(q) . (x_d - o_hc(q)) / ||x_d - o_hc(q)|| = 1

plus two inequalities that block the roll at its rest value when the pitch approaches its
lower limit (within 5 deg, through a tanh of 1 deg width: a head looking down does not roll
to point lower). The three neck joints (pitch, roll, yaw) are one more than the two of a
direction: the rest term keeps the roll near 0.

Here the pointing constraint becomes a least-squares term with the rest term weighted by
``rest_weight`` (small) and per joint by ``rest_joint_weights`` (iKinGazeCtrl: all 1; a
heavier roll keeps the head more upright), solved with bounds by scipy's trust-region
reflective least squares from the current neck angles:

    r(q) = [ d_hc(q) - e_z ;  sqrt(rest_weight) W (q - q_rest) ],
    d_hc = R_hc^T (x_d - o_hc) / ||x_d - o_hc||

and the roll block is applied as a second solve with the roll fixed at rest when the first
solution's pitch lies within 5 deg of its lower limit (the tanh's two regimes, without its
steep transition, which traps a gradient solver). A target outside the neck's range yields
the closest pointing the limits allow (the eyes then do the rest). The head pose comes from
the URDF (pinocchio), the head-centre offset from the iKin eye geometry
(:class:`~icub_pmp.gaze.eye_fixation.EyeFixation`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.optimize import least_squares

from icub_pmp.kinematics.robot_model import IcubModel

__all__ = ["NeckSolver", "NeckSolution", "NECK_JOINTS"]

NECK_JOINTS = ("neck_pitch", "neck_roll", "neck_yaw")
_EZ = np.array([0.0, 0.0, 1.0])
#: iKinGazeCtrl blocks the roll when the pitch is this near its lower limit [rad]
_ROLL_BLOCK_ZONE = math.radians(5.0)


class NeckSolution(NamedTuple):
    """Neck angles (3,) [rad] (pitch, roll, yaw), the angle left between the head-centre z
    axis and the target [rad], the joints at a limit, the solver's evaluations."""

    neck: np.ndarray
    pointing_error: float
    at_limit: tuple[str, ...]
    evaluations: int


class NeckSolver:
    """Point the head centre at a point (module doc).

    Args:
        model: the pinocchio model (torso and neck).
        T_head_center: head-centre frame (4, 4) in the URDF ``head`` frame.
        rest_weight: weight of the rest posture [-].
        rest_joint_weights: relative weights of pitch, roll, yaw in the rest term [-].
        margin: targets stay this far inside the neck limits [rad].
        rest: neck rest posture (3,) [rad] (default: 0, head upright on an upright torso).
    """

    def __init__(self, model: IcubModel, T_head_center: np.ndarray, rest_weight: float = 1e-3,
                 margin: float = 0.0, rest_joint_weights: tuple[float, ...] = (1.0, 1.0, 1.0),
                 rest: np.ndarray | None = None):
        self.model = model
        self.T_head_center = np.asarray(T_head_center, dtype=float)
        self.rest_weight = float(rest_weight)
        self.idx = model.indices(NECK_JOINTS)
        self.lower = model.lower[self.idx] + margin
        self.upper = model.upper[self.idx] - margin
        self.rest = np.zeros(3) if rest is None else np.asarray(rest, dtype=float)
        self._w = math.sqrt(self.rest_weight) * np.asarray(rest_joint_weights, dtype=float)
        self._head = model.frame_id("head")

    def head_pose(self, q_model: np.ndarray) -> np.ndarray:
        """URDF ``head`` frame (4, 4) in root_link at the model configuration (nq,)."""
        return self.model.frame_pose(q_model, self._head).homogeneous

    def direction(self, q_model: np.ndarray, p_root: np.ndarray) -> np.ndarray:
        """Unit direction (3,) to ``p_root`` in the head-centre frame (e_z = pointing)."""
        T = self.head_pose(q_model) @ self.T_head_center
        v = T[:3, :3].T @ (np.asarray(p_root, dtype=float) - T[:3, 3])
        return v / max(float(np.linalg.norm(v)), 1e-12)

    def pointing_error(self, q_model: np.ndarray, p_root: np.ndarray) -> float:
        """Angle [rad] between the head-centre z axis and the direction to ``p_root``."""
        d = self.direction(q_model, p_root)
        return math.atan2(math.hypot(d[0], d[1]), d[2])

    def solve(self, q_model: np.ndarray, p_root: np.ndarray) -> NeckSolution:
        """Neck angles for ``p_root`` (3,) [m], warm-started from the neck of ``q_model``
        (nq,) (the torso is taken from it too)."""
        q = np.array(q_model, dtype=float)
        p = np.asarray(p_root, dtype=float)
        x0 = np.clip(q[self.idx], self.lower, self.upper)
        x, nfev = self._solve(q, p, x0, free=np.array([True, True, True]))
        if x[0] < self.lower[0] + _ROLL_BLOCK_ZONE:  # looking down: roll blocked at rest
            x0[1] = min(max(self.rest[1], self.lower[1]), self.upper[1])
            x, n2 = self._solve(q, p, x0, free=np.array([True, False, True]))
            nfev += n2
        q[self.idx] = x
        at_limit = tuple(n for n, v, lo, hi in zip(NECK_JOINTS, x, self.lower, self.upper)
                         if v - lo < 1e-6 or hi - v < 1e-6)
        return NeckSolution(x, self.pointing_error(q, p), at_limit, nfev)

    def _solve(self, q: np.ndarray, p: np.ndarray, x0: np.ndarray, free: np.ndarray
               ) -> tuple[np.ndarray, int]:
        """Least squares over the ``free`` neck joints (the others stay at ``x0``)."""
        x = x0.copy()
        w = self._w[free]
        rest = self.rest[free]

        def residual(v: np.ndarray) -> np.ndarray:
            x[free] = v
            q[self.idx] = x
            return np.concatenate((self.direction(q, p) - _EZ, w * (v - rest)))

        res = least_squares(residual, x0[free], bounds=(self.lower[free], self.upper[free]),
                            method="trf", xtol=1e-10, ftol=1e-12, gtol=1e-12, max_nfev=200)
        x[free] = np.clip(res.x, self.lower[free], self.upper[free])
        return x, int(res.nfev)
