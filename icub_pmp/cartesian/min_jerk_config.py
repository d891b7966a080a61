"""MinJerkConfig: parameters of the multi-referential minimum-jerk trajectory generator."""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["MinJerkConfig"]


@dataclasses.dataclass(frozen=True)
class MinJerkConfig(ConfigBase):
    """Defaults from iKin's cartesianController (icub-main ServerCartesianController.cpp,
    iKinInv.cpp).

    Attributes:
        trajectory_time: T of the min-jerk generators [s] (2 s as in Fig 9; >= 10 period).
        period: generator sample period [s] (controller period 10 ms).
        gamma: gain of the task-space coupling matrix W in the joint interior [-].
        guard_ratio: W fades to 0 within 0.25 * guard_ratio * range of a joint limit [-].
        task_space: couple the joint generator with the task-space one (x_dot = J q_dot);
            False = joint-space min-jerk only.
        settle_tolerance: the rollout ends when every joint is this close to q_d [rad].
        max_duration_factor: the rollout never exceeds this many T [-].
        max_trajectory_time: the longest T a goal may ask for [s] (as PmpConfig.max_tau: a
            goal asking 1e9 s rolled out 1e11 samples inside the service call).
    """

    trajectory_time: float = 2.0
    period: float = 0.01
    gamma: float = 0.05
    guard_ratio: float = 0.1
    task_space: bool = True
    settle_tolerance: float = 1e-4
    max_duration_factor: float = 4.0
    max_trajectory_time: float = 60.0

    def validate(self) -> None:
        """Check ranges (raise :class:`ConfigError` naming the field)."""
        for name in ("period", "settle_tolerance", "max_duration_factor", "guard_ratio"):
            v = getattr(self, name)
            if not (v > 0 and math.isfinite(v)):
                raise ConfigError(f"MinJerkConfig.{name} must be > 0 and finite, got {v!r}")
        if not (math.isfinite(self.gamma) and self.gamma >= 0):
            raise ConfigError(f"MinJerkConfig.gamma must be >= 0, got {self.gamma!r}")
        if not (math.isfinite(self.trajectory_time) and self.trajectory_time >= 10 * self.period):
            raise ConfigError(
                f"MinJerkConfig.trajectory_time must be >= 10 * period = {10 * self.period} s, "
                f"got {self.trajectory_time!r}"
            )
        if self.max_duration_factor < 1.0:
            raise ConfigError("MinJerkConfig.max_duration_factor must be >= 1")
        if not (math.isfinite(self.max_trajectory_time)
                and self.max_trajectory_time >= self.trajectory_time):
            raise ConfigError(
                f"MinJerkConfig.max_trajectory_time must be finite and >= trajectory_time = "
                f"{self.trajectory_time} s, got {self.max_trajectory_time!r}")
