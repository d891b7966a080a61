"""PmpNodeConfig: the pmp_planner node's own parameters (besides :class:`~icub_pmp.pmp.PmpConfig`,
which it also takes as ROS parameters; ``config/pmp_planner.yaml``)."""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["PmpNodeConfig"]


@dataclasses.dataclass(frozen=True)
class PmpNodeConfig(ConfigBase):
    """Attributes:
    plan_from_rest_without_state: no /joint_states yet and no start_state: plan from 'rest'
        (said in the answer; the plan is not executed).
    joint_state_timeout: [s] older /joint_states count as missing (0 = any age).
    warm_up: build the bimanual+torso posture memory before serving.
    subscriber_timeout: [s, wall] wait up to this long for a subscriber on /joint_trajectory
        before publishing a plan (discovery right after start-up).
    controller_timeout: [s, wall] the reach action waits this long for the controller's
        FollowJointTrajectory server (and aborts a goal whose server vanished that long).
    """

    plan_from_rest_without_state: bool = True
    joint_state_timeout: float = 0.0
    warm_up: bool = True
    subscriber_timeout: float = 1.0
    controller_timeout: float = 5.0

    def validate(self) -> None:
        """The timeouts finite and >= 0."""
        for name in ("joint_state_timeout", "subscriber_timeout", "controller_timeout"):
            t = getattr(self, name)
            if not math.isfinite(t) or t < 0:
                raise ConfigError(f"{name}: expected a float >= 0 s, got {t!r}")
