"""RobotSpec: the robot facts of ``config/robot.yaml`` (joint sets, torque ratings, postures)."""

from __future__ import annotations

import dataclasses
import math
from functools import lru_cache
from pathlib import Path
from types import MappingProxyType
from typing import Mapping

import yaml

from icub_pmp.config import config_dir
from icub_pmp.errors import ConfigError, ModelError, UnknownName

__all__ = ["RobotSpec", "urdf_path", "HANDS"]

HANDS = ("left", "right")


@dataclasses.dataclass(frozen=True)
class RobotSpec:
    """Joint sets, torque limits [N m] and named postures [rad] of the simulated iCub."""

    model_name: str
    torso_joints: tuple[str, ...]
    left_arm_joints: tuple[str, ...]
    right_arm_joints: tuple[str, ...]
    neck_joints: tuple[str, ...]
    eye_joints: tuple[str, ...]
    hand_frames: Mapping[str, str]
    arm_ft_frames: Mapping[str, str]
    root_frame: str
    torque_limits: Mapping[str, float]
    postures: Mapping[str, Mapping[str, float]]
    velocity_limits: Mapping[str, float] = dataclasses.field(default_factory=dict)
    acceleration_limits: Mapping[str, float] = dataclasses.field(default_factory=dict)

    @classmethod
    def load(cls, path: str | Path | None = None) -> "RobotSpec":
        """Read ``config/robot.yaml`` (or ``path``); postures are converted from deg to rad."""
        path = Path(path) if path else config_dir() / "robot.yaml"
        return _load_cached(str(path))

    @property
    def upper_body_joints(self) -> tuple[str, ...]:
        """Torso, left arm, right arm, neck: the URDF joints actuated in the simulation."""
        return self.torso_joints + self.left_arm_joints + self.right_arm_joints + self.neck_joints

    @property
    def actuated_joints(self) -> tuple[str, ...]:
        """Every actuated joint of the simulated robot: upper body then eyes."""
        return self.upper_body_joints + self.eye_joints

    def arm_joints(self, hand: str) -> tuple[str, ...]:
        """The 7 arm joints of ``hand`` ('left' or 'right')."""
        if hand == "left":
            return self.left_arm_joints
        if hand == "right":
            return self.right_arm_joints
        raise UnknownName("hand", hand, HANDS)

    def hand_frame(self, hand: str) -> str:
        """URDF frame of the hand end effector (``l_hand_dh_frame`` / ``r_hand_dh_frame``)."""
        if hand not in self.hand_frames:
            raise UnknownName("hand", hand, self.hand_frames)
        return self.hand_frames[hand]

    def posture(self, name: str) -> dict[str, float]:
        """Named posture as {joint: rad} over all actuated joints (unlisted joints are 0)."""
        if name not in self.postures:
            raise UnknownName("posture", name, self.postures)
        q = {j: 0.0 for j in self.actuated_joints}
        q.update(self.postures[name])
        return q

    def torque_limit(self, joint: str) -> float:
        """Peak torque of ``joint`` [N m]."""
        if joint not in self.torque_limits:
            raise UnknownName("joint", joint, self.torque_limits)
        return self.torque_limits[joint]

    def velocity_limit(self, joint: str) -> float:
        """Largest joint speed of ``joint`` [rad/s] (``velocity_limits``: per joint or
        ``default``)."""
        return _rate_limit(self.velocity_limits, joint, self.actuated_joints, "velocity")

    def acceleration_limit(self, joint: str) -> float:
        """Largest joint acceleration of ``joint`` [rad/s^2] (``acceleration_limits``)."""
        return _rate_limit(self.acceleration_limits, joint, self.actuated_joints,
                           "acceleration")


def _rate_limit(limits: Mapping[str, float], joint: str, joints: tuple[str, ...],
                what: str) -> float:
    if joint not in joints:
        raise UnknownName("joint", joint, joints)
    value = limits.get(joint, limits.get("default"))
    if value is None:
        raise ConfigError(f"robot spec: no {what} limit for {joint!r} and no default")
    return value


@lru_cache(maxsize=8)
def _load_cached(path: str) -> RobotSpec:
    try:
        d = yaml.safe_load(Path(path).read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError(f"cannot read robot spec {path}: {exc}") from exc
    names = {f.name for f in dataclasses.fields(RobotSpec)}
    optional = {"velocity_limits", "acceleration_limits"}
    unknown = sorted(set(d) - names)
    missing = sorted(names - optional - set(d))
    if unknown or missing:
        raise ConfigError(f"{path}: unknown keys {unknown}, missing keys {missing}")
    postures = {
        name: MappingProxyType({j: math.radians(float(v)) for j, v in (p or {}).items()})
        for name, p in d["postures"].items()
    }
    spec = RobotSpec(
        model_name=str(d["model_name"]),
        torso_joints=tuple(d["torso_joints"]),
        left_arm_joints=tuple(d["left_arm_joints"]),
        right_arm_joints=tuple(d["right_arm_joints"]),
        neck_joints=tuple(d["neck_joints"]),
        eye_joints=tuple(d["eye_joints"]),
        hand_frames=MappingProxyType(dict(d["hand_frames"])),
        arm_ft_frames=MappingProxyType(dict(d["arm_ft_frames"])),
        root_frame=str(d["root_frame"]),
        torque_limits=MappingProxyType({k: float(v) for k, v in d["torque_limits"].items()}),
        postures=MappingProxyType(postures),
        velocity_limits=_rad_limits(d.get("velocity_limits"), path, "velocity_limits"),
        acceleration_limits=_rad_limits(d.get("acceleration_limits"), path,
                                        "acceleration_limits"),
    )
    for key in ("velocity_limits", "acceleration_limits"):
        bad = sorted(set(getattr(spec, key)) - set(spec.actuated_joints) - {"default"})
        if bad:
            raise ConfigError(f"{path}: {key} names unknown joints {bad} (joints or 'default')")
    missing_tau = sorted(set(spec.actuated_joints) - set(spec.torque_limits))
    if missing_tau:
        raise ConfigError(f"{path}: torque_limits missing for {missing_tau}")
    for name, p in postures.items():
        bad = sorted(set(p) - set(spec.actuated_joints))
        if bad:
            raise ConfigError(f"{path}: posture {name!r} names unknown joints {bad}")
    return spec


def _rad_limits(d: Mapping | None, path: str, key: str) -> Mapping[str, float]:
    """{joint or 'default': limit} in deg/s or deg/s^2 -> rad units, each finite and > 0."""
    out = {}
    for k, v in (d or {}).items():
        try:
            value = float(v)
        except (TypeError, ValueError):
            value = math.nan
        if not math.isfinite(value) or value <= 0:
            raise ConfigError(f"{path}: {key}.{k} must be a number > 0, got {v!r}")
        out[str(k)] = math.radians(value)
    return MappingProxyType(out)


def urdf_path(model_name: str) -> Path:
    """Path of the icub-models URDF ``model_name`` (e.g. ``iCubGazeboV2_7``)."""
    try:
        import icub_models
    except ImportError as exc:  # pragma: no cover - installed by make env
        raise ModelError("the icub-models package is not installed (run make env)") from exc
    names = icub_models.get_robot_names()
    if model_name not in names:
        raise UnknownName("icub-models model", model_name, names)
    return Path(icub_models.get_model_file(model_name))
