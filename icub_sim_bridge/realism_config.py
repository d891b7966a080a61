"""RealismConfig: the imperfections of the real iCub that the simulator adds (``realism.*``).

The ROS parameters are ``realism.<field>`` (``config/sim_bridge.yaml`` nests them under
``realism:``). ``preset`` picks a set of values: ``ideal`` (every imperfection off: the
simulator behaves exactly as without this module) or ``icub`` (the figures below). Every
numeric field may override its preset value; ``-1`` (the default of each field) means "the
preset's value". :meth:`RealismConfig.resolved` gives the figures in use as a
:class:`RealismSettings`.

Sources of the ``icub`` figures (docs/references.md, docs/decisions/0035):

- FT white noise: the STRAIN board's resolution, 0.25 N (Fx, Fy, Fz) and 0.005 N m (Tx, Ty;
  0.004 Tz) per count (icub-tech documentation ``ft_sensors``), as the 1-sigma noise of each
  1 ms sample. Start-up offset: uniform in +-2 N / +-0.1 N m per axis, drawn per sensor --
  chosen larger than the residual means of the force paper's Table 1 (Fumagalli et al.,
  up to 0.87 N / 0.06 N m on the arms after calibration), so calibration is needed as
  wholeBodyDynamics needs it. Drift: a temperature-like warm-up ``A (1 - exp(-t / T))``
  with ``A`` uniform in +-0.5 N / +-0.02 N m per axis and ``T`` = 300 s (chosen: no public
  figure). Bandwidth: a first-order low-pass at 50 Hz (chosen; the STRAIN publishes at 100 Hz).
- Model mismatch: masses uniform within +-10 %, centres of mass within +-1 cm per axis,
  inertias scaled with the mass (the issue's figures: "the rigid-body model is wrong the way
  a CAD model is wrong").
- Joint friction per group (torso, arm, neck+eyes): Coulomb, stiction (break-away) and
  viscous terms. No public torque figure exists (robots-configuration gives the firmware's
  friction compensation in PWM units only); chosen near 1 % of the group's largest torque
  limit (config/robot.yaml).
- Actuation: a one-sample (1 ms) delay between command and applied torque (the controller
  board's command is applied at the next 1 ms cycle).
- Encoders: 12-bit absolute joint encoders, 2 pi / 4096 rad per count (assumed: the iCub's
  AEA magnetic encoders); velocity noise 0.005 rad/s (the firmware differentiates encoders).
- IMU: accelerometer noise 0.02 m/s^2 and bias +-0.05 m/s^2, gyro noise 0.005 rad/s and bias
  +-0.01 rad/s per axis (assumed typical MEMS figures).
- Cameras: pixel noise 2 grey levels (1-sigma), focal length +-2 %, principal point +-3 px,
  extrinsic rotation up to 1 deg (chosen: the real calibrations of icubEyes.ini differ from
  the nominal model by far more, ICUB_FACTS); ``camera_info`` keeps the nominal values.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Mapping, NamedTuple

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["RealismConfig", "RealismSettings", "PRESETS", "PARAMETER_PREFIX"]

PARAMETER_PREFIX = "realism."


class RealismSettings(NamedTuple):
    """The imperfections in use (a preset with its overrides); 0 = that imperfection off."""

    seed: int
    ft_force_noise_std: float  # [N] per axis, per sample
    ft_torque_noise_std: float  # [N m]
    ft_force_offset: float  # [N] half-range of the uniform start-up offset per axis
    ft_torque_offset: float  # [N m]
    ft_force_drift: float  # [N] half-range of the warm-up drift amplitude per axis
    ft_torque_drift: float  # [N m]
    ft_drift_time_constant: float  # [s]
    ft_bandwidth_hz: float  # [Hz] first-order low-pass (0 = none)
    mass_error: float  # [-] half-range of the relative mass error per link
    com_error: float  # [m] half-range of the COM shift per axis
    friction_coulomb: tuple[float, float, float]  # [N m] torso, arm, neck+eyes
    friction_stiction: tuple[float, float, float]  # [N m] break-away torque
    friction_viscous: tuple[float, float, float]  # [N m s/rad] added to the joint damping
    friction_stribeck_velocity: float  # [rad/s]
    actuator_delay_steps: int  # [steps] command -> applied torque
    actuator_bandwidth_hz: float  # [Hz] first-order torque bandwidth (0 = none)
    encoder_resolution: float  # [rad] per count (0 = exact)
    velocity_noise_std: float  # [rad/s]
    imu_acc_noise_std: float  # [m/s^2]
    imu_acc_bias: float  # [m/s^2] half-range per axis
    imu_gyro_noise_std: float  # [rad/s]
    imu_gyro_bias: float  # [rad/s]
    camera_noise_std: float  # [grey levels]
    camera_focal_error: float  # [-] half-range of the relative focal-length error
    camera_principal_error: float  # [px] half-range of the principal-point shift per axis
    camera_rotation_error_deg: float  # [deg] largest extrinsic rotation

    @property
    def active(self) -> bool:
        """Whether any imperfection is on."""
        return (self.ft_active or self.friction_active or self.camera_active
                or any((self.mass_error, self.com_error, self.actuator_delay_steps,
                        self.actuator_bandwidth_hz, self.encoder_resolution,
                        self.velocity_noise_std, self.imu_acc_noise_std, self.imu_acc_bias,
                        self.imu_gyro_noise_std, self.imu_gyro_bias)))

    @property
    def ft_active(self) -> bool:
        """Whether the FT sensors differ from the ideal ones."""
        return any((self.ft_force_noise_std, self.ft_torque_noise_std, self.ft_force_offset,
                    self.ft_torque_offset, self.ft_force_drift, self.ft_torque_drift,
                    self.ft_bandwidth_hz))

    @property
    def friction_active(self) -> bool:
        """Whether joint friction is added."""
        return any(self.friction_coulomb + self.friction_stiction + self.friction_viscous)

    @property
    def camera_active(self) -> bool:
        """Whether the cameras differ from the nominal ones."""
        return any((self.camera_noise_std, self.camera_focal_error,
                    self.camera_principal_error, self.camera_rotation_error_deg))


_IDEAL = RealismSettings(
    seed=0, ft_force_noise_std=0.0, ft_torque_noise_std=0.0, ft_force_offset=0.0,
    ft_torque_offset=0.0, ft_force_drift=0.0, ft_torque_drift=0.0,
    ft_drift_time_constant=300.0, ft_bandwidth_hz=0.0, mass_error=0.0, com_error=0.0,
    friction_coulomb=(0.0, 0.0, 0.0), friction_stiction=(0.0, 0.0, 0.0),
    friction_viscous=(0.0, 0.0, 0.0), friction_stribeck_velocity=0.01,
    actuator_delay_steps=0, actuator_bandwidth_hz=0.0, encoder_resolution=0.0,
    velocity_noise_std=0.0, imu_acc_noise_std=0.0, imu_acc_bias=0.0, imu_gyro_noise_std=0.0,
    imu_gyro_bias=0.0, camera_noise_std=0.0, camera_focal_error=0.0,
    camera_principal_error=0.0, camera_rotation_error_deg=0.0)

_ICUB = RealismSettings(
    seed=0, ft_force_noise_std=0.25, ft_torque_noise_std=0.005, ft_force_offset=2.0,
    ft_torque_offset=0.1, ft_force_drift=0.5, ft_torque_drift=0.02,
    ft_drift_time_constant=300.0, ft_bandwidth_hz=50.0, mass_error=0.10, com_error=0.01,
    friction_coulomb=(0.4, 0.15, 0.05), friction_stiction=(0.6, 0.25, 0.08),
    friction_viscous=(0.3, 0.1, 0.02), friction_stribeck_velocity=0.01,
    actuator_delay_steps=1, actuator_bandwidth_hz=0.0,
    encoder_resolution=2.0 * math.pi / 4096.0, velocity_noise_std=0.005,
    imu_acc_noise_std=0.02, imu_acc_bias=0.05, imu_gyro_noise_std=0.005, imu_gyro_bias=0.01,
    camera_noise_std=2.0, camera_focal_error=0.02, camera_principal_error=3.0,
    camera_rotation_error_deg=1.0)

#: preset name -> its figures (module doc)
PRESETS: dict[str, RealismSettings] = {"ideal": _IDEAL, "icub": _ICUB}


@dataclasses.dataclass(frozen=True)
class RealismConfig(ConfigBase):
    """The ``realism.*`` parameters of ``sim_bridge`` (module doc; -1 = the preset's value).

    Attributes:
        preset: ideal (no imperfection: today's simulator) | icub (the real robot's).
        seed: random seed of every drawn imperfection (same seed, same robot) [-].
        ft_force_noise_std: FT white noise per force axis [N] (-1 = preset).
        ft_torque_noise_std: FT white noise per torque axis [N m] (-1 = preset).
        ft_force_offset: FT start-up offset, uniform half-range per force axis [N].
        ft_torque_offset: FT start-up offset, uniform half-range per torque axis [N m].
        ft_force_drift: FT warm-up drift amplitude half-range per force axis [N].
        ft_torque_drift: FT warm-up drift amplitude half-range per torque axis [N m].
        ft_drift_time_constant: time constant of the FT warm-up drift [s].
        ft_bandwidth_hz: first-order low-pass of the FT sensors [Hz] (0 = none).
        mass_error: relative link-mass error half-range (0.1 = +-10 %) [-].
        com_error: centre-of-mass shift half-range per axis [m].
        friction_coulomb: Coulomb friction torso, arm, neck+eyes [N m] (-1 each = preset).
        friction_stiction: break-away (static) friction torso, arm, neck+eyes [N m].
        friction_viscous: viscous friction added to the joint damping [N m s/rad].
        friction_stribeck_velocity: speed below which stiction applies [rad/s].
        actuator_delay_steps: physics steps between a command and its torque [-].
        actuator_bandwidth_hz: first-order torque bandwidth [Hz] (0 = none).
        encoder_resolution: joint encoder resolution [rad] (0 = exact).
        velocity_noise_std: joint velocity noise [rad/s].
        imu_acc_noise_std: accelerometer white noise per axis [m/s^2].
        imu_acc_bias: accelerometer bias half-range per axis [m/s^2].
        imu_gyro_noise_std: gyro white noise per axis [rad/s].
        imu_gyro_bias: gyro bias half-range per axis [rad/s].
        camera_noise_std: image noise [grey levels].
        camera_focal_error: relative focal-length error half-range [-].
        camera_principal_error: principal-point shift half-range [px].
        camera_rotation_error_deg: largest camera extrinsic rotation error [deg].
    """

    preset: str = "ideal"
    seed: int = 0
    ft_force_noise_std: float = -1.0
    ft_torque_noise_std: float = -1.0
    ft_force_offset: float = -1.0
    ft_torque_offset: float = -1.0
    ft_force_drift: float = -1.0
    ft_torque_drift: float = -1.0
    ft_drift_time_constant: float = -1.0
    ft_bandwidth_hz: float = -1.0
    mass_error: float = -1.0
    com_error: float = -1.0
    friction_coulomb: tuple[float, ...] = (-1.0, -1.0, -1.0)
    friction_stiction: tuple[float, ...] = (-1.0, -1.0, -1.0)
    friction_viscous: tuple[float, ...] = (-1.0, -1.0, -1.0)
    friction_stribeck_velocity: float = -1.0
    actuator_delay_steps: int = -1
    actuator_bandwidth_hz: float = -1.0
    encoder_resolution: float = -1.0
    velocity_noise_std: float = -1.0
    imu_acc_noise_std: float = -1.0
    imu_acc_bias: float = -1.0
    imu_gyro_noise_std: float = -1.0
    imu_gyro_bias: float = -1.0
    camera_noise_std: float = -1.0
    camera_focal_error: float = -1.0
    camera_principal_error: float = -1.0
    camera_rotation_error_deg: float = -1.0

    # ------------------------------------------------------------------ ROS names: realism.*
    @classmethod
    def field_names(cls) -> list[str]:
        """The ROS parameter names: ``realism.<field>``."""
        return [PARAMETER_PREFIX + f.name for f in dataclasses.fields(cls)]

    @classmethod
    def from_dict(cls, params: Mapping[str, Any], *, ignore_unknown: bool = False
                  ) -> RealismConfig:
        """Build from ``{"realism.<field>": value}`` (unknown keys rejected by name unless
        ``ignore_unknown``)."""
        plain = {f.name for f in dataclasses.fields(cls)}
        own = {k[len(PARAMETER_PREFIX):]: v for k, v in params.items()
               if k.startswith(PARAMETER_PREFIX)}
        unknown = sorted(k for k in params if not (k.startswith(PARAMETER_PREFIX)
                                                    and k[len(PARAMETER_PREFIX):] in plain))
        if unknown and not ignore_unknown:
            raise ConfigError(f"RealismConfig: unknown parameter(s) {unknown}; valid: "
                              f"{sorted(cls.field_names())}")
        return ConfigBase.from_dict.__func__(cls, {k: v for k, v in own.items() if k in plain},
                                             ignore_unknown=True)

    def to_dict(self) -> dict[str, Any]:
        """``{"realism.<field>": value}`` (tuples as lists, for ROS parameters)."""
        return {PARAMETER_PREFIX + k: v for k, v in super().to_dict().items()}

    # ------------------------------------------------------------------ checks
    def validate(self) -> None:
        """The preset exists; overrides are -1 (preset) or >= 0; friction has 3 groups."""
        if self.preset not in PRESETS:
            raise ConfigError(f"RealismConfig.preset: {self.preset!r} is not one of "
                              f"{sorted(PRESETS)}")
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if f.name in ("preset", "seed"):
                continue
            if isinstance(v, tuple):
                if len(v) != 3 or not all(math.isfinite(x) and (x >= 0.0 or x == -1)
                                          for x in v):
                    raise ConfigError(f"RealismConfig.{f.name}: expected 3 values (torso, arm, "
                                      f"neck+eyes), each -1 (preset) or >= 0, got {list(v)}")
            elif not math.isfinite(v) or (v < 0.0 and v != -1):
                raise ConfigError(f"RealismConfig.{f.name}: expected -1 (the preset's value)"
                                  f" or a finite value >= 0, got {v}")
        if self.seed < 0:
            raise ConfigError(f"RealismConfig.seed: expected >= 0, got {self.seed}")
        s = self.resolved()
        if s.ft_drift_time_constant <= 0.0:
            raise ConfigError("RealismConfig.ft_drift_time_constant: expected > 0 s, got "
                              f"{s.ft_drift_time_constant}")
        if s.mass_error >= 1.0:
            raise ConfigError(f"RealismConfig.mass_error: expected < 1 (a relative error), "
                              f"got {s.mass_error}")
        if s.friction_stribeck_velocity <= 0.0:
            raise ConfigError("RealismConfig.friction_stribeck_velocity: expected > 0 rad/s")

    def resolved(self) -> RealismSettings:
        """The figures in use: the preset's, overridden by every field not -1 / empty."""
        base = PRESETS[self.preset]
        values = {}
        for name in RealismSettings._fields:
            v = getattr(self, name)
            if name == "seed":
                values[name] = int(v)
            elif isinstance(v, tuple):
                values[name] = tuple(getattr(base, name)[i] if x == -1 else float(x)
                                     for i, x in enumerate(v))
            elif v == -1:
                values[name] = getattr(base, name)
            else:
                values[name] = type(getattr(base, name))(v)
        return RealismSettings(**values)
