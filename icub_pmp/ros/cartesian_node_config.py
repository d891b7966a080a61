"""CartesianNodeConfig: the cartesian_solver node's own parameters (besides IkConfig and
MinJerkConfig, which it also takes as ROS parameters)."""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.cartesian.kinematic_chain import CHAIN_NAMES
from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["CartesianNodeConfig"]


@dataclasses.dataclass(frozen=True)
class CartesianNodeConfig(ConfigBase):
    """Attributes:
    default_chain: chain used when a request leaves ``chain`` empty.
    prebuild_chains: chains whose NLP is built (and compiled) at start-up, so the first
        request on them is fast; others are built on first use.
    subscriber_timeout: [s, wall] go_to_pose waits up to this long for a subscriber on
        /joint_trajectory before publishing (discovery right after start-up).
    """

    default_chain: str = "torso_right_arm"
    prebuild_chains: tuple[str, ...] = ("torso_right_arm",)
    subscriber_timeout: float = 1.0

    def validate(self) -> None:
        """Chain names must be known; the timeout finite and >= 0."""
        if not (math.isfinite(self.subscriber_timeout) and self.subscriber_timeout >= 0):
            raise ConfigError(
                f"subscriber_timeout must be >= 0 s, got {self.subscriber_timeout!r}")
        for name in (self.default_chain, *self.prebuild_chains):
            if name not in CHAIN_NAMES:
                raise ConfigError(f"unknown chain {name!r}; valid: {', '.join(CHAIN_NAMES)}")
