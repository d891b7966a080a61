"""IkSolution: the typed result of one Cartesian solve (eq 11)."""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["IkSolution"]


@dataclasses.dataclass(frozen=True)
class IkSolution:
    """Joint solution and the evidence of how good it is.

    Attributes:
        success: the hard constraints hold at ``q``: position error within
            sqrt(epsilon + constraint_tolerance), joint limits, shoulder constraints.
        converged: IPOPT reported an optimal (or acceptable) solution.
        chain: chain name (``torso_right_arm`` ...).
        joint_names: the chain's optimised joints (URDF names), order of ``q``.
        q: solution (n,) [rad] (read-only).
        position: hand position reached, (3,) [m] in root_link.
        rotation: hand orientation reached, (3, 3) ``R_root_hand``.
        position_error: ||x_d - K_x(q)|| [m].
        orientation_error: rotation angle between target and reached orientation [rad];
            NaN for a position-only request.
        constraint_violation: largest violation of the joint limits, the linear (shoulder)
            constraints [rad] and any extra constraint (its own units); 0 when met.
        solve_time: wall time of the solve [s].
        iterations: IPOPT iterations.
        status: IPOPT return status (``Solve_Succeeded``, ``Infeasible_Problem_Detected``,
            ``Maximum_WallTime_Exceeded`` ...) or ``exception``.
        message: one line for a user (why it failed, or a summary).
        seeded: the answer is IPOPT's, warm-started from the seed (:class:`IkSeed`);
            False when IPOPT ran from the start joints (seed off, missed, or fallback).
    """

    success: bool
    converged: bool
    chain: str
    joint_names: tuple[str, ...]
    q: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    position_error: float
    orientation_error: float
    constraint_violation: float
    solve_time: float
    iterations: int
    status: str
    message: str
    seeded: bool = False

    def __post_init__(self) -> None:
        for name in ("q", "position", "rotation"):
            a = np.array(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    def as_dict(self) -> dict[str, float]:
        """Joint name -> solution angle [rad]."""
        return dict(zip(self.joint_names, (float(v) for v in self.q)))
