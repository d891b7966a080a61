"""DlsSolver: damped-least-squares inverse kinematics, the classical baseline PMP is compared to.

The method the PMP paper contrasts itself with (Sect. 1: Nakamura & Hanafusa 1986, Wampler
1986; "DLS, also called the Levenberg-Marquardt method"): iterate

    dq = J^T (J J^T + mu^2 I)^-1 (x_T - x),     q <- clip(q + dq, q_min, q_max)

on the stacked hand positions until every hand is within ``tolerance`` of its target. It gives
a final posture only (no timing, no trajectory): the benchmark compares where it ends and how
long it takes with the PMP planner on the same targets, joints and limits.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.dls_step import damped_least_squares_step
from icub_pmp.pmp.jacobian_provider import JacobianProvider

__all__ = ["DlsSolver", "DlsResult"]


class DlsResult(NamedTuple):
    """Outcome of a DLS solve."""

    q: np.ndarray  # (nq,) full configuration [rad]
    residuals: np.ndarray  # (k,) hand distances to their targets [m]
    iterations: int
    success: bool  # every residual <= success_tolerance


class DlsSolver:
    """DLS IK on ``provider`` for the joints ``joint_names`` and the frames ``frames``.

    Args:
        damping: mu [m] (the damping factor of the DLS normal equations).
        max_iterations: iteration cap. tolerance: stop when all hands are this close [m].
        success_tolerance: verdict threshold [m]. max_step: cap on |dq| per iteration [rad].
        stall_iterations: stop after this many iterations without a 1% improvement.
    """

    def __init__(
        self,
        provider: JacobianProvider,
        joint_names: Sequence[str],
        frames: Sequence[str],
        damping: float = 0.02,
        max_iterations: int = 200,
        tolerance: float = 2.0e-5,
        success_tolerance: float = 1.0e-3,
        max_step: float = 0.5,
        stall_iterations: int = 20,
    ):
        for name, v in (("damping", damping), ("tolerance", tolerance),
                        ("success_tolerance", success_tolerance), ("max_step", max_step)):
            if not np.isfinite(v) or v <= 0:
                raise InvalidInput(f"DLS {name}: expected a finite value > 0, got {v}")
        self.provider = provider
        self.index = np.array([provider.joint_names.index(j) for j in joint_names], dtype=int)
        self.frames = tuple(frames)
        self.damping = float(damping)
        self.max_iterations = int(max_iterations)
        self.tolerance = float(tolerance)
        self.success_tolerance = float(success_tolerance)
        self.max_step = float(max_step)
        self.stall_iterations = int(stall_iterations)

    def solve(self, q_start: np.ndarray, targets: np.ndarray, lower: np.ndarray | None = None,
              upper: np.ndarray | None = None) -> DlsResult:
        """Iterate from ``q_start`` (nq,) toward ``targets`` (k, 3) [m]."""
        q = np.array(q_start, dtype=float)
        idx = self.index
        lo = self.provider.lower[idx] if lower is None else np.asarray(lower, dtype=float)
        hi = self.provider.upper[idx] if upper is None else np.asarray(upper, dtype=float)
        xt = np.asarray(targets, dtype=float).reshape(-1)
        k = len(self.frames)
        best, best_it, it = np.inf, 0, 0
        while True:
            kin = self.provider.kinematics(q, self.frames)
            e = xt - kin.positions.reshape(-1)
            res = np.linalg.norm(e.reshape(k, 3), axis=1)
            worst = float(res.max())
            if worst <= self.tolerance or it >= self.max_iterations:
                break
            if worst < 0.99 * best:
                best, best_it = worst, it
            elif it - best_it >= self.stall_iterations:
                break
            it += 1
            g = kin.jacobians[:, :3, :][:, :, idx].reshape(3 * k, len(idx))
            dq = damped_least_squares_step(g, e, self.damping, self.max_step)
            q[idx] = np.clip(q[idx] + dq, lo, hi)
        return DlsResult(q, res, it, bool(worst <= self.success_tolerance))
