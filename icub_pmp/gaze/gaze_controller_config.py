"""GazeControllerConfig: parameters of the gaze controller core (= ROS parameters of the
``gaze_controller`` node, ``config/gaze_controller.yaml``)."""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["GazeControllerConfig"]


@dataclasses.dataclass(frozen=True)
class GazeControllerConfig(ConfigBase):
    """Defaults from iKinGazeCtrl (robotology/icub-main ``src/modules/iKinGazeCtrl``).

    Attributes:
        neck_traj_time: T of the neck's minimum-jerk controller [s] (iKinGazeCtrl
            ``trajectory_time::neck`` 0.75 s; must exceed ``eyes_traj_time``).
        eyes_traj_time: T of the eyes' minimum-jerk controller [s] (``trajectory_time::eyes``
            0.25 s).
        period: controller period = sample time of the published trajectories [s]
            (iKinGazeCtrl's controller thread runs at 10 ms).
        min_distance: nearest fixation point, from the eyes' midpoint [m] (vergence grows as
            the point nears: 2 atan(0.034 / d), 50 deg, its limit, at 0.073 m).
        fixation_tolerance: a solution whose predicted fixation error (angle between an
            optical axis and the direction to the point) exceeds this is not exact [rad].
        rest_weight: weight of the neck's rest posture (0, 0, 0) against the head-centre
            pointing error (the cost of iKinGazeCtrl's HeadCenter_NLP) [-].
        rest_joint_weights: relative weights of neck pitch, roll, yaw in the rest term [-]
            (iKinGazeCtrl: 1, 1, 1; the roll weighs more here to keep the head upright).
        neck_activation_angle: while tracking, the neck is re-solved only when the target is
            this far from the current neck target, seen from the head centre [rad]
            (iKinGazeCtrl ``NECKSOLVER_ACTIVATIONANGLE`` 2.5 deg); the eyes always follow.
        joint_limit_margin: joint targets stay this far inside the joint limits [rad].
        settle_tolerance: a trajectory ends when neck and eyes are this close to their
            targets [rad].
        max_duration_factor: and never lasts longer than this many ``neck_traj_time`` [-].
        max_neck_traj_time: the longest neck time a request may ask for [s] (a look_at
            asking 1e9 s rolled out 3e11 samples inside the service call).
    """

    neck_traj_time: float = 0.75
    eyes_traj_time: float = 0.25
    period: float = 0.01
    min_distance: float = 0.1
    fixation_tolerance: float = 1.0e-3
    rest_weight: float = 1.0e-3
    rest_joint_weights: tuple[float, ...] = (1.0, 10.0, 1.0)
    neck_activation_angle: float = math.radians(2.5)
    joint_limit_margin: float = 0.01
    settle_tolerance: float = 1.0e-4
    max_duration_factor: float = 3.0
    max_neck_traj_time: float = 60.0

    def validate(self) -> None:
        """Check ranges (raise :class:`ConfigError` naming the field)."""
        for name in ("period", "min_distance", "fixation_tolerance", "settle_tolerance",
                     "eyes_traj_time"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ConfigError(f"GazeControllerConfig.{name} must be > 0 and finite, got {v!r}")
        for name in ("rest_weight", "neck_activation_angle", "joint_limit_margin"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ConfigError(
                    f"GazeControllerConfig.{name} must be >= 0 and finite, got {v!r}")
        w = self.rest_joint_weights
        if len(w) != 3 or not all(math.isfinite(x) and x >= 0 for x in w):
            raise ConfigError(f"GazeControllerConfig.rest_joint_weights: expected 3 finite "
                              f"values >= 0 (pitch, roll, yaw), got {list(w)}")
        if self.eyes_traj_time < 10 * self.period:
            raise ConfigError(
                f"GazeControllerConfig.eyes_traj_time must be >= 10 * period = "
                f"{10 * self.period} s, got {self.eyes_traj_time!r}")
        if not (math.isfinite(self.neck_traj_time) and self.neck_traj_time > self.eyes_traj_time):
            raise ConfigError(
                f"GazeControllerConfig.neck_traj_time must exceed eyes_traj_time = "
                f"{self.eyes_traj_time} s (iKinGazeCtrl: Tneck > Teyes), got "
                f"{self.neck_traj_time!r}")
        if self.joint_limit_margin > 0.1:
            raise ConfigError(f"GazeControllerConfig.joint_limit_margin must be <= 0.1 rad, got "
                              f"{self.joint_limit_margin!r}")
        if not (math.isfinite(self.max_duration_factor) and self.max_duration_factor >= 1.5):
            raise ConfigError(
                f"GazeControllerConfig.max_duration_factor must be >= 1.5 (the min-jerk "
                f"transient lasts 1.5 T), got {self.max_duration_factor!r}")
        if not (math.isfinite(self.max_neck_traj_time)
                and self.max_neck_traj_time >= self.neck_traj_time):
            raise ConfigError(
                f"GazeControllerConfig.max_neck_traj_time must be finite and >= "
                f"neck_traj_time = {self.neck_traj_time} s, got {self.max_neck_traj_time!r}")
