"""PmpConfig: parameters of the PMP planner (= ROS parameters of the ``pmp_planner`` node).

Gains are "virtual" (Mohan et al. 2009: K_ext a virtual stiffness, A_int a virtual admittance):
only their ratios shape the plan, because the relaxation rate is normalised per plan (the
initial rate of Appendix A is set to 1 per unit of relaxation time). References for the
ratios: the DARWIN PMP on the iCub (its PMPconfiguration.ini, see docs/references.md) uses an
isotropic-ish K_virt,
arm admittances of the same order for all arm joints and a trunk admittance 1-2 orders of
magnitude smaller (a stiff trunk recruited when the arms are not enough).
"""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["PmpConfig", "TIME_PARAMETRISATIONS"]

TIME_PARAMETRISATIONS = ("progress", "gamma")


@dataclasses.dataclass(frozen=True)
class PmpConfig(ConfigBase):
    """PMP planner configuration (units in the field comments)."""

    # timing (Sect. 2.4)
    tau: float = 2.0  # default TBG duration [s]
    max_tau: float = 60.0  # longest TBG duration a goal may ask for [s]
    sample_period: float = 0.02  # time between trajectory points [s]
    time_parametrisation: str = "progress"  # "progress" (gamma of eq A5 normalised to 1) | "gamma"
    rotation_length_scale: float = 0.1  # [m/rad] orientation motion in the progress measure
    progress_joint_floor: float = 0.0  # >0: joint motion counted as progress (extension, 0061)
    # extrinsic fields (eq 1)
    stiffness: tuple[float, ...] = (1000.0, 1000.0, 1000.0)  # K_ext diagonal, root_link x y z [N/m]
    rotation_stiffness: float = 10.0  # orientation field [N m/rad]
    curl: float = 0.0  # rotational component of the target field [N/m]
    curl_axis: tuple[float, ...] = (0.0, 0.0, 1.0)  # its axis (root_link)
    # admittances (eq 3, Sect. 3.1), relative; order of robot.yaml's joint lists
    arm_admittance: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0)  # [rad/(s N m)]
    trunk_admittance: tuple[float, ...] = (0.2, 0.2, 0.2)  # A_trunk [rad/(s N m)]
    range_normalised_admittance: bool = True  # scale A_i by (range_i / mean range)^2
    balance_hands: bool = True  # per-hand K_ext scaled so both hands start at the same rate
    synchronise_hands: float = 0.0  # >0: exponent of a per-hand progress feedback (extension)
    # internal constraints (eq 6)
    joint_limit_alpha: float = 1.0e-3  # scale of the joint-limit field [N m]
    # relaxation (integration in relaxation time s)
    initial_step: float = 0.2  # first step [s units]
    step_growth: float = 1.35  # growth of the step from one step to the next
    max_step: float = 1.0e4  # largest step [s units]
    max_displacement: float = 0.0  # >0: step control, hand motion per step [m]
    max_steps: int = 200  # per relaxation
    stall_steps: int = 15  # steps without 1% improvement = equilibrium
    convergence_tolerance: float = 1.0e-4  # stop when every hand is this close [m]
    rotation_tolerance: float = 1.0e-4  # and orientation this close [rad]
    boundary_fraction: float = 0.99  # max fraction of the distance to a limit per step
    obstacle_step: float = 0.01  # [m] with obstacles: step control, hand motion per step (the
    # sampled plan then follows the relaxation's path around them); 0 = as without obstacles
    obstacle_body_links: tuple[str, ...] = ("hand", "wrist_1", "forearm")  # links (after the
    # l_/r_ prefix) whose collision hulls the obstacle fields keep clear, as spheres
    # (BodyVolume); () = the hand frames only
    obstacle_body_null_distance: float = 0.05  # [m] within this of its target a hand's body
    # fields act in the null space of its position only (the equilibrium stays on the target)
    # success (mental simulation verdict)
    success_tolerance: float = 1.0e-3  # hand within this of its target at tau [m]
    rotation_success_tolerance: float = 0.01  # [rad]
    start_tolerance: float = 0.05  # start may exceed a limit by this much [rad] (then clamped)
    # idle hands (decision 0056): a hand that takes no part in a goal with the trunk keeps its
    # position while the trunk moves (its arm compensates; it does not act on the trunk)
    hold_idle_hands: bool = False
    idle_hand_margin: float = 0.05  # the compensating arm stays this far inside its limits [rad]
    # posture memory fallback (Sect. 4)
    posture_memory_size: int = 20000  # babbled postures (0 = no fallback)
    posture_memory_seed: int = 0
    posture_memory_attempts: int = 3  # nearest postures tried, one relaxation each
    posture_field_gain: float = 300.0  # pull toward the recalled posture [N m/rad]
    posture_field_decay: float = 2.0  # its fading constant [s units]
    # torque-limit settling (Sect. 2.3)
    torque_limit_margin: float = 0.95  # settle below this fraction of each rating
    torque_gravity: bool = True  # include gravity torques in the required torques
    settle_max_steps: int = 300
    settle_max_step: float = 100.0  # largest settling step [s units] (the saturation field is
    # linearised by its diagonal only: long steps would let the hand drift off the target)

    def validate(self) -> None:
        """Check ranges; raise :class:`ConfigError` naming the field."""
        positive = (
            "tau", "max_tau", "sample_period", "rotation_length_scale", "rotation_stiffness",
            "initial_step", "max_step", "convergence_tolerance", "rotation_tolerance",
            "success_tolerance", "rotation_success_tolerance", "posture_field_decay",
            "settle_max_step",
        )
        for name in positive:
            v = getattr(self, name)
            if not math.isfinite(v) or v <= 0:
                raise ConfigError(f"PmpConfig.{name}: expected a finite value > 0, got {v}")
        nonneg = ("curl", "joint_limit_alpha", "posture_field_gain", "start_tolerance",
                  "max_displacement", "synchronise_hands", "obstacle_step", "idle_hand_margin",
                  "obstacle_body_null_distance", "progress_joint_floor")
        for name in nonneg:
            v = getattr(self, name)
            if not math.isfinite(v) or v < 0:
                raise ConfigError(f"PmpConfig.{name}: expected a finite value >= 0, got {v}")
        if self.tau > self.max_tau:
            raise ConfigError(f"PmpConfig.tau: {self.tau} s exceeds max_tau {self.max_tau} s")
        if self.time_parametrisation not in TIME_PARAMETRISATIONS:
            raise ConfigError(
                f"PmpConfig.time_parametrisation: {self.time_parametrisation!r}; "
                f"valid: {list(TIME_PARAMETRISATIONS)}"
            )
        for name, n in (("stiffness", 3), ("curl_axis", 3), ("arm_admittance", 7),
                        ("trunk_admittance", 3)):
            v = getattr(self, name)
            if len(v) != n or not all(math.isfinite(x) for x in v):
                raise ConfigError(f"PmpConfig.{name}: expected {n} finite values, got {v}")
        if min(self.stiffness) <= 0:
            raise ConfigError(f"PmpConfig.stiffness: expected values > 0, got {self.stiffness}")
        for name in ("arm_admittance", "trunk_admittance"):
            if min(getattr(self, name)) < 0:
                raise ConfigError(f"PmpConfig.{name}: admittances must be >= 0")
        if max(self.arm_admittance) <= 0:
            raise ConfigError("PmpConfig.arm_admittance: at least one arm joint must move")
        if self.step_growth < 1.0 or self.max_step < self.initial_step:
            raise ConfigError("PmpConfig: need step_growth >= 1 and max_step >= initial_step")
        for name in ("max_steps", "stall_steps", "settle_max_steps", "posture_memory_attempts"):
            if getattr(self, name) < 1:
                raise ConfigError(f"PmpConfig.{name}: expected >= 1")
        if self.posture_memory_size < 0:
            raise ConfigError("PmpConfig.posture_memory_size: expected >= 0")
        if not 0 < self.boundary_fraction < 1:
            raise ConfigError("PmpConfig.boundary_fraction: expected in (0, 1)")
        if not 0 < self.torque_limit_margin <= 1:
            raise ConfigError("PmpConfig.torque_limit_margin: expected in (0, 1]")
