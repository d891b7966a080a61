"""WrenchEstimatorConfig: parameters of the wrench estimator (= ROS parameters of the
``wrench_estimator`` node, ``config/wrench_estimator.yaml``)."""

from __future__ import annotations

import dataclasses

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["WrenchEstimatorConfig", "FT_CONVENTIONS", "GRAVITY_SOURCES"]

#: "parent_on_child": the FT reports the wrench the proximal side (shoulder) applies to the
#: distal side (upper arm); "child_on_parent": the opposite (Gazebo's ``child_to_parent``).
FT_CONVENTIONS = ("parent_on_child", "child_on_parent")
GRAVITY_SOURCES = ("model", "imu")


@dataclasses.dataclass(frozen=True)
class WrenchEstimatorConfig(ConfigBase):
    """Filtering, contact detection, RFRR learning and model options of the estimator."""

    rate_hz: float = 1000.0  # nominal joint-state rate [Hz]
    sample_every: int = 1  # process one joint-state sample in N (runs at rate_hz / N)
    ft_convention: str = "child_on_parent"  # sign convention of the /ft/* wrenches
    velocity_cutoff_hz: float = 0.0  # low-pass on measured joint velocity [Hz], 0 = as measured
    acceleration_cutoff_hz: float = 30.0  # low-pass on the differentiated velocity [Hz]
    ft_cutoff_hz: float = 0.0  # low-pass on the FT wrenches [Hz], 0 = none
    gravity_source: str = "model"  # "model" (fixed mainstay) or "imu" (head accelerometer)
    imu_frame: str = "head_imu_0"  # URDF frame of the /imu measurements
    imu_cutoff_hz: float = 3.0  # low-pass on the IMU acceleration [Hz] (wbd default 3 Hz)
    ft_offset_samples: int = 0  # average (measured - model) over the first N samples, 0 = off
    calibration_samples: int = 500  # FT offset calibration (~/calibrate): the last N samples
    calibration_motion_tolerance: float = 0.01  # joint spread over them that refuses it [rad]
    calibrate_at_startup: bool = False  # calibrate once the first still N samples are in
    calibrate_at_startup_within: float = 10.0  # ... within this much time after the start [s]
    contact_force_on: float = 1.0  # external force norm that sets the contact flag [N]
    contact_force_off: float = 0.5  # external force norm that clears it [N]
    contact_min_samples: int = 5  # consecutive samples needed to switch the flag
    rfrr_enabled: bool = False  # add the learnt residual to the model's internal wrench
    rfrr_learning: bool = False  # update the RFRR on contact-free samples
    rfrr_features: int = 200  # number D of random features
    rfrr_bandwidth: float = 1.5  # RBF kernel width sigma (scaled input units)
    rfrr_ridge: float = 0.01  # ridge regulariser lambda
    rfrr_forgetting: float = 1.0  # RLS forgetting factor beta in (0, 1]
    rfrr_position_scale: float = 1.0  # input scale of joint positions [rad]
    rfrr_velocity_scale: float = 2.0  # input scale of joint velocities [rad/s]
    rfrr_acceleration_scale: float = 20.0  # input scale of joint accelerations [rad/s^2]
    rfrr_update_every: int = 1  # learn from one sample in N (time budget at large D)
    rfrr_seed: int = 0  # random seed of the features
    mismatch_link: str = ""  # URDF link whose mass the estimator's model scales ("" = none)
    mismatch_scale: float = 1.0  # the scale factor (a deliberate model mismatch)
    require_same_stamp: bool = True  # node: joint states and FT must carry the same stamp
    stale_timeout: float = 0.1  # node: FT older than this (vs joint states) is stale [s]
    publish_every: int = 1  # node: wrench/contact/predicted-FT topics every N samples
    enabled: bool = True  # node: false = no sample processed, nothing published (stopped)

    @property
    def sample_rate_hz(self) -> float:
        """Rate of the samples the estimator processes [Hz] (filters are designed for it)."""
        return self.rate_hz / self.sample_every

    def validate(self) -> None:
        """Check ranges and choices (raises :class:`ConfigError` naming the field)."""
        if self.rate_hz <= 0:
            raise ConfigError(f"rate_hz must be > 0, got {self.rate_hz}")
        if self.ft_convention not in FT_CONVENTIONS:
            raise ConfigError(f"ft_convention {self.ft_convention!r}; valid: {FT_CONVENTIONS}")
        if self.gravity_source not in GRAVITY_SOURCES:
            raise ConfigError(
                f"gravity_source {self.gravity_source!r}; valid: {GRAVITY_SOURCES}"
            )
        if self.sample_every < 1:
            raise ConfigError(f"sample_every must be >= 1, got {self.sample_every}")
        nyquist = self.sample_rate_hz / 2
        for name in ("velocity_cutoff_hz", "acceleration_cutoff_hz", "ft_cutoff_hz",
                     "imu_cutoff_hz"):
            v = getattr(self, name)
            if not 0 <= v < nyquist:
                raise ConfigError(
                    f"{name} must be in [0, {nyquist}) (Nyquist of rate_hz / sample_every), "
                    f"got {v}")
        if not 0 <= self.contact_force_off < self.contact_force_on:
            raise ConfigError(
                "need 0 <= contact_force_off < contact_force_on, got "
                f"{self.contact_force_off}, {self.contact_force_on}"
            )
        for name in ("contact_min_samples", "rfrr_features", "rfrr_update_every",
                     "publish_every"):
            if getattr(self, name) < 1:
                raise ConfigError(f"{name} must be >= 1, got {getattr(self, name)}")
        if not self.calibrate_at_startup_within > 0:
            raise ConfigError("calibrate_at_startup_within must be > 0 s, got "
                              f"{self.calibrate_at_startup_within}")
        if self.calibration_samples < 1:
            raise ConfigError(f"calibration_samples must be >= 1, got {self.calibration_samples}")
        if not self.calibration_motion_tolerance > 0:
            raise ConfigError("calibration_motion_tolerance must be > 0 rad, got "
                              f"{self.calibration_motion_tolerance}")
        if self.ft_offset_samples < 0:
            raise ConfigError(f"ft_offset_samples must be >= 0, got {self.ft_offset_samples}")
        for name in ("rfrr_bandwidth", "rfrr_ridge", "rfrr_position_scale",
                     "rfrr_velocity_scale", "rfrr_acceleration_scale", "stale_timeout"):
            if not getattr(self, name) > 0:
                raise ConfigError(f"{name} must be > 0, got {getattr(self, name)}")
        if not 0 < self.rfrr_forgetting <= 1:
            raise ConfigError(f"rfrr_forgetting must be in (0, 1], got {self.rfrr_forgetting}")
        if not self.mismatch_scale > 0:
            raise ConfigError(f"mismatch_scale must be > 0, got {self.mismatch_scale}")
