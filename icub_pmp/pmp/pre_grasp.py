"""PreGrasp: where the hand goes above a seen object, and by which way it gets there.

The goal is ``clearance`` above the centre of the object's top face (the pre-grasp of a grasp
from above). A reach moves the hand about along the straight line from where it is (PMP's
force field pulls it straight to the target, Mohan et al. 2009), so a hand that starts below
the goal or beside the object could sweep through it; the hand then first goes to a via point
``lift`` above the goal (at least as high as it already is), and descends to the goal from
there. The straight path is kept when each of its points is ``radius`` + ``margin`` away from
the object's axis, or when the hand is already over the object (within ``radius`` +
``margin`` of its axis, at the goal's height or above) and only descends. A hand that arrives
from the side at the goal's height is not kept: the iCub's fingers hang 4-8 cm below the hand
frame (docs/decisions/0053), and with the 6 cm clearance they swept the cylinder's top and
knocked it over (the vision bench's trial 17, docs/decisions/0058).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError, InvalidInput

__all__ = ["PreGrasp", "PreGraspConfig"]


@dataclasses.dataclass(frozen=True)
class PreGraspConfig(ConfigBase):
    """Parameters of :class:`PreGrasp`.

    Attributes:
        clearance: the hand's goal above the object's top centre [m].
        lift: the via point above the goal [m].
        margin: the hand's path keeps this far from the object's surface [m].
    """

    clearance: float = 0.06
    lift: float = 0.08
    margin: float = 0.05

    def validate(self) -> None:
        """Check ranges; raise :class:`ConfigError` naming the field."""
        for f in ("clearance", "lift", "margin"):
            if getattr(self, f) <= 0.0:
                raise ConfigError(f"PreGraspConfig.{f}: expected > 0 m, got {getattr(self, f)}")


class PreGrasp:
    """Goal and via points above an upright object (module doc)."""

    def __init__(self, config: PreGraspConfig | None = None):
        self.config = config or PreGraspConfig()

    def goal(self, top: np.ndarray) -> np.ndarray:
        """The hand's goal (3,) [m]: ``clearance`` above the top centre ``top`` (3,) [m]."""
        return _point(top, "top") + np.array([0.0, 0.0, self.config.clearance])

    def waypoints(self, hand: np.ndarray, top: np.ndarray, radius: float, height: float
                  ) -> np.ndarray:
        """Points (k, 3) [m] the hand goes through, the goal last (k = 1 or 2).

        Args:
            hand: (3,) the hand's position now [m] (root_link).
            top: (3,) the object's top centre [m].
            radius: the object's horizontal extent about its axis [m].
            height: its top above the support [m].

        Raises:
            InvalidInput: non-finite or negative sizes, malformed points.
        """
        c = self.config
        hand, top = _point(hand, "hand"), _point(top, "top")
        if not (np.isfinite(radius) and np.isfinite(height) and radius >= 0 and height >= 0):
            raise InvalidInput(f"radius, height: expected finite sizes >= 0 m, got {radius}, "
                               f"{height}")
        goal = self.goal(top)
        path = hand + np.linspace(0.0, 1.0, 21)[:, None] * (goal - hand)
        beside = np.linalg.norm(path[:, :2] - top[:2], axis=1) >= radius + c.margin
        over = not beside[0] and hand[2] >= goal[2] - 0.005
        if np.all(beside) or over:
            return goal[None, :]
        via = goal + np.array([0.0, 0.0, c.lift])
        via[2] = max(via[2], hand[2])
        return np.stack([via, goal])


def _point(p: np.ndarray, name: str) -> np.ndarray:
    a = np.asarray(p, dtype=float).reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise InvalidInput(f"{name}: expected a finite (3,) point [m], got "
                           f"{np.asarray(p).tolist()}")
    return a
