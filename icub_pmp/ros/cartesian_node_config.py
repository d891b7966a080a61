"""CartesianNodeConfig: the cartesian_solver node's own parameters (besides IkConfig and
MinJerkConfig, which it also takes as ROS parameters)."""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.cartesian.kinematic_chain import CHAIN_NAMES
from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["CartesianNodeConfig", "EXECUTIONS"]

#: the go_to_pose action's execution modes (CartesianNodeConfig.execution)
EXECUTIONS = ("trajectory", "closed_loop")


@dataclasses.dataclass(frozen=True)
class CartesianNodeConfig(ConfigBase):
    """Attributes:
    default_chain: chain used when a request leaves ``chain`` empty.
    prebuild_chains: chains whose NLP is built (and compiled) at start-up, so the first
        request on them is fast; others are built on first use.
    subscriber_timeout: [s, wall] go_to_pose waits up to this long for a subscriber on
        /joint_trajectory before publishing (discovery right after start-up).
    controller_timeout: [s, wall] the go_to_pose action waits this long for the controller's
        FollowJointTrajectory server.
    execution: how the go_to_pose action executes: ``trajectory`` (the min-jerk trajectory
        rolled out once and sent to the controller's FollowJointTrajectory action) or
        ``closed_loop`` (the generator fed back with the measured joints every period, its
        joint velocities sent to the controller's velocity mode: the cartesianController's
        scheme, Fig 8 of the reaching paper).
    """

    default_chain: str = "torso_right_arm"
    prebuild_chains: tuple[str, ...] = ("torso_right_arm",)
    subscriber_timeout: float = 1.0
    controller_timeout: float = 5.0
    execution: str = "trajectory"

    def validate(self) -> None:
        """Chain names must be known; the timeouts finite and >= 0; a known execution."""
        if self.execution not in EXECUTIONS:
            raise ConfigError(f"execution {self.execution!r}; valid: {', '.join(EXECUTIONS)}")
        for name in ("subscriber_timeout", "controller_timeout"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ConfigError(f"{name} must be >= 0 s, got {v!r}")
        for name in (self.default_chain, *self.prebuild_chains):
            if name not in CHAIN_NAMES:
                raise ConfigError(f"unknown chain {name!r}; valid: {', '.join(CHAIN_NAMES)}")
