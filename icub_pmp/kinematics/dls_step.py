"""damped_least_squares_step: one iteration of damped-least-squares inverse kinematics.

The step of the DLS baseline (:class:`icub_pmp.baselines.DlsSolver`: the PMP paper's Sect. 1
comparison, Nakamura & Hanafusa 1986 / Wampler 1986, and the reaching paper's Sect. 4.1
comparison through Orocos KDL):

    dq = J^T (J J^T + mu^2 I)^-1 e,

scaled down to norm ``max_step`` when longer. Projecting ``q + dq`` on the joint limits is left
to the caller (it knows which joints ``J``'s columns are).
"""

from __future__ import annotations

import numpy as np

__all__ = ["damped_least_squares_step"]


def damped_least_squares_step(
    jacobian: np.ndarray, error: np.ndarray, damping: float, max_step: float
) -> np.ndarray:
    """The DLS joint step for ``jacobian`` (m, n) and task ``error`` (m,), norm <= max_step.

    ``damping`` is mu (in the task's units). Equivalent to the least-squares solution of
    ``[J; mu I] dq = [e; 0]`` (the Levenberg-Marquardt step), before the norm cap.
    """
    a = jacobian @ jacobian.T
    a.flat[:: a.shape[0] + 1] += damping**2  # + mu^2 I, in place
    dq = jacobian.T @ np.linalg.solve(a, error)
    norm = float(np.linalg.norm(dq))
    if norm > max_step:
        dq *= max_step / norm
    return dq
