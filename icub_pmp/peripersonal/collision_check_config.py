"""CollisionCheckConfig: parameters of the imagined collision check and pair scheduling."""

from __future__ import annotations

import dataclasses

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError
from icub_pmp.peripersonal.arm_body_model import DEFAULT_CAPSULE_LINKS, DEFAULT_DISTAL_FRAMES

__all__ = ["CollisionCheckConfig"]


@dataclasses.dataclass(frozen=True)
class CollisionCheckConfig(ConfigBase):
    """Imagined collision check (units in the field comments).

    ``margin`` was chosen on tuning pairs of reaches executed in parallel in the simulator
    (``bench/peripersonal.py --tune``, pair seed 1, 120 pairs): the pairs whose arms touched
    in the physics had been imagined at most 1.8 mm (30,000-babble maps) and 2.2 mm
    (40,000-babble maps) apart, about the hull sampling, while a few that did not touch had
    been imagined as close as 0.9-1.2 mm (the executed motion lags the imagined one). 8 mm
    keeps about 6 mm of safety above every touching pair (precision 0.84 and 0.95 on those
    sets); the benchmark scores it on other pairs (seed 2)."""

    reach_tau: float = 2.0  # duration of each imagined reach [s]
    check_period: float = 0.02  # time between checked samples of the trajectories [s]
    distal_threshold: float = 0.05  # wrist/hand points of the two arms closer = collision [m]
    body_check: bool = True  # also compare the arms' link hulls
    margin: float = 0.008  # link hulls closer than this = collision [m] (tuned, see doc)
    broad_phase: float = 0.03  # hulls compared where their capsules are this close [m]
    hull_spacing: float = 0.006  # surface samples of the link hulls this far apart [m]
    capsule_links: tuple[str, ...] = DEFAULT_CAPSULE_LINKS  # links with capsules (no l_/r_)
    distal_frames: tuple[str, ...] = DEFAULT_DISTAL_FRAMES  # the paper's distal joints (no l_/r_)
    safe_posture: str = "park"  # config/robot.yaml posture where a waiting arm waits
    park_duration: float = 1.5  # joint-space move to or from the safe posture [s]

    def validate(self) -> None:
        """Range checks (raise :class:`ConfigError` naming the field)."""
        for name in ("reach_tau", "check_period", "park_duration", "broad_phase",
                     "hull_spacing"):
            if not getattr(self, name) > 0.0:
                raise ConfigError(f"CollisionCheckConfig.{name}: expected > 0, got "
                                  f"{getattr(self, name)}")
        if self.distal_threshold < 0.0:
            raise ConfigError(f"CollisionCheckConfig.distal_threshold: expected >= 0 m, got "
                              f"{self.distal_threshold}")
        if not -0.05 <= self.margin <= 0.5:
            raise ConfigError(f"CollisionCheckConfig.margin: expected in [-0.05, 0.5] m, got "
                              f"{self.margin}")
        if not self.distal_frames or (self.body_check and not self.capsule_links):
            raise ConfigError("CollisionCheckConfig: distal_frames (and capsule_links with "
                              "body_check) must not be empty")
