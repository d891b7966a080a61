"""IkConfig: parameters of the eq 11 Cartesian solver (field names = ROS parameter names)."""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["IkConfig"]


@dataclasses.dataclass(frozen=True)
class IkConfig(ConfigBase):
    """Eq 11 of the reaching paper, solved by IPOPT (defaults: icub-main iKinSlv.cpp).

    ``epsilon`` bounds the SQUARED position error: the paper's [1e-5, 1e-4] m^2 allows
    3.2-10 mm. The default 2.5e-7 m^2 allows 0.5 mm, half of the 1 mm accuracy goal: IPOPT
    meets the bound only up to ``constraint_tolerance`` (worst case
    sqrt(epsilon + constraint_tolerance) = 0.51 mm), and the other half is left for tracking.

    Attributes:
        epsilon: bound on ||x_d - K_x(q)||^2 [m^2].
        constraint_tolerance: IPOPT ``constr_viol_tol`` on that constraint [m^2].
        orientation_weight: weight of the orientation term ||alpha_d - K_alpha(q)||^2 [1/rad^2].
        rest_weight: beta of eq 11, weight of the rest-posture term (< 1) [1/rad^2].
        rest_joint_weights_torso: diagonal of W on torso pitch, roll, yaw [-].
        rest_joint_weights_arm: diagonal of W on the 7 arm joints [-].
        rest_posture: named posture of config/robot.yaml used as q_rest (waist upright).
        shoulder_constraints: add iKin's 7 linear shoulder tendon / forearm constraints.
        tol: IPOPT ``tol`` (iKin default 1e-4).
        max_iter: IPOPT ``max_iter`` (iKin: 200).
        max_solve_time: wall-clock bound of one IPOPT solve [s] (``max_wall_time``). A solve
            takes milliseconds; the bound only stops pathological cases (iKin: 0.05-0.5 s on
            a broken install) and is loose enough that a loaded machine (solves 4-6 times
            slower, measured here) does not change the answers. It bounds each IPOPT call:
            with ``seed_warm_start`` a solve makes at most two (warm start, then fallback)
            after the seed, which is a fixed number of iterations (~0.3 ms).
        codegen: compile the NLP functions to C with gcc (cached on disk) for speed.
        seed_warm_start: start IPOPT warm (primal point and multipliers) from a compiled
            fixed-iteration Newton seed on eq 11 (:class:`IkSeed`) run from the start joints;
            IPOPT's answer is returned, and IPOPT from the usual start is the fallback when
            the seed misses the target or the warm-started IPOPT does not converge.
    """

    epsilon: float = 2.5e-7
    constraint_tolerance: float = 1e-8
    orientation_weight: float = 1.0
    rest_weight: float = 0.01
    rest_joint_weights_torso: tuple[float, ...] = (1.0, 1.0, 1.0)
    rest_joint_weights_arm: tuple[float, ...] = (0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1)
    rest_posture: str = "rest"
    shoulder_constraints: bool = True
    tol: float = 1e-4
    max_iter: int = 200
    max_solve_time: float = 0.5
    codegen: bool = True
    seed_warm_start: bool = True

    def validate(self) -> None:
        """Check ranges (raise :class:`ConfigError` naming the field)."""
        positive = ("epsilon", "constraint_tolerance", "tol", "max_solve_time")
        for name in positive:
            v = getattr(self, name)
            if not (v > 0 and math.isfinite(v)):
                raise ConfigError(f"IkConfig.{name} must be > 0 and finite, got {v!r}")
        for name in ("orientation_weight", "rest_weight"):
            v = getattr(self, name)
            if not (v >= 0 and math.isfinite(v)):
                raise ConfigError(f"IkConfig.{name} must be >= 0 and finite, got {v!r}")
        if self.max_iter < 1:
            raise ConfigError(f"IkConfig.max_iter must be >= 1, got {self.max_iter}")
        for name, n in (("rest_joint_weights_torso", 3), ("rest_joint_weights_arm", 7)):
            v = getattr(self, name)
            if len(v) != n or any(not (w >= 0 and math.isfinite(w)) for w in v):
                raise ConfigError(f"IkConfig.{name} needs {n} finite weights >= 0, got {v!r}")
