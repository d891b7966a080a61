"""BoxObstacleField: the repulsive field of :class:`ObstacleField` around an oriented box
(a table top, a shelf, a crate)."""

from __future__ import annotations

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.pmp.obstacle_field import ObstacleField, check_point, check_positive

__all__ = ["BoxObstacleField"]


class BoxObstacleField(ObstacleField):
    """Box centred at ``center`` (3,) [m], edges along the columns of ``rotation`` (3, 3)
    (``R_base_box``), ``half_extents`` (3,) [m] > 0; the other arguments as
    :class:`ObstacleField`."""

    kind = "box"

    def __init__(self, center, rotation, half_extents, influence: float = 0.05,
                 gain: float = 1e-3, inflation: float = 0.0):
        self.center = check_point("center", center)
        r = np.array(rotation, dtype=float)
        if r.shape != (3, 3) or not np.all(np.isfinite(r)) or \
                np.abs(r.T @ r - np.eye(3)).max() > 1e-6:
            raise InvalidInput("obstacle box: rotation must be a 3x3 rotation matrix")
        self.rotation = r
        self.rotation.setflags(write=False)
        h = check_point("box size", half_extents)
        for i, v in enumerate(h):
            check_positive(f"box size[{i}]", v)
        self.half_extents = h
        self.radius = float(np.linalg.norm(h))  # bounding sphere
        self._init_field(influence, gain, inflation)

    def _surface(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        local = (x - self.center) @ self.rotation  # box coordinates
        h = self.half_extents
        q = np.abs(local) - h
        outside = np.maximum(q, 0.0)
        out_dist = np.linalg.norm(outside, axis=-1)
        in_dist = np.minimum(q.max(axis=-1), 0.0)
        dist = out_dist + in_dist
        # normal: outside, toward the point from its closest point on the box; inside, the
        # nearest face's normal
        sign = np.where(local >= 0, 1.0, -1.0)
        safe = np.where(out_dist > 0, out_dist, 1.0)[..., None]
        n_out = outside * sign / safe
        face = np.argmax(q, axis=-1)
        n_in = np.zeros_like(local)
        np.put_along_axis(n_in, face[..., None],
                          np.take_along_axis(sign, face[..., None], axis=-1), axis=-1)
        n_local = np.where(out_dist[..., None] > 0, n_out, n_in)
        return dist, n_local @ self.rotation.T
