"""Idle hands stay where they were while the trunk moves (decision 0056).

A PMP goal for one hand with the trunk (Sect. 3.1, Fig 5 with one branch) moves the trunk
under both arms, but only the goal's arm is in the network: the other arm keeps its joint
angles and its hand is carried wherever the trunk takes it. With the iCub's rest posture
(forearms forward, hands 11 cm above the table) a reach to the far side of the table bends
the trunk 15-25 deg forward and turns it: the idle hand is pressed into the table (up to
100 N measured in the physics), and that contact holds the trunk 2-3 deg short of its plan,
so the reaching hand ends 2-4 cm from its target.

:func:`hold_idle_hand` gives the idle arm's joint path that keeps its hand at its start
position along the planned trunk path: damped least squares on the hand's position Jacobian
(the idle arm's columns only), a few iterations per sample, warm-started from the previous
sample. The idle arm does not act on the trunk, so the reaching hand's plan is unchanged.
Where the idle arm cannot compensate (joint limits, out of reach) its hand is kept as near
as it can be (best effort).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from icub_pmp.pmp.jacobian_provider import JacobianProvider

__all__ = ["hold_idle_hand"]


def hold_idle_hand(
    provider: JacobianProvider,
    frame: str,
    arm: Sequence[int],
    q_path: np.ndarray,
    margin: float = 0.05,
    damping: float = 0.01,
    iterations: int = 3,
    max_step: float | np.ndarray = np.inf,
    max_step_change: float | np.ndarray = np.inf,
) -> np.ndarray:
    """The idle arm's joint path (m, k) [rad] keeping ``frame`` at its position in
    ``q_path[0]``.

    Args:
        provider: the body model.
        frame: the idle hand's frame.
        arm: indices (k,) of the idle arm's joints in the provider's configuration.
        q_path: (m, nq) planned configurations [rad] (the trunk moving, the idle arm as at
            the start).
        margin: the arm stays this far inside its joint limits (or where it starts when
            nearer) [rad].
        damping: damping of the least squares [m].
        iterations: Gauss-Newton steps per sample.
        max_step: largest change of each idle joint from one sample to the next [rad] (scalar
            or (k,)): near a singular idle arm the least-squares step jumps (a 1.6 rad jump
            of ``l_wrist_pitch`` within one 20 ms sample was measured, which slowed a 3 s reach
            to 137 s at the joint velocity limits); the hand then lags a little instead.
        max_step_change: largest change of that step from one sample to the next [rad]
            (an acceleration bound, scalar or (k,)).
    """
    arm = np.asarray(arm, dtype=int)
    q_path = np.asarray(q_path, dtype=float)
    q0 = q_path[0, arm]
    lo = np.minimum(provider.lower[arm] + margin, q0)
    hi = np.maximum(provider.upper[arm] - margin, q0)
    target = provider.positions(q_path[0], [frame])[0]
    out = np.empty((len(q_path), len(arm)))
    out[0] = q0
    qa = q0.copy()
    lam2 = damping ** 2 * np.eye(3)
    step = np.zeros(len(arm))
    for i in range(1, len(q_path)):
        q = q_path[i].copy()
        prev = qa.copy()
        lo_step = np.maximum(step - max_step_change, -max_step)
        hi_step = np.minimum(step + max_step_change, max_step)
        for _ in range(iterations):
            q[arm] = qa
            kin = provider.kinematics(q, [frame])
            err = target - kin.positions[0]
            jac = kin.jacobians[0, :3][:, arm]
            qa = np.clip(qa + jac.T @ np.linalg.solve(jac @ jac.T + lam2, err), lo, hi)
            qa = np.clip(qa, prev + lo_step, prev + hi_step)
        step = qa - prev
        out[i] = qa
    return out
