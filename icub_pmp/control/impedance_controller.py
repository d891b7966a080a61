"""ImpedanceController: the 1 kHz joint controller of the iCub boards (Sect. 3, eqs 4-7).

Per step (one joint-state sample):

1. the set-point (q_d, q_dot_d, q_ddot_d) from trajectories, velocity commands (eq 7) or a hold
   (:class:`SetpointGenerator`);
2. the desired torque, eq 6 written with the restoring sign and a model feed-forward:
   ``tau_d = -K (q - q_d) - D (q_dot - q_dot_d) + tau_ff`` with ``tau_ff`` = g(q) (gravity
   compensation from :class:`IcubModel`) or RNEA(q, q_dot_d, q_ddot_d). (The paper's eq 6 has
   ``+K (q - q_d)`` because iCub torques are reported as the load on the joint.) Modes:
   ``position`` (stiff K, D), ``impedance`` (compliant K, D), ``torque`` (``tau_d = tau_ff`` +
   trajectory efforts, no position feedback);
3. the joint-limit guard: a joint within ``joint_limit_margin`` of a limit and nearer to it
   than its set-point (pushed there; any joint in torque mode) gets a spring-damper pushing it
   back; set-points themselves are kept within the joint limits;
4. the torque loop (eqs 4-5, :class:`TorquePid`) on ``e = tau_hat - tau_d`` when a fresh
   estimate ``tau_hat`` exists;
5. saturation at the :class:`RobotSpec` torque limits.

Watchdogs: an estimate older than ``estimate_timeout`` (in the joint states' time) turns the
torque loop off (feed-forward only); no joint state for ``state_timeout`` (checked by
:meth:`check_watchdog`) aborts every motion and latches a hold at the last measured posture.
Inputs with NaN, wrong sizes or unknown joints raise :class:`InvalidInput` and change nothing.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np

from icub_pmp.control.impedance_controller_config import ImpedanceControllerConfig
from icub_pmp.control.joint_trajectory import JointTrajectory
from icub_pmp.control.setpoint_generator import Setpoint, SetpointGenerator
from icub_pmp.control.torque_pid import TorquePid
from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.eye_kinematics import EYE_LIMITS
from icub_pmp.kinematics.robot_model import IcubModel
from icub_pmp.kinematics.robot_spec import RobotSpec

__all__ = ["ImpedanceController", "ControlOutput", "STATUSES"]

#: ok: torque loop closed; no_estimate: never received one (feed-forward only);
#: estimate_stale: the estimate is too old (feed-forward only); safe_hold: the joint-state
#: watchdog tripped (holding the last measured posture).
STATUSES = ("ok", "no_estimate", "estimate_stale", "safe_hold")


class ControlOutput(NamedTuple):
    """One controller step at time ``t`` [s] over :attr:`ImpedanceController.joint_names`.

    ``tau``: command (n,) [N m]; ``tau_d``: desired torque before the torque loop (n,) [N m];
    ``setpoint``: the desired state; ``saturated`` / ``limit_guard``: (n,) bool;
    ``status``: one of :data:`STATUSES`.
    """

    t: float
    tau: np.ndarray
    tau_d: np.ndarray
    setpoint: Setpoint
    saturated: np.ndarray
    limit_guard: np.ndarray
    status: str


class ImpedanceController:
    """The controller core (no ROS): feed :meth:`step` one joint-state sample at a time."""

    def __init__(
        self,
        config: ImpedanceControllerConfig | None = None,
        spec: RobotSpec | None = None,
        model: IcubModel | None = None,
    ):
        self.spec = spec or RobotSpec.load()
        self.model = model or IcubModel(self.spec)
        self.joint_names: tuple[str, ...] = self.spec.actuated_joints
        self.n = len(self.joint_names)
        self._index = {n: i for i, n in enumerate(self.joint_names)}
        # model joints (torso, arms, neck) inside the controller vector and the model vector
        upper = self.spec.upper_body_joints
        self._ctl_model = np.array([self._index[j] for j in upper])
        self._model_idx = self.model.indices(upper)
        # q_model = q[_to_model]; tau[:n_model] += tau_model[_from_model]
        self._to_model = np.empty(self.model.nq, dtype=int)
        self._to_model[self._model_idx] = self._ctl_model
        if not np.array_equal(self._ctl_model, np.arange(len(upper))):
            raise ValueError("the model joints must come first in RobotSpec.actuated_joints")
        self._from_model = np.array(self._model_idx)
        self._n_model = len(upper)
        lower = np.zeros(self.n)
        upper_lim = np.zeros(self.n)
        lower[self._ctl_model] = self.model.lower[self._model_idx]
        upper_lim[self._ctl_model] = self.model.upper[self._model_idx]
        for j in self.spec.eye_joints:
            lower[self._index[j]], upper_lim[self._index[j]] = EYE_LIMITS[j]
        self.lower, self.upper = lower, upper_lim
        self.lower.setflags(write=False)
        self.upper.setflags(write=False)
        self.torque_limits = np.array([self.spec.torque_limit(j) for j in self.joint_names])
        self._pid = TorquePid(self.n)
        self.set_config(config or ImpedanceControllerConfig())
        self._est = np.zeros(self.n)
        self._est_mask = np.zeros(self.n, dtype=bool)
        self._est_t: float | None = None
        self._t: float | None = None
        self._q = np.zeros(self.n)
        self._saturated = np.zeros(self.n, dtype=bool)
        self._safe = False
        self._was_fresh = False
        self.steps = 0

    # ------------------------------------------------------------------ configuration
    def set_config(self, config: ImpedanceControllerConfig) -> None:
        """Apply a (validated) configuration at run time: gains, mode, limits.

        A mode change resets the torque-loop integral; set-points and motions continue.
        """
        old = getattr(self, "config", None)
        c = config
        self._k = {
            kind: np.array(c.gains(kind, "stiffness")) for kind in ("position", "impedance")
        }
        self._d = {kind: np.array(c.gains(kind, "damping")) for kind in ("position", "impedance")}
        self._pid.set_gains(c.torque_kp, c.torque_ki, c.torque_kd, c.torque_kff,
                            c.torque_integral_limit, c.torque_derivative_cutoff_hz)
        self._tau_max = self.torque_limits * c.torque_limit_scale
        self._guard_lo = self.lower + c.joint_limit_margin
        self._guard_hi = self.upper - c.joint_limit_margin
        if old is None:
            self.setpoints = SetpointGenerator(self.joint_names, self.lower, self.upper)
        if old is not None and old.mode != c.mode:
            self._pid.reset()
        self.config = c

    @property
    def mode(self) -> str:
        """The current control mode."""
        return self.config.mode

    def indices(self, names: Sequence[str]) -> np.ndarray:
        """Positions of ``names`` in the controller's joint vector (raises UnknownName)."""
        return self.setpoints.indices(names)

    # ------------------------------------------------------------------ inputs
    def make_trajectory(
        self,
        names: Sequence[str],
        times: Sequence[float],
        positions: np.ndarray,
        velocities: np.ndarray | None = None,
        accelerations: np.ndarray | None = None,
        efforts: np.ndarray | None = None,
        start: float = 0.0,
    ) -> JointTrajectory:
        """A validated :class:`JointTrajectory` for this robot (names, NaN, times, limits)."""
        lower = dict(zip(self.joint_names, self.lower))
        upper = dict(zip(self.joint_names, self.upper))
        return JointTrajectory(
            names, times, positions, velocities, accelerations, efforts, start=start,
            valid_names=self.joint_names, lower=lower, upper=upper,
        )

    def set_trajectory(self, traj: JointTrajectory, t_now: float) -> None:
        """Follow ``traj`` from time ``t_now`` [s] (preempts older sources on its joints)."""
        if self._safe:
            raise InvalidInput(
                "controller is in safe hold (stale joint states): trajectory refused")
        self.setpoints.set_trajectory(traj, t_now)

    def set_velocity_command(self, names: Sequence[str], velocities: np.ndarray,
                             t_now: float) -> None:
        """Velocity mode (eq 7) for joints ``names`` [rad/s] from ``t_now`` [s]."""
        if self._safe:
            raise InvalidInput("controller is in safe hold (stale joint states): command refused")
        self.setpoints.set_velocity(names, velocities, t_now,
                                    self.config.velocity_command_timeout)

    def hold(self) -> None:
        """Stop all motion and hold the last measured posture."""
        if self.setpoints.initialised or self._t is not None:
            self.setpoints.hold(self._q)

    def set_estimate(self, t: float, names: Sequence[str], tau_hat: np.ndarray) -> None:
        """Store the estimated joint torques ``tau_hat`` [N m] of joints ``names`` at ``t`` [s]
        (joints not named keep no estimate)."""
        idx = self.indices(names)
        tau_hat = np.asarray(tau_hat, dtype=float)
        if tau_hat.shape != (len(idx),) or not np.all(np.isfinite(tau_hat)):
            raise InvalidInput(f"estimate: expected {len(idx)} finite torques")
        if not math.isfinite(t):
            raise InvalidInput("estimate: time is not finite")
        self._est_mask[:] = False
        self._est_mask[idx] = True
        self._est[idx] = tau_hat
        self._est_t = float(t)

    # ------------------------------------------------------------------ watchdog
    def check_watchdog(self, now: float) -> bool:
        """Trip the safe hold if the last joint state is older than ``state_timeout`` at
        ``now`` [s]. Returns True when it trips on this call."""
        if self._t is None or self._safe:
            return False
        if now - self._t > self.config.state_timeout:
            self._safe = True
            self.setpoints.hold(self._q)
            self._pid.reset()
            return True
        return False

    @property
    def safe_hold(self) -> bool:
        """True while the joint-state watchdog holds the robot."""
        return self._safe

    # ------------------------------------------------------------------ step
    def step(self, t: float, q: np.ndarray, v: np.ndarray) -> ControlOutput:
        """One control step for the joint state (q, v) (n,) [rad, rad/s] at time ``t`` [s]."""
        q = np.asarray(q, dtype=float)
        v = np.asarray(v, dtype=float)
        if q.shape != (self.n,) or v.shape != (self.n,):
            raise InvalidInput(f"step: expected q and v of shape ({self.n},), got {q.shape}, "
                               f"{v.shape}")
        if not (math.isfinite(float(q.sum())) and math.isfinite(float(v.sum()))
                and math.isfinite(t)):
            raise InvalidInput("step: joint state contains NaN or infinite values")
        c = self.config
        if self._t is None or t < self._t - 1e-9:  # first sample, or time went back (reset)
            self.setpoints.hold(q, t)
            self._pid.reset()
            self._t = None
            self._safe = False
        elif self._safe:  # joint states are back after the watchdog tripped
            self._safe = False
            self.setpoints.hold(q, t)
        dt = 0.0 if self._t is None else t - self._t
        self._t = float(t)
        self._q = q.copy()
        sp = self.setpoints.update(t)

        # eq 6 with the restoring sign, plus the model feed-forward
        if c.mode == "torque":
            tau_d = sp.effort.copy()
        else:
            tau_d = -self._k[c.mode] * (q - sp.q) - self._d[c.mode] * (v - sp.v)
        if c.feedforward != "none":
            m = self._to_model
            if c.feedforward == "gravity" or c.mode == "torque":
                ff = self.model.gravity_torques(q[m])
            else:
                ff = self.model.inverse_dynamics(q[m], sp.v[m], sp.a[m])
            tau_d[: self._n_model] += ff[self._from_model]

        # joint-limit guard: within `margin` of a limit and nearer to it than the set-point
        # (pushed there; any joint in torque mode), a spring-damper pushes back to the band
        # edge or to the set-point, whichever is nearer to the limit
        lo, hi = self._guard_lo, self._guard_hi
        if c.mode != "torque":
            lo = np.minimum(lo, sp.q)
            hi = np.maximum(hi, sp.q)
        below, above = q < lo, q > hi
        guard = below | above
        if guard.any():
            push = np.where(below, lo - q, 0.0) + np.where(above, hi - q, 0.0)
            outward = np.where(below, np.minimum(v, 0.0), 0.0) + np.where(
                above, np.maximum(v, 0.0), 0.0)
            tau_d += c.joint_limit_stiffness * push - c.joint_limit_damping * outward

        # torque loop (eqs 4-5)
        status = "ok"
        fresh = False
        if self._est_t is None:
            status = "no_estimate"
        elif t - self._est_t > c.estimate_timeout:
            status = "estimate_stale"
        else:
            fresh = True
        if fresh and not self._was_fresh:
            self._pid.reset()
        self._was_fresh = fresh
        if c.torque_loop and fresh:
            tau = self._pid(tau_d, self._est, dt, self._est_mask, self._saturated)
        else:
            tau = tau_d.copy()

        # saturation
        self._saturated = np.abs(tau) > self._tau_max
        np.clip(tau, -self._tau_max, self._tau_max, out=tau)
        self.steps += 1
        return ControlOutput(float(t), tau, tau_d, sp, self._saturated.copy(), guard, status)
