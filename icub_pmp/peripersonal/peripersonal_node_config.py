"""PeripersonalNodeConfig: the peripersonal_space node's own parameters (besides
PeripersonalConfig and CollisionCheckConfig, which it also takes as ROS parameters)."""

from __future__ import annotations

import dataclasses

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["PeripersonalNodeConfig"]


@dataclasses.dataclass(frozen=True)
class PeripersonalNodeConfig(ConfigBase):
    """Attributes:
        maps_dir: folder of the two maps (peripersonal_left.npz, peripersonal_right.npz,
            peripersonal_arms.json, as PeripersonalSpace.save writes them); relative to the
            repository root unless absolute.
        grow_if_missing: when maps_dir holds no maps, grow them at start-up (in the
            background, the services answer "not loaded yet" meanwhile) from babble_samples
            babbled hand positions per arm, and save them there.
        babble_samples: babbled hand positions per arm for growing the maps [-].
        babble_seed: seed of the babbling (left uses it, right uses it + 1) [-].
        map_topic: sensor_msgs/PointCloud2 of both maps' neurons (latched): x, y, z [m,
            root_link], arm (0 left, 1 right), shared (1 when the other arm reaches it too).
    """

    maps_dir: str = "data/peripersonal"
    grow_if_missing: bool = True
    babble_samples: int = 40000
    babble_seed: int = 1
    map_topic: str = "/peripersonal/maps"

    def validate(self) -> None:
        """Ranges and names (raise :class:`ConfigError` naming the field)."""
        if not self.maps_dir.strip():
            raise ConfigError("PeripersonalNodeConfig.maps_dir: empty path")
        if self.babble_samples < 100:
            raise ConfigError(f"PeripersonalNodeConfig.babble_samples must be >= 100, got "
                              f"{self.babble_samples}")
        t = self.map_topic
        if not t or " " in t or t.endswith("/"):
            raise ConfigError(f"PeripersonalNodeConfig.map_topic: not a topic name: {t!r}")
