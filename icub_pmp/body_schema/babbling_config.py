"""BabblingConfig: the body_schema node's babbling parameters (``config/body_schema.yaml``)."""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError
from icub_pmp.kinematics.robot_spec import HANDS

__all__ = ["BabblingConfig"]


@dataclasses.dataclass(frozen=True)
class BabblingConfig(ConfigBase):
    """Attributes:
        arm: the arm a start request without one babbles ('left' | 'right').
        samples: the sample budget of a start request without one.
        use_torso: babble torso + arm (10 joints) when the request does not say.
        move_time: time of each arm movement [s, simulated] (min-jerk, impedance controller).
        settle_time: wait after the movement before the images are taken [s, simulated].
        move_timeout: wall-time limit of one movement + settling [s, wall] (a slow simulator).
        image_timeout: wait this long for a stereo pair newer than the settled posture [s,
            wall].
        limit_margin: fraction of each joint range kept clear at both ends.
        seed: seed of the random targets (each run adds its index).
        look_at_hand: look at the hand's expected position (/gaze/look_at) at each posture.
        look_duration: neck trajectory time of each look [s]; 0 = the gaze node's default.
        marker_offset: the marker in the hand DH frame [m] (the simulator's
            ``hand_marker_offset``): used for the ground truth only.
        data_dir: folder of the datasets; empty = ``data/body_schema`` in the repository.
        progress_rate: progress messages while idle at most this often [Hz, wall].
    """

    arm: str = "right"
    samples: int = 100
    use_torso: bool = False
    move_time: float = 1.0
    settle_time: float = 0.4
    move_timeout: float = 60.0
    image_timeout: float = 10.0
    limit_margin: float = 0.05
    seed: int = 0
    look_at_hand: bool = True
    look_duration: float = 0.0
    marker_offset: tuple[float, ...] = (-0.02, -0.02, 0.04)
    data_dir: str = ""
    progress_rate: float = 1.0

    def validate(self) -> None:
        """Ranges (raise :class:`ConfigError` naming the field)."""
        if self.arm not in HANDS:
            raise ConfigError(f"BabblingConfig.arm: expected one of {HANDS}, got {self.arm!r}")
        if self.samples < 1:
            raise ConfigError(f"BabblingConfig.samples: expected >= 1, got {self.samples}")
        for name in ("move_time", "move_timeout", "image_timeout", "progress_rate"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ConfigError(f"BabblingConfig.{name}: expected > 0, got {v!r}")
        for name in ("settle_time", "look_duration"):
            if getattr(self, name) < 0:
                raise ConfigError(f"BabblingConfig.{name}: expected >= 0, got "
                                  f"{getattr(self, name)}")
        if not 0.0 <= self.limit_margin < 0.5:
            raise ConfigError(f"BabblingConfig.limit_margin: expected in [0, 0.5), got "
                              f"{self.limit_margin}")
        if len(self.marker_offset) != 3:
            raise ConfigError(f"BabblingConfig.marker_offset: expected 3 values [m], got "
                              f"{list(self.marker_offset)}")
