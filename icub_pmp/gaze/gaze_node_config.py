"""GazeNodeConfig: the gaze_controller node's own parameters (besides GazeControllerConfig,
which it also takes as ROS parameters)."""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["GazeNodeConfig"]


@dataclasses.dataclass(frozen=True)
class GazeNodeConfig(ConfigBase):
    """Attributes:
        tracking: follow the points published on ``tracking_topic`` (also switched by the
            ``/gaze/set_tracking`` service).
        tracking_topic: geometry_msgs/PointStamped topic of the moving target (e.g.
            ``/motion/target``, the motion segmenter's stereo target).
        tracking_min_interval: re-plan at most once per this interval while tracking [s,
            node clock].
        fixation_rate: rate of ``/gaze/fixation_point`` [Hz, node clock].
        subscriber_timeout: wait up to this long for a subscriber on /joint_trajectory
            before publishing (discovery right after start-up) [s, wall].
        wait_timeout: a look_at with ``wait`` answers after at most this long [s, wall].
        motion_done_neck: the motion is done when every neck joint is this close to its
            target [rad] (iKinGazeCtrl ``GAZECTRL_MOTIONDONE_NECK_QTHRES`` 0.5 deg) ...
        motion_done_eyes: ... and every eye joint this close [rad] (``..._EYES_QTHRES``
            0.1 deg).
    """

    tracking: bool = False
    tracking_topic: str = "/motion/target"
    tracking_min_interval: float = 0.05
    fixation_rate: float = 30.0
    subscriber_timeout: float = 5.0
    wait_timeout: float = 30.0
    motion_done_neck: float = math.radians(0.5)
    motion_done_eyes: float = math.radians(0.1)

    def validate(self) -> None:
        """Ranges and the topic name (raise :class:`ConfigError` naming the field)."""
        for name in ("tracking_min_interval", "subscriber_timeout"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ConfigError(f"GazeNodeConfig.{name} must be >= 0 s, got {v!r}")
        for name in ("fixation_rate", "wait_timeout", "motion_done_neck", "motion_done_eyes"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ConfigError(f"GazeNodeConfig.{name} must be > 0, got {v!r}")
        t = self.tracking_topic
        if not t or " " in t or t.endswith("/"):
            raise ConfigError(f"GazeNodeConfig.tracking_topic: not a topic name: {t!r}")
