"""WrenchEstimator: joint torques, external hand wrenches and contact flags from the joint
states and the arm FT sensors (the wholeBodyDynamics / iDyn role, Sect. 3 of the paper).

Per sample, with the graph of Fig. 4b (the FT sensors cut the arms, contacts only at the hands,
kinematics from the fixed base, gravity from the model or the IMU):

1. joint velocities / accelerations filtered (:class:`JointStateFilter`);
2. RNEA with no external wrench (eqs 8-10) predicts the internal wrench ``w_i`` through each
   FT sensor (plus the RFRR residual when enabled);
3. eq 2: the external wrench at the hand ``w_e = -X_hand<-sensor (w_s - w_i)``: the excess
   wrench the shoulder applies through the sensor balances the environment's wrench on the
   distal arm; it is moved to the hand frame (force unchanged, moment ``mu - r_se x f``);
4. RNEA again with ``w_e`` on the hands gives the joint torques ``tau_hat`` (eq 3's
   ``J^T w_e`` folded into the recursion): for the joints proximal to the sensors (shoulder,
   torso) this is exactly the measured FT wrench propagated to the joints;
5. contact flag per hand (:class:`ContactDetector`, hysteresis on |f_e|);
6. optionally the RFRR (:class:`RandomFeaturesRidge`) learns ``w_s - w_i,model`` from
   (q, q_dot, q_ddot) of torso + arm on contact-free samples.

Units: N, N m, rad; wrenches (6,) = [force, torque]. External wrenches are those the
environment applies to the hand, about the hand frame origin (``l_hand_dh_frame``).
"""

from __future__ import annotations

import math
from typing import Mapping, NamedTuple

import numpy as np

from icub_pmp.dynamics.butterworth_low_pass import ButterworthLowPass
from icub_pmp.dynamics.contact_detector import ContactDetector
from icub_pmp.dynamics.ft_dynamics_model import FtDynamicsModel
from icub_pmp.dynamics.ft_offset_calibration import (
    CalibrationError,
    FtOffsetCalibration,
    FtOffsets,
)
from icub_pmp.dynamics.joint_state_filter import FilteredState, JointStateFilter
from icub_pmp.dynamics.random_features_ridge import RandomFeaturesRidge
from icub_pmp.dynamics.wrench_estimator_config import WrenchEstimatorConfig
from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS, RobotSpec

__all__ = ["WrenchEstimator", "WrenchEstimate"]

_LEFT, _RIGHT = HANDS


class WrenchEstimate(NamedTuple):
    """One estimator output (time ``t`` [s]).

    ``tau``: joint torques (nq,) [N m] over :attr:`WrenchEstimator.joint_names`;
    ``ext_hand`` / ``ext_root``: {hand: (6,)} external wrench on the hand about its origin,
    in the hand frame / in root_link axes; ``contact``: {hand: bool};
    ``ft_measured`` / ``ft_predicted``: {hand: (6,)} FT wrench as measured (filtered, offset
    removed) and as predicted without external wrench (model + RFRR), in the sensor frame and
    the sensor's sign convention; ``state``: the filtered joint state used.
    """

    t: float
    tau: np.ndarray
    ext_hand: dict[str, np.ndarray]
    ext_root: dict[str, np.ndarray]
    contact: dict[str, bool]
    ft_measured: dict[str, np.ndarray]
    ft_predicted: dict[str, np.ndarray]
    state: FilteredState


class WrenchEstimator:
    """The estimator core (no ROS). Feed :meth:`update` one sample at a time."""

    def __init__(self, config: WrenchEstimatorConfig | None = None, spec: RobotSpec | None = None):
        self.config = cfg = config or WrenchEstimatorConfig()
        self.spec = spec or RobotSpec.load()
        mismatch = {cfg.mismatch_link: cfg.mismatch_scale} if cfg.mismatch_link else {}
        self.model = FtDynamicsModel(self.spec, mismatch)
        if not self.model.model.existFrame(cfg.imu_frame):
            raise UnknownName("frame", cfg.imu_frame, [f.name for f in self.model.model.frames])
        self.joint_names = self.model.joint_names
        self.nq = self.model.nq
        self._sign = 1.0 if cfg.ft_convention == "parent_on_child" else -1.0
        rate = cfg.sample_rate_hz
        self._filter = JointStateFilter(
            self.nq, rate, cfg.velocity_cutoff_hz, cfg.acceleration_cutoff_hz
        )
        self._ft_filter = {h: ButterworthLowPass(6, cfg.ft_cutoff_hz, rate) for h in HANDS}
        # the model's sensor wrench through the same low-pass: measured and predicted wrenches
        # then have the same lag (a filter on the measurement alone is an error in motion)
        self._model_filter = {h: ButterworthLowPass(6, cfg.ft_cutoff_hz, rate) for h in HANDS}
        self._imu_filter = ButterworthLowPass(3, cfg.imu_cutoff_hz, rate)
        self._contact = {
            h: ContactDetector(cfg.contact_force_on, cfg.contact_force_off,
                               cfg.contact_min_samples)
            for h in HANDS
        }
        # RFRR inputs per hand: torso + arm joints (q, q_dot, q_ddot) -> 30 inputs, 6 outputs
        self._rfrr_idx = {
            h: self.model.indices(self.spec.torso_joints + self.spec.arm_joints(h)) for h in HANDS
        }
        n_in = 3 * len(self._rfrr_idx["left"])
        n_j = len(self._rfrr_idx["left"])
        scale = np.concatenate([
            np.full(n_j, cfg.rfrr_position_scale),
            np.full(n_j, cfg.rfrr_velocity_scale),
            np.full(n_j, cfg.rfrr_acceleration_scale),
        ])
        self.rfrr = {
            h: RandomFeaturesRidge(
                n_in, 6, cfg.rfrr_features, cfg.rfrr_bandwidth, cfg.rfrr_ridge,
                cfg.rfrr_forgetting, scale, cfg.rfrr_seed + k,
            )
            for k, h in enumerate(HANDS)
        }
        self.rfrr_enabled = cfg.rfrr_enabled
        self.rfrr_learning = cfg.rfrr_learning
        self._offset = {h: np.zeros(6) for h in HANDS}
        self._offset_acc = {h: np.zeros(6) for h in HANDS}
        self._offset_n = 0
        self._samples = 0
        self._last_contact = {h: False for h in HANDS}
        #: the last samples' FT residuals, for :meth:`calibrate_from_recent`
        self.calibration = FtOffsetCalibration(
            cfg.calibration_samples, self.nq, len(HANDS), cfg.calibration_motion_tolerance,
            tuple(self.joint_names))
        self.calibrated = False  # offsets from a calibration (not the start-up average)
        self._startup_window_skipped = False  # calibrate_at_startup (calibrate_offsets)
        self._startup_samples = 0  # samples since calibrate_offsets (calibrate_at_startup)
        self.calibration_error: str = ""  # why the last start-up attempt was refused
        self._residual = np.zeros((len(HANDS), 6))

    # ------------------------------------------------------------------ helpers
    def apply_live_config(self, config: WrenchEstimatorConfig) -> None:
        """Apply the settings that need no rebuild: RFRR on/off, learning on/off, contact
        thresholds (flags restart clear). Other fields of ``config`` must be unchanged."""
        self.rfrr_enabled = config.rfrr_enabled
        self.rfrr_learning = config.rfrr_learning
        self._contact = {
            h: ContactDetector(config.contact_force_on, config.contact_force_off,
                               config.contact_min_samples)
            for h in HANDS
        }
        self.config = config

    def reset(self) -> None:
        """Forget filter states, contact flags and the offset calibration (not the RFRR)."""
        self.clear_history()
        self.calibrate_offsets()
        self._samples = 0

    def clear_history(self) -> None:
        """Forget what is ordered in time (joint-state, FT and IMU filters, contact flags)
        when the clock went back (a restarted simulator): the next :meth:`update` starts
        afresh at its own time. The FT offsets (a property of the sensors) and the learnt RFRR
        stay."""
        self._filter.reset()
        for f in list(self._ft_filter.values()) + list(self._model_filter.values()):
            f.reset()
        self._imu_filter.reset()
        for c in self._contact.values():
            c.reset()
        self._last_contact = {h: False for h in HANDS}

    def calibrate_offsets(self) -> None:
        """Restart the FT offset calibration (``ft_offset_samples`` contact-free samples)."""
        self._offset = {h: np.zeros(6) for h in HANDS}
        self._offset_acc = {h: np.zeros(6) for h in HANDS}
        self._offset_n = 0
        self.calibrated = False
        self.calibration.clear()
        # calibrate_at_startup skips the first full window: the FT low-passes start on the
        # first sample, which in the node graph can be one of before the physics loop ran
        self._startup_window_skipped = False
        self._startup_samples = 0

    @property
    def startup_calibration_expired(self) -> bool:
        """True once ``calibrate_at_startup_within`` seconds of samples passed since the start
        (or :meth:`calibrate_offsets`) without a start-up calibration: it is not tried again."""
        return self._startup_samples >= self.config.calibrate_at_startup_within \
            * self.config.sample_rate_hz

    def calibrate_from_recent(self) -> FtOffsets:
        """Set the FT offsets to the mean residual (measured - predicted) of the last
        ``calibration_samples`` samples (:class:`FtOffsetCalibration`); raises
        :class:`CalibrationError` (offsets unchanged) when the robot moved during them or
        fewer samples came. The robot must be still and free of contact."""
        result = self.calibration.calibrate()
        for k, h in enumerate(HANDS):
            self._offset[h] = result.offsets[k].copy()
        self._offset_n = max(self.config.ft_offset_samples, 1)
        self.calibrated = True
        self.calibration_error = ""
        return result

    @property
    def offsets(self) -> dict[str, np.ndarray]:
        """Current FT offsets {hand: (6,)} in the sensor's convention (measured - model)."""
        return {h: o.copy() for h, o in self._offset.items()}

    def rfrr_input(self, hand: str, state: FilteredState) -> np.ndarray:
        """RFRR input (30,) of ``hand``: torso + arm q, q_dot, q_ddot."""
        i = self._rfrr_idx[hand]
        return np.concatenate([state.q[i], state.v[i], state.a[i]])

    def predict_ft(
        self, q: np.ndarray, v: np.ndarray | None = None, a: np.ndarray | None = None
    ) -> dict[str, np.ndarray]:
        """Model-predicted FT wrenches {hand: (6,)} with null external wrenches, in the
        sensor's sign convention (no RFRR, no offsets)."""
        r = self.model.rnea(self._check(q, "q"), v, a)
        return {h: self._sign * w for h, w in r.sensor.items()}

    def _check(self, x: np.ndarray, name: str) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if x.shape != (self.nq,):
            raise InvalidInput(f"{name}: expected shape ({self.nq},), got {x.shape}")
        if not math.isfinite(x @ x):
            raise InvalidInput(f"{name}: contains NaN or infinite values")
        return x

    @staticmethod
    def _reject_ft(ft: Mapping[str, np.ndarray]) -> None:
        """Raise InvalidInput naming what is wrong with the FT wrenches ``ft``."""
        for h in HANDS:
            try:
                w = np.asarray(ft[h], dtype=float)
            except (KeyError, TypeError):
                raise InvalidInput(f"ft: missing the {h} arm wrench (need {HANDS})") from None
            except ValueError:
                raise InvalidInput(f"ft[{h!r}]: expected 6 finite values, got {ft[h]!r}") \
                    from None
            if w.shape != (6,) or not np.all(np.isfinite(w)):
                raise InvalidInput(f"ft[{h!r}]: expected 6 finite values, got {w!r}")
        raise InvalidInput(f"ft: expected 6 finite values per hand, got {ft!r}")

    def _gravity_from_imu(self, q: np.ndarray, acc: np.ndarray) -> None:
        acc = np.asarray(acc, dtype=float)
        if acc.shape != (3,) or not np.all(np.isfinite(acc)):
            raise InvalidInput(f"imu acceleration: expected 3 finite values, got {acc!r}")
        acc_f = self._imu_filter(acc)
        self.model.forward(q)
        r_root_imu = self.model.frame_rotation(self.config.imu_frame)
        # an accelerometer at rest measures -g (specific force): g_root = -R_root_imu acc
        self.model.set_gravity(-(r_root_imu @ acc_f))

    # ------------------------------------------------------------------ main step
    def update(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray | None,
        ft: Mapping[str, np.ndarray],
        imu_acc: np.ndarray | None = None,
    ) -> WrenchEstimate:
        """Process one sample at time ``t`` [s].

        ``q`` (nq,) [rad], ``v`` (nq,) [rad/s] or None (differentiated), ``ft`` {hand: (6,)}
        measured FT wrenches in the sensor frame (both hands), ``imu_acc`` (3,) [m/s^2] the
        IMU linear acceleration (used when ``gravity_source == 'imu'``).
        """
        q = self._check(q, "q")
        if v is not None:
            v = self._check(v, "v")
        # x: measured FT wrenches in the sensor's convention (filtered, offsets removed below)
        try:  # both hands in one array: one copy and one finiteness test per sample
            w = np.concatenate((ft[_LEFT], ft[_RIGHT]), dtype=float)
        except (KeyError, TypeError, ValueError):
            w = None
        if w is None or w.shape != (12,) or not math.isfinite(w @ w):
            self._reject_ft(ft)
        x = {_LEFT: w[:6], _RIGHT: w[6:]}
        for h in HANDS:
            f = self._ft_filter[h]
            if f.enabled:
                x[h] = f(x[h])
        cfg = self.config
        if cfg.gravity_source == "imu":
            if imu_acc is None:
                raise InvalidInput("gravity_source is 'imu' but no IMU acceleration was given")
            self._gravity_from_imu(q, imu_acc)
        state = self._filter.update(t, q, v)
        # eqs 8-10: the internal wrench through each sensor (model; parent on child), and the
        # forward kinematics for eq 2
        free = self.model.free_sensor_wrenches(state.q, state.v, state.a)
        if cfg.ft_cutoff_hz > 0:
            free = {h: self._model_filter[h](free[h]) for h in HANDS}
        self._samples += 1

        # predicted internal wrench p in the sensor's convention: model (+ learnt residual)
        sign = self._sign
        x_in = {}
        if self.rfrr_enabled or self.rfrr_learning:
            p = {}
            for h in HANDS:
                x_in[h] = self.rfrr_input(h, state)
                w_int = free[h] + self.rfrr[h].predict(x_in[h]) if self.rfrr_enabled \
                    else free[h]
                p[h] = sign * w_int
        else:
            p = {}
            for h in HANDS:
                p[h] = sign * free[h]
        # FT offsets (measured - predicted), averaged over the first contact-free samples
        if self._offset_n < cfg.ft_offset_samples:
            self._offset_n += 1
            for h in HANDS:
                self._offset_acc[h] += x[h] - p[h]
                self._offset[h] = self._offset_acc[h] / self._offset_n
        r = self._residual
        for k, h in enumerate(HANDS):
            r[k] = x[h] - p[h]
        self.calibration.add(q, r)
        startup = cfg.calibrate_at_startup and not self.calibrated
        if startup and not self.startup_calibration_expired:
            self._startup_samples += 1
            if self.startup_calibration_expired:  # no still window at start-up: never later,
                # when a still arm may be a pushed one whose push would become the offset
                self.calibration_error = (
                    f"start-up calibration gave up: no still, free window of "
                    f"{cfg.calibration_samples} samples within {cfg.calibrate_at_startup_within:g}"
                    f" s of the start; call ~/calibrate with the robot still and free")
        if startup and self.calibration.full and not self.startup_calibration_expired:
            if not self._startup_window_skipped:  # the filters' start (calibrate_offsets)
                self._startup_window_skipped = True
                self.calibration.clear()
            else:
                try:
                    self.calibrate_from_recent()
                except CalibrationError as exc:  # moved: try again on the next full window
                    self.calibration_error = str(exc)
                    self.calibration.clear()
        if self._offset_n:
            x = {h: x[h] - self._offset[h] for h in HANDS}

        # eq 2: the external wrench on the distal arm at the sensor is the predicted internal
        # wrench minus the measured one (parent on child: sign * (p - x)), moved to the hand;
        # eq 3 (the joint torques with the estimated hand wrenches) folded into a second RNEA
        # (loops, not comprehensions: this runs at 1 kHz and a comprehension is a call)
        excess = {}
        for h in HANDS:
            excess[h] = p[h] - x[h] if sign > 0 else x[h] - p[h]
        tau, ext_hand, ext_root = self.model.torques_with_sensor_excess(excess)
        contact = {}
        for h in HANDS:
            contact[h] = self._contact[h].update(ext_hand[h][:3])

        # RFRR learning on contact-free samples (never while calibrating offsets): the target
        # is the measured minus the model wrench, parent on child
        if (
            self.rfrr_learning
            and self._offset_n >= cfg.ft_offset_samples
            and self._samples % cfg.rfrr_update_every == 0
        ):
            for h in HANDS:
                if not contact[h] and not self._last_contact[h]:
                    self.rfrr[h].update(x_in[h], sign * x[h] - free[h])
        self._last_contact = contact
        return WrenchEstimate(
            t=float(t),
            tau=tau,
            ext_hand=ext_hand,
            ext_root=ext_root,
            contact=contact,
            ft_measured=x,
            ft_predicted=p,
            state=state,
        )
