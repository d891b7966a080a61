"""ObstacleField: a repulsive field around a spherical obstacle in the extrinsic space.

External constraints of the PMP network (Sect. 2.3 of Mohan et al. 2009: "a typical
constraint is an obstacle, which can be implemented as a repulsive force field in the
extrinsic space, to be added to the attractive force field to the target"). The paper gives no
profile; we use the classic FIRAS potential (Khatib 1986) on the clearance
``rho = |x - c| - r``::

    U(rho) = 1/2 gain (1/rho - 1/rho0)^2          for rho < rho0, else 0
    F      = gain (1/rho - 1/rho0) / rho^2 * n     n = (x - c) / |x - c|

It is zero beyond the influence distance ``rho0``, so it does not move an equilibrium at a
target outside that shell, and it diverges at the surface.
"""

from __future__ import annotations

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["ObstacleField"]


class ObstacleField:
    """Sphere ``center`` (3,) [m], ``radius`` [m], influence distance ``influence`` [m] beyond
    the surface, ``gain`` [N m^2]."""

    #: smallest clearance [m] used in the force (inside the sphere the force is that of rho_min)
    rho_min = 1e-3

    def __init__(self, center, radius: float, influence: float = 0.05, gain: float = 1e-3):
        c = np.array(center, dtype=float).reshape(-1)
        if c.shape != (3,) or not np.all(np.isfinite(c)):
            raise InvalidInput(f"obstacle center: expected 3 finite numbers, got {center!r}")
        for name, v in (("radius", radius), ("influence", influence), ("gain", gain)):
            if not np.isfinite(v) or v <= 0:
                raise InvalidInput(f"obstacle {name}: expected a finite value > 0, got {v}")
        self.center = c
        self.center.setflags(write=False)
        self.radius = float(radius)
        self.influence = float(influence)
        self.gain = float(gain)

    def clearance(self, x) -> float | np.ndarray:
        """Distance [m] from point(s) ``x`` (..., 3) to the sphere surface (< 0 inside)."""
        return np.linalg.norm(np.asarray(x, dtype=float) - self.center, axis=-1) - self.radius

    def force(self, x) -> np.ndarray:
        """Repulsive force (3,) [N] on a point at ``x`` (3,) [m]."""
        d = np.asarray(x, dtype=float) - self.center
        dist = float(np.linalg.norm(d))
        rho = dist - self.radius
        if rho >= self.influence:
            return np.zeros(3)
        rho = max(rho, self.rho_min)
        n = d / dist if dist > 0 else np.array([0.0, 0.0, 1.0])
        return self.gain * (1.0 / rho - 1.0 / self.influence) / rho**2 * n

    def potential(self, x) -> float:
        """FIRAS potential [J] at ``x``."""
        rho = max(float(self.clearance(x)), self.rho_min)
        if rho >= self.influence:
            return 0.0
        return 0.5 * self.gain * (1.0 / rho - 1.0 / self.influence) ** 2
