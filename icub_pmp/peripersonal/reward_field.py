"""RewardField: the default reward over an arm's peripersonal map (Bhat and Mohan 2018,
"Spatiotemporal reward field dynamics for goal-directed reasoning").

``R_i = (exp(-(y_i - Y)^2 / 2 sigma_R^2) + R_c) / Z`` with ``y_i`` the y coordinate of
neuron i, ``Y`` the y coordinate of the acting arm, ``R_c`` a constant reward for merely
acting (1 in the paper) and ``Z`` such that ``sum_i R_i = 1``.

The paper's two robots stand at the two ends of the workspace, so a reward that falls with
the y distance from the robot keeps each robot "within its unshared workspace for as many
successful assemblies as possible". On the iCub the two arms play the two robots
(root_link's y axis points to the robot's right), but the shoulders (y = -/+ 0.12 m) lie
above the space both arms reach; :class:`PeripersonalSpace` therefore puts each arm's Y at
the middle of the space only that arm reaches (the mean y of its unshared neurons), which
keeps the paper's intent: the reward peaks on the acting arm's side and is lowest in the
shared workspace.
"""

from __future__ import annotations

import math

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["RewardField"]


class RewardField:
    """Rewards (N,) of the neurons of one map.

    Args:
        neurons: the map's sensory weights (N, 3) [m] (root_link).
        arm_y: Y, the acting arm's y coordinate [m] (root_link).
        sigma_r: sigma_R, width of the reward along y [m].
        r_c: R_c, the constant minimum reward [-].
    """

    def __init__(self, neurons: np.ndarray, arm_y: float, sigma_r: float, r_c: float):
        for name, v in (("arm_y", arm_y), ("sigma_r", sigma_r), ("r_c", r_c)):
            if not math.isfinite(v):
                raise InvalidInput(f"{name}: expected a finite number, got {v}")
        if sigma_r <= 0:
            raise InvalidInput(f"sigma_r: expected a width > 0 m, got {sigma_r}")
        if r_c < 0:
            raise InvalidInput(f"r_c: expected a reward >= 0, got {r_c}")
        neurons = np.asarray(neurons, dtype=float)
        if neurons.ndim != 2 or neurons.shape[1] != 3 or len(neurons) == 0:
            raise InvalidInput(f"neurons: expected shape (N, 3) with N > 0, got {neurons.shape}")
        self.arm_y, self.sigma_r, self.r_c = float(arm_y), float(sigma_r), float(r_c)
        raw = np.exp(-((neurons[:, 1] - arm_y) ** 2) / (2.0 * sigma_r ** 2)) + r_c
        self.z = float(raw.sum())
        self.rewards = raw / self.z
        self.rewards.setflags(write=False)

    def __getitem__(self, i: int | np.ndarray) -> np.ndarray:
        """R_i of neuron(s) ``i``."""
        return self.rewards[i]

    @property
    def peak(self) -> int:
        """Index of the neuron with the largest reward."""
        return int(np.argmax(self.rewards))
