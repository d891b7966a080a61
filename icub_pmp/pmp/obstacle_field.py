"""ObstacleField: a repulsive field around a spherical obstacle in the extrinsic space.

External constraints of the PMP network (Sect. 2.3 of Mohan et al. 2009: "a typical
constraint is an obstacle, which can be implemented as a repulsive force field in the
extrinsic space, to be added to the attractive force field to the target"). The paper gives no
profile; we use the classic FIRAS potential (Khatib 1986) on the clearance
``rho = |x - c| - r - inflation``::

    U(rho) = 1/2 gain (1/rho - 1/rho0)^2          for rho < rho0, else 0
    F      = gain (1/rho - 1/rho0) / rho^2 * n     n = (x - c) / |x - c|

It is zero beyond the influence distance ``rho0``, so it does not move an equilibrium at a
target outside that shell, and it diverges at the (inflated) surface. ``inflation`` [m] is the
clearance the hands must keep: the field and :meth:`clearance` act on the obstacle grown by
it, :meth:`surface_distance` measures the real surface. Other primitives
(:class:`~icub_pmp.pmp.capsule_obstacle_field.CapsuleObstacleField`,
:class:`~icub_pmp.pmp.box_obstacle_field.BoxObstacleField`) override :meth:`_surface`.
"""

from __future__ import annotations

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["ObstacleField"]


def check_positive(name: str, v: float, allow_zero: bool = False) -> float:
    """``v`` as a float, or InvalidInput naming ``name`` if not finite and > 0 (>= 0)."""
    v = float(v)
    if not np.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise InvalidInput(f"obstacle {name}: expected a finite value {bound}, got {v}")
    return v


def check_point(name: str, p) -> np.ndarray:
    """``p`` as a read-only (3,) array, or InvalidInput naming ``name``."""
    c = np.array(p, dtype=float).reshape(-1)
    if c.shape != (3,) or not np.all(np.isfinite(c)):
        raise InvalidInput(f"obstacle {name}: expected 3 finite numbers, got {p!r}")
    c.setflags(write=False)
    return c


class ObstacleField:
    """Sphere ``center`` (3,) [m], ``radius`` [m], influence distance ``influence`` [m] beyond
    the inflated surface, ``gain`` [N m^2], ``inflation`` [m] (the clearance to keep)."""

    #: smallest clearance [m] used in the force (inside the sphere the force is that of rho_min)
    rho_min = 1e-3
    kind = "sphere"

    def __init__(self, center, radius: float, influence: float = 0.05, gain: float = 1e-3,
                 inflation: float = 0.0):
        self.center = check_point("center", center)
        self.radius = check_positive("radius", radius)
        self._init_field(influence, gain, inflation)

    def _init_field(self, influence: float, gain: float, inflation: float) -> None:
        self.influence = check_positive("influence", influence)
        self.gain = check_positive("gain", gain)
        self.inflation = check_positive("inflation", inflation, allow_zero=True)
        self.rho_min = min(type(self).rho_min, 0.1 * self.influence)

    def clear_of(self, points) -> "ObstacleField":
        """This field with its influence shrunk so that ``points`` (k, 3) [m] (the targets)
        lie outside it (at most 0.9 of their clearance): the field then does not move an
        equilibrium at a target. Raises InvalidInput when a point is inside the grown surface."""
        pts = np.asarray(points, dtype=float).reshape(-1, 3)
        if not len(pts):
            return self
        rho = float(np.min(self.clearance(pts)))
        if rho <= 0:
            raise InvalidInput(f"obstacle {self.kind}: a target is {rho * 1e3:.1f} mm inside its "
                               f"surface grown by the clearance ({self.inflation * 1e3:.1f} mm)")
        if 0.9 * rho >= self.influence:
            return self
        field = object.__new__(type(self))
        field.__dict__.update(self.__dict__)
        field.influence = 0.9 * rho
        field.rho_min = min(type(self).rho_min, 0.1 * field.influence)
        return field

    def _surface(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(signed distance to the real surface (...,) [m], < 0 inside; outward unit normal
        (..., 3)) at points ``x`` (..., 3)."""
        d = x - self.center
        dist = np.linalg.norm(d, axis=-1)
        safe = np.where(dist > 0, dist, 1.0)[..., None]
        n = np.where(dist[..., None] > 0, d / safe, np.array([0.0, 0.0, 1.0]))
        return dist - self.radius, n

    def surface_distance(self, x) -> float | np.ndarray:
        """Distance [m] from point(s) ``x`` (..., 3) to the real surface (< 0 inside)."""
        return self._surface(np.asarray(x, dtype=float))[0]

    def clearance(self, x) -> float | np.ndarray:
        """Distance [m] from point(s) ``x`` (..., 3) to the surface inflated by
        ``inflation`` (< 0: closer than the clearance to keep)."""
        return self.surface_distance(x) - self.inflation

    def force(self, x) -> np.ndarray:
        """Repulsive force (3,) [N] on a point at ``x`` (3,) [m]."""
        dist, n = self._surface(np.asarray(x, dtype=float))
        rho = float(dist) - self.inflation
        if rho >= self.influence:
            return np.zeros(3)
        rho = max(rho, self.rho_min)
        return self.gain * (1.0 / rho - 1.0 / self.influence) / rho**2 * n

    def sphere_forces(self, x, radii) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Repulsive forces (n, 3) [N] on spheres centred at ``x`` (n, 3) [m] with ``radii``
        (n,) [m] (the field of :meth:`force` with the clearance reduced by each radius), their
        clearances (n,) [m] (< 0: closer than the clearance to keep) and the field's stiffness
        along the normal ``-d|F|/d rho`` (n,) [N/m] (0 outside the influence)."""
        dist, n = self._surface(np.asarray(x, dtype=float))
        rho = dist - self.inflation - np.asarray(radii, dtype=float)
        r = np.maximum(rho, self.rho_min)
        inside = rho < self.influence
        mag = np.where(inside, self.gain * (1.0 / r - 1.0 / self.influence) / r**2, 0.0)
        stiff = np.where(inside, self.gain * (3.0 / r**4 - 2.0 / (self.influence * r**3)), 0.0)
        return mag[:, None] * n, rho, np.maximum(stiff, 0.0)

    def potential(self, x) -> float:
        """FIRAS potential [J] at ``x``."""
        rho = max(float(self.clearance(x)), self.rho_min)
        if rho >= self.influence:
            return 0.0
        return 0.5 * self.gain * (1.0 / rho - 1.0 / self.influence) ** 2
