"""ImpedanceControllerConfig: parameters of the joint impedance controller (= ROS parameters of
the ``impedance_controller`` node, ``config/impedance_controller.yaml``).

Gains are given per joint group and shared by both arms: ``*_torso`` (torso_pitch, torso_roll,
torso_yaw), ``*_arm`` (shoulder_pitch, shoulder_roll, shoulder_yaw, elbow, wrist_prosup,
wrist_pitch, wrist_yaw), ``*_neck`` (pitch, roll, yaw), ``*_eyes`` (tilt, version, vergence).
"""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["ImpedanceControllerConfig", "MODES", "FEEDFORWARDS", "GROUP_SIZES"]

#: position: stiff set-point tracking; impedance: compliant (eq 6); torque: tau_d = feed-forward
#: (gravity + trajectory efforts) with no position feedback.
MODES = ("position", "impedance", "torque")
#: model feed-forward added to eq 6: none, gravity g(q), or inverse dynamics RNEA(q, qd_d, qdd_d)
FEEDFORWARDS = ("none", "gravity", "inverse_dynamics")
GROUP_SIZES = {"torso": 3, "arm": 7, "neck": 3, "eyes": 3}


@dataclasses.dataclass(frozen=True)
class ImpedanceControllerConfig(ConfigBase):
    """Modes, gains and safety limits of the 1 kHz joint controller."""

    rate_hz: float = 1000.0  # control rate [Hz] (one step per joint state in lockstep)
    mode: str = "impedance"  # position | impedance | torque
    feedforward: str = "gravity"  # none | gravity | inverse_dynamics
    # stiff position tracking gains: K [N m/rad], D [N m s/rad]
    position_stiffness_torso: tuple[float, ...] = (400.0, 400.0, 300.0)
    position_stiffness_arm: tuple[float, ...] = (300.0, 300.0, 200.0, 200.0, 60.0, 40.0, 40.0)
    position_stiffness_neck: tuple[float, ...] = (60.0, 60.0, 60.0)
    position_stiffness_eyes: tuple[float, ...] = (5.0, 5.0, 5.0)
    position_damping_torso: tuple[float, ...] = (20.0, 20.0, 15.0)
    position_damping_arm: tuple[float, ...] = (10.0, 10.0, 8.0, 8.0, 2.0, 1.5, 1.5)
    position_damping_neck: tuple[float, ...] = (2.0, 2.0, 2.0)
    position_damping_eyes: tuple[float, ...] = (0.05, 0.05, 0.05)
    # compliant impedance gains (eq 6)
    impedance_stiffness_torso: tuple[float, ...] = (100.0, 100.0, 60.0)
    impedance_stiffness_arm: tuple[float, ...] = (30.0, 30.0, 20.0, 20.0, 5.0, 5.0, 5.0)
    impedance_stiffness_neck: tuple[float, ...] = (20.0, 20.0, 20.0)
    impedance_stiffness_eyes: tuple[float, ...] = (5.0, 5.0, 5.0)
    impedance_damping_torso: tuple[float, ...] = (5.0, 5.0, 4.0)
    impedance_damping_arm: tuple[float, ...] = (2.0, 2.0, 1.5, 1.5, 0.3, 0.3, 0.3)
    impedance_damping_neck: tuple[float, ...] = (1.0, 1.0, 1.0)
    impedance_damping_eyes: tuple[float, ...] = (0.05, 0.05, 0.05)
    # joint torque PID on e = tau_hat - tau_d (eqs 4-5)
    torque_loop: bool = True  # close the loop on the estimated joint torques
    torque_kp: float = 0.0  # [N m / N m]
    torque_ki: float = 20.0  # [1/s]
    torque_kd: float = 0.0  # [s]
    torque_kff: float = 1.0  # feed-forward gain on tau_d
    torque_integral_limit: float = 2.0  # clamp of the integral term [N m]
    torque_derivative_cutoff_hz: float = 50.0  # low-pass of e_dot [Hz]
    # friction compensation in the torque loop (icub_pmp/control/friction_compensation.py),
    # per group torso, arm, neck, eyes
    friction_compensation: bool = False  # add the joint friction model to the command
    friction_coulomb: tuple[float, ...] = (0.4, 0.15, 0.05, 0.05)  # [N m]
    friction_viscous: tuple[float, ...] = (0.3, 0.1, 0.02, 0.02)  # [N m s/rad]
    friction_velocity_epsilon: float = 0.01  # tanh smoothing speed of the Coulomb term [rad/s]
    # safety
    torque_limit_scale: float = 1.0  # saturate at this fraction of the RobotSpec limits
    joint_limit_margin: float = 0.03  # guard band inside each joint limit [rad]
    joint_limit_stiffness: float = 50.0  # guard spring in the band [N m/rad]
    joint_limit_damping: float = 2.0  # guard damping of outward motion in the band [N m s/rad]
    estimate_timeout: float = 0.05  # estimate older than this -> torque loop off [s]
    estimate_lost_timeout: float = 0.5  # torque loop on, no estimate this long -> safe hold
    # [s] (0 = never: feed-forward only)
    state_timeout: float = 0.1  # no joint state for this long -> safe hold [s, joint states' time]
    state_wall_timeout: float = 2.0  # no joint state for this long in wall time -> safe hold,
    # "simulator paused or gone" [s, wall] (0 = never)
    velocity_command_timeout: float = 0.2  # velocity command lapses after this [s]
    rate_limit_tolerance: float = 0.05  # refuse trajectories beyond the joint velocity /
    # acceleration limits of config/robot.yaml by more than this fraction [-]
    # trajectory goals (FollowJointTrajectory action): defaults when a goal leaves them empty
    path_tolerance: float = 0.0  # |q - q_d| allowed while moving [rad] (0 = no check)
    goal_tolerance: float = 0.05  # |q - q_d| allowed at the end [rad] (0 = no check)
    goal_time_tolerance: float = 1.0  # time after the last point to come within it [s]
    feedback_every: int = 50  # action feedback every N control steps
    # node
    lockstep: bool = True  # answer every /joint_states at once (stamp copied)
    wait_for_estimate: bool = True  # while the simulator runs lockstep (/sim/status): answer
    # a joint state only with the estimate of its stamp (never in free run)
    state_publish_every: int = 10  # publish /impedance_controller/state every N steps

    def validate(self) -> None:
        """Check choices, vector lengths and ranges (raises :class:`ConfigError`)."""
        if self.mode not in MODES:
            raise ConfigError(f"mode {self.mode!r}; valid: {MODES}")
        if self.feedforward not in FEEDFORWARDS:
            raise ConfigError(f"feedforward {self.feedforward!r}; valid: {FEEDFORWARDS}")
        if not self.rate_hz > 0:
            raise ConfigError(f"rate_hz must be > 0, got {self.rate_hz}")
        for kind in ("position", "impedance"):
            for gain in ("stiffness", "damping"):
                for group, size in GROUP_SIZES.items():
                    name = f"{kind}_{gain}_{group}"
                    v = getattr(self, name)
                    if len(v) != size:
                        raise ConfigError(f"{name}: expected {size} values, got {len(v)}")
                    if any(not (math.isfinite(x) and x >= 0) for x in v):
                        raise ConfigError(f"{name}: values must be finite and >= 0, got {v}")
        for name in ("torque_kp", "torque_ki", "torque_kd", "torque_kff",
                     "torque_integral_limit", "joint_limit_stiffness", "joint_limit_damping",
                     "joint_limit_margin"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ConfigError(f"{name} must be finite and >= 0, got {v}")
        for name in ("estimate_lost_timeout", "state_wall_timeout", "rate_limit_tolerance",
                     "path_tolerance", "goal_tolerance", "goal_time_tolerance"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ConfigError(f"{name} must be finite and >= 0, got {v}")
        for name in ("friction_coulomb", "friction_viscous"):
            v = getattr(self, name)
            if len(v) != len(GROUP_SIZES) or any(not (math.isfinite(x) and x >= 0) for x in v):
                raise ConfigError(f"{name}: expected {len(GROUP_SIZES)} values >= 0 (torso, "
                                  f"arm, neck, eyes), got {list(v)}")
        if not self.friction_velocity_epsilon > 0:
            raise ConfigError("friction_velocity_epsilon must be > 0, got "
                              f"{self.friction_velocity_epsilon}")
        if self.feedback_every < 1:
            raise ConfigError(f"feedback_every must be >= 1, got {self.feedback_every}")
        for name in ("torque_derivative_cutoff_hz", "estimate_timeout", "state_timeout",
                     "velocity_command_timeout"):
            if not getattr(self, name) > 0:
                raise ConfigError(f"{name} must be > 0, got {getattr(self, name)}")
        if not 0 < self.torque_limit_scale <= 1:
            raise ConfigError(
                f"torque_limit_scale must be in (0, 1], got {self.torque_limit_scale}")
        if self.state_publish_every < 0:
            raise ConfigError(f"state_publish_every must be >= 0, got {self.state_publish_every}")

    def friction(self, which: str) -> tuple[float, ...]:
        """Per-joint friction_``which`` (coulomb / viscous) in the order of :meth:`gains`."""
        t, a, n, e = getattr(self, f"friction_{which}")
        s = GROUP_SIZES
        return (t,) * s["torso"] + (a,) * (2 * s["arm"]) + (n,) * s["neck"] + (e,) * s["eyes"]

    def gains(self, kind: str, gain: str) -> tuple[float, ...]:
        """Concatenated group vector of ``kind`` (position/impedance) ``gain``
        (stiffness/damping) in the order torso, arm (left), arm (right), neck, eyes."""
        g = {grp: getattr(self, f"{kind}_{gain}_{grp}") for grp in GROUP_SIZES}
        return g["torso"] + g["arm"] + g["arm"] + g["neck"] + g["eyes"]
