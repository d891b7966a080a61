"""CapsuleObstacleField: the repulsive field of :class:`ObstacleField` around a capsule
(a segment ``[a, b]`` grown by ``radius``; e.g. a pole, a bottle, a forearm)."""

from __future__ import annotations

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.pmp.obstacle_field import ObstacleField, check_point, check_positive

__all__ = ["CapsuleObstacleField"]


class CapsuleObstacleField(ObstacleField):
    """Capsule between cap centres ``a`` and ``b`` (3,) [m] of ``radius`` [m]; the other
    arguments as :class:`ObstacleField`."""

    kind = "capsule"

    def __init__(self, a, b, radius: float, influence: float = 0.05, gain: float = 1e-3,
                 inflation: float = 0.0):
        self.a = check_point("capsule end a", a)
        self.b = check_point("capsule end b", b)
        if np.linalg.norm(self.b - self.a) <= 0:
            raise InvalidInput("obstacle capsule: its two ends coincide (length 0)")
        self.radius = check_positive("radius", radius)
        self.center = check_point("center", 0.5 * (self.a + self.b))
        self._init_field(influence, gain, inflation)

    def _surface(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ab = self.b - self.a
        t = np.clip(((x - self.a) @ ab) / float(ab @ ab), 0.0, 1.0)
        closest = self.a + t[..., None] * ab
        d = x - closest
        dist = np.linalg.norm(d, axis=-1)
        safe = np.where(dist > 0, dist, 1.0)[..., None]
        side = np.cross(ab, [1.0, 0.0, 0.0])
        if np.linalg.norm(side) < 1e-9:
            side = np.cross(ab, [0.0, 1.0, 0.0])
        side = side / np.linalg.norm(side)
        n = np.where(dist[..., None] > 0, d / safe, side)
        return dist - self.radius, n
