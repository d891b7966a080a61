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
   estimate ``tau_hat`` exists, plus the joint friction of the desired motion
   (:class:`FrictionCompensation`, ``friction_compensation``);
5. saturation at the :class:`RobotSpec` torque limits.

Watchdogs: an estimate older than ``estimate_timeout`` (in the joint states' time) turns the
torque loop off (feed-forward only); with the torque loop on, no estimate for
``estimate_lost_timeout`` latches a safe hold until estimates are back (new estimates within
half that timeout of the joint states, even if not yet fresh); no joint state for
``state_timeout`` (checked by :meth:`check_watchdog`, in the joint states' time) or for
``state_wall_timeout`` of wall time (the node calls :meth:`enter_safe_hold`) aborts every
motion and latches a hold at the last measured posture until joint states are back. The
reason is kept in :attr:`safe_hold_reason`.

Trajectories must respect the joints' velocity and acceleration limits
(:class:`JointRateLimits`, from ``config/robot.yaml``): a faster one is refused with a message
naming the joint. :meth:`execute` starts a trajectory as a goal (:class:`TrajectoryGoal`)
whose outcome (success, preemption, tolerance violations, safe hold, cancel) is decided
step by step. Inputs with NaN, wrong sizes or unknown joints raise :class:`InvalidInput` and
change nothing.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np

from icub_pmp.control.friction_compensation import FrictionCompensation
from icub_pmp.control.impedance_controller_config import ImpedanceControllerConfig
from icub_pmp.control.joint_trajectory import JointTrajectory
from icub_pmp.control.setpoint_generator import Setpoint, SetpointGenerator
from icub_pmp.control.torque_pid import TorquePid
from icub_pmp.control.trajectory_goal import GoalCode, TrajectoryGoal
from icub_pmp.control.trajectory_limits import JointRateLimits
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
        self.rate_limits = JointRateLimits.from_spec(self.spec, self.joint_names)
        self._pid = TorquePid(self.n)
        self.set_config(config or ImpedanceControllerConfig())
        self._est = np.zeros(self.n)
        self._est_mask = np.zeros(self.n, dtype=bool)
        self._est_t: float | None = None
        self._t: float | None = None
        self._q = np.zeros(self.n)
        self._saturated = np.zeros(self.n, dtype=bool)
        self._safe = False
        self._safe_kind = ""  # "state": released by a joint state; "estimate": by an estimate
        self._lost_est_t = -math.inf  # stamp of the last estimate before the hold [s]
        self._safe_reason: str | None = None
        self._was_fresh = False
        self._goals: list[TrajectoryGoal] = []
        self._goal_seq = 0
        self.steps = 0
        #: steps with the torque loop on that had no fresh estimate (after the first one)
        self.stale_estimate_steps = 0

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
        self._friction = FrictionCompensation(
            np.array(c.friction("coulomb")), np.array(c.friction("viscous")),
            c.friction_velocity_epsilon) if c.friction_compensation else None
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
        """Follow ``traj`` from time ``t_now`` [s] (preempts older sources on its joints).

        Raises :class:`InvalidInput` in a safe hold or when the trajectory, joined from the
        current set-point, exceeds the joints' velocity or acceleration limits."""
        self.setpoints.follow(self._checked(traj, t_now))

    def _checked(self, traj: JointTrajectory, t_now: float) -> JointTrajectory:
        if self._safe:
            raise InvalidInput(f"controller is in safe hold ({self._safe_reason}): refused")
        anchored = self.setpoints.anchor(traj, t_now)
        self.rate_limits.check(anchored, self.config.rate_limit_tolerance)
        return anchored

    def execute(self, traj: JointTrajectory, t_now: float,
                path_tolerance: Sequence[float] = (), goal_tolerance: Sequence[float] = (),
                goal_time_tolerance: float = 0.0) -> TrajectoryGoal:
        """Start ``traj`` as a goal (see :class:`TrajectoryGoal`); tolerances [rad] per joint
        of ``traj`` or one value for all (empty = the configured default), goal time
        tolerance [s] (0 = default). Raises :class:`InvalidInput` as :meth:`set_trajectory`
        and on bad tolerances."""
        k = len(traj.joint_names)
        c = self.config
        path = _tolerances(path_tolerance, k, c.path_tolerance, "path_tolerance")
        goal = _tolerances(goal_tolerance, k, c.goal_tolerance, "goal_tolerance")
        gtt = float(goal_time_tolerance)
        if not math.isfinite(gtt) or gtt < 0:
            raise InvalidInput(f"goal_time_tolerance: expected a finite time >= 0 s, got {gtt}")
        anchored = self._checked(traj, t_now)
        self._goal_seq += 1
        idx = self.setpoints.follow(anchored, owner=self._goal_seq)
        g = TrajectoryGoal(self._goal_seq, anchored.joint_names, idx, anchored.start,
                           anchored.end, path, goal, gtt or c.goal_time_tolerance)
        self._goals.append(g)
        return g

    def cancel(self, goal: TrajectoryGoal) -> None:
        """Stop ``goal``: the joints it still owns hold their measured position (outcome
        CANCELED)."""
        if goal.done:
            return
        owned = goal.idx[self.setpoints.owner[goal.idx] == goal.goal_id]
        if len(owned) and self._t is not None:
            self.setpoints.hold_joints(owned, self._q[owned])
        t = self._t if self._t is not None else goal.start
        goal.finish(GoalCode.CANCELED, "canceled", self._q, self.setpoints.q, t)
        self._goals = [g for g in self._goals if not g.done]

    def estimate_age(self, t: float) -> float:
        """Time from the latest estimate to ``t`` [s] (-1 before the first estimate)."""
        return -1.0 if self._est_t is None else float(t) - self._est_t

    @property
    def measured_position(self) -> np.ndarray:
        """The last measured joint positions (n,) [rad] (read-only copy)."""
        q = self._q.copy()
        q.setflags(write=False)
        return q

    @property
    def goals(self) -> tuple[TrajectoryGoal, ...]:
        """The goals still running."""
        return tuple(self._goals)

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
        ``now`` [s] (the joint states' clock). Returns True when it trips on this call."""
        if self._t is None or (self._safe and self._safe_kind == "state"):
            return False
        if now - self._t > self.config.state_timeout:
            self.enter_safe_hold(f"no joint state for {self.config.state_timeout} s")
            return True
        return False

    def enter_safe_hold(self, reason: str, kind: str = "state") -> None:
        """Abort every motion and goal and hold the last measured posture until joint states
        (``kind`` 'state') or estimates ('estimate') are back."""
        if self._safe and self._safe_kind == "state":
            return
        self._safe = True
        self._safe_kind = kind
        self._safe_reason = reason
        self._lost_est_t = self._est_t if self._est_t is not None else -math.inf
        if self._t is not None:
            self.setpoints.hold(self._q)
            for g in self._goals:
                g.finish(GoalCode.SAFE_HOLD, f"safe hold: {reason}", self._q,
                         self.setpoints.q, self._t)
        self._goals = []
        self._pid.reset()

    @property
    def safe_hold(self) -> bool:
        """True while a watchdog holds the robot (:attr:`safe_hold_reason` says why)."""
        return self._safe

    @property
    def safe_hold_reason(self) -> str | None:
        """Why the robot is held (None when it is not)."""
        return self._safe_reason if self._safe else None

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
            if self._t is not None:
                for g in self._goals:
                    g.finish(GoalCode.SAFE_HOLD, "time went back (simulator reset): motion "
                             "stopped", self._q, self.setpoints.q, self._t)
                self._goals = []
                if self._est_t is not None and self._est_t > t:  # from the old timeline
                    self._est_t = None
                    self._est_mask[:] = False
            self.setpoints.hold(q, t)
            self._pid.reset()
            self._t = None
            self._safe = False
        elif self._safe and self._safe_kind == "state":  # joint states are back
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
        if c.torque_loop and c.estimate_lost_timeout > 0 and self._est_t is not None:
            if (self._safe and self._safe_kind == "estimate" and self._est_t > self._lost_est_t
                    and t - self._est_t <= 0.5 * c.estimate_lost_timeout):
                # estimates are back: motions may be commanded again. Judged on estimates that
                # arrive again (newer than the last before the hold) within half the loss
                # timeout, not on `fresh`: a restarted estimator on a loaded machine may stay
                # a little more than estimate_timeout behind for a while, and the hold would
                # never release (the torque loop itself still runs only on fresh estimates)
                self._safe = False
            elif (not fresh and not self._safe
                  and t - self._est_t > c.estimate_lost_timeout):
                # takes effect from the next step (the set-point is held from now on)
                self.enter_safe_hold(
                    f"estimator lost: no joint torque estimate for "
                    f"{c.estimate_lost_timeout} s", kind="estimate")
        if c.torque_loop and not fresh and self._est_t is not None:
            self.stale_estimate_steps += 1
        if c.torque_loop and fresh:
            tau = self._pid(tau_d, self._est, dt, self._est_mask, self._saturated)
        else:
            tau = tau_d.copy()
        if self._friction is not None:  # the gearbox's friction, added back (eqs 4-5)
            tau += self._friction(sp.v)

        # saturation
        self._saturated = np.abs(tau) > self._tau_max
        np.clip(tau, -self._tau_max, self._tau_max, out=tau)
        self.steps += 1
        if self._goals:
            owner = self.setpoints.owner
            for g in self._goals:
                g.update(t, q, sp.q, bool(np.all(owner[g.idx] == g.goal_id)), None)
            self._goals = [g for g in self._goals if not g.done]
        if self._safe:
            status = "safe_hold"
        return ControlOutput(float(t), tau, tau_d, sp, self._saturated.copy(), guard, status)


def _tolerances(values: Sequence[float], k: int, default: float, name: str) -> np.ndarray:
    """Per-joint tolerances (k,) [rad] from a goal's list: empty = default, one = all."""
    v = np.asarray(list(values), dtype=float).reshape(-1)
    if v.size == 0:
        v = np.full(k, default)
    elif v.size == 1:
        v = np.full(k, float(v[0]))
    elif v.size != k:
        raise InvalidInput(f"{name}: expected 0, 1 or {k} values (one per joint), got {v.size}")
    if not np.all(np.isfinite(v)) or np.any(v < 0):
        raise InvalidInput(f"{name}: values must be finite and >= 0 [rad], got {v.tolist()}")
    return v
