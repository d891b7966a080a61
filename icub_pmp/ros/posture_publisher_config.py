"""PosturePublisherConfig: parameters of the ``posture_publisher`` node."""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["PosturePublisherConfig"]


@dataclasses.dataclass(frozen=True)
class PosturePublisherConfig(ConfigBase):
    """Attributes:
    posture: named posture of config/robot.yaml.
    rate_hz: publication rate [Hz].
    topic: the JointState topic (fixed once the node runs).
    """

    posture: str = "rest"
    rate_hz: float = 100.0
    topic: str = "joint_states"

    def validate(self) -> None:
        """The rate must be finite and > 0."""
        if not (math.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ConfigError(f"rate_hz must be > 0, got {self.rate_hz!r}")
