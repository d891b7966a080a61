"""PeripersonalConfig: parameters of the peripersonal-space queries (maps, rewards, empty
areas) of Bhat and Mohan 2018."""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["PeripersonalConfig"]


@dataclasses.dataclass(frozen=True)
class PeripersonalConfig(ConfigBase):
    """Peripersonal-space queries (units in the field comments)."""

    reach_radius: float = 0.025  # a point this close to a neuron is inside the map [m]
    sigma_s: float = 0.03  # width of the activity kernel x_i [m]
    sigma_r: float = 0.12  # width sigma_R of the reward along y [m]
    r_c: float = 1.0  # constant reward R_c for merely acting (the paper's 1) [-]
    gripper_width: float = 0.07  # empty-area threshold T: the iCub hand's width [m]

    def validate(self) -> None:
        """Range checks (raise :class:`ConfigError` naming the field)."""
        for name in ("reach_radius", "sigma_s", "sigma_r", "gripper_width"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0.0):
                raise ConfigError(f"PeripersonalConfig.{name}: expected > 0 m, got {v}")
        if not (math.isfinite(self.r_c) and self.r_c >= 0.0):
            raise ConfigError(f"PeripersonalConfig.r_c: expected >= 0, got {self.r_c}")
