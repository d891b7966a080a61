"""wrench_estimator: joint torques, external hand wrenches and contact flags from the joint
states and the arm FT sensors (stands in for wholeBodyDynamics; the core is
:class:`icub_pmp.dynamics.WrenchEstimator`).

subscribes /joint_states (JointState), /ft/l_arm_ft, /ft/r_arm_ft (WrenchStamped), /imu (Imu,
           only while ``gravity_source`` is ``imu``)
publishes  /estimated_joint_torques (JointState: name + effort [N m], stamp of the sample),
           /wrench_estimator/external_wrench/{left,right}_hand (WrenchStamped, hand frame
           ``l_hand_dh_frame`` / ``r_hand_dh_frame``), /wrench_estimator/external_wrench_root/
           {left,right}_hand (WrenchStamped, root_link axes, about the hand origin),
           /wrench_estimator/contact/{left,right}_hand (std_msgs/Bool),
           /wrench_estimator/predicted_ft/{l_arm_ft,r_arm_ft} (WrenchStamped: the FT reading
           the model predicts with null hand wrenches, for the Table 1 validation)
services   ~/calibrate (std_srvs/Trigger): FT offset calibration from the last
           ``calibration_samples`` samples, which must be still and contact-free (as
           wholeBodyDynamics's ``calib``): success with the offsets, or success=false and the
           reason (the robot moved, too few samples) with the offsets unchanged;
           ``calibrate_at_startup`` does it once by itself as soon as a still window is in,
           within ``calibrate_at_startup_within`` s of the start (never later: a still arm
           then may be a pushed one; an error in the log says to call ~/calibrate)

Time: the estimator works on message stamps only (no clock, ``use_sim_time`` not needed: it
saves deserialising /clock at 1 kHz). Synchronisation: with ``require_same_stamp`` (lockstep
with the simulator) a sample is processed when the joint state and both arm FT wrenches with
the same stamp have arrived (in any order); otherwise each joint state is processed with the
latest FT wrenches, unless they are older than ``stale_timeout`` (then it is skipped with a
throttled warning). Malformed messages (unknown or missing joints, wrong lengths, NaN) are
dropped on arrival with a throttled warning, before they reach the synchroniser: a bad message
never takes the place of a good one with the same stamp. Time: a joint state older than the
newest one means the clock went back (a restarted simulator,
:class:`~icub_pmp.time_jump_detector.TimeJumpDetector`): the node says so, clears the
synchroniser and the estimator's filters and contact flags, and goes on at once. One
synchronised sample in ``sample_every`` is processed (wholeBodyDynamics runs at 100 Hz on the
robot: ``sample_every: 10`` at 1 kHz). The joint torques are published for every processed
sample, the other topics every ``publish_every`` processed samples. Parameters:
:class:`WrenchEstimatorConfig` fields (``config/wrench_estimator.yaml``); ``rfrr_enabled``,
``rfrr_learning``, ``contact_*``, ``require_same_stamp``, ``stale_timeout``,
``publish_every`` and ``enabled`` (false: FT wrenches and joint states are ignored, nothing
is published, as a stopped estimator) change at run time, the others rebuild the estimator
(its learnt RFRR state is lost).

In-process listeners (the composed ``torque_loop`` process, :mod:`icub_pmp.nodes.torque_loop`):
``joint_state_listener`` gets the bytes of every /joint_states message on arrival (before the
estimator looks at it), ``estimate_listener`` gets the joint torques of every processed sample
(stamp [ns], joint names, torques [N m]) before they are published.

In-process inputs (``in_process_inputs=True``, the composed ``robot_loop`` process,
:mod:`icub_sim_bridge.robot_loop_node`): the node does not subscribe to /joint_states and the arm
FT topics; the simulator in the same process hands each message's bytes over with
:meth:`take_joint_state` and :meth:`take_ft`, with the same checks and synchroniser.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
from geometry_msgs.msg import WrenchStamped
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import Imu, JointState
from std_msgs.msg import Bool
from std_srvs.srv import Trigger

from icub_pmp.dynamics.ft_offset_calibration import CalibrationError
from icub_pmp.dynamics.stamp_synchroniser import StampSynchroniser
from icub_pmp.dynamics.wrench_estimator import WrenchEstimator
from icub_pmp.dynamics.wrench_estimator_config import WrenchEstimatorConfig
from icub_pmp.errors import IcubPmpError, InvalidInput
from icub_pmp.kinematics.robot_spec import HANDS
from icub_pmp.ros.conversions import joint_state_arrays, wrench_to_array
from icub_pmp.ros.node_runner import spin_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.ros.raw_messages import (
    RawJointState,
    RawJointStateReader,
    RawJointStateWriter,
    RawWrenchStampedWriter,
    raw_wrench_stamped,
    read_joint_state,
)
from icub_pmp.ros.warning_throttle import WarningThrottle
from icub_pmp.time_jump_detector import TimeJumpDetector

__all__ = ["WrenchEstimatorNode", "main"]

#: parameters applied to the running estimator; any other change rebuilds it
_LIVE = {"rfrr_enabled", "rfrr_learning", "contact_force_on", "contact_force_off",
         "contact_min_samples", "require_same_stamp", "stale_timeout", "publish_every",
         "enabled"}
_FT_TOPIC = {"left": "l_arm_ft", "right": "r_arm_ft"}
_BUFFER = 64  # samples kept while waiting for the matching messages
_FT_KEY = {h: f"/ft/{t}" for h, t in _FT_TOPIC.items()}  # the synchroniser's stream names


class WrenchEstimatorNode(Node):
    """The wrench_estimator node (module doc)."""

    def __init__(self, in_process_inputs: bool = False) -> None:
        """``in_process_inputs``: joint states and arm FT wrenches come by direct calls
        (:meth:`take_joint_state`, :meth:`take_ft`; module doc), not from their topics."""
        super().__init__("wrench_estimator")
        self.params = ConfigParameters(self, WrenchEstimatorConfig,
                                       on_change=self._on_config_change)
        self.estimator = WrenchEstimator(self.config)
        self.names = list(self.estimator.joint_names)
        self._cached_names: list[str] | None = None  # the name list of self._idx
        self._valid_names: list[str] | None = None  # the name list last checked on arrival
        self._js_reader = RawJointStateReader()  # joint states read from their bytes
        self._idx: np.ndarray | None = None
        # joint states and FT wrenches are checked on arrival and buffered read (arrays)
        self.sync: StampSynchroniser[object] = StampSynchroniser(
            [_FT_KEY[h] for h in HANDS], _BUFFER)
        self.clock = TimeJumpDetector()
        self._imu: np.ndarray | None = None
        self._seen = 0
        self.samples = 0
        self.dropped = 0
        self.jumps = 0
        self.warn = WarningThrottle(self.get_logger())  # one budget per kind of warning
        # in-process listeners (module doc): the composed torque_loop process sets them
        self.joint_state_listener: Callable[[bytes], None] | None = None
        self.estimate_listener: Callable[[int, list[str], np.ndarray], None] | None = None

        sd = qos_profile_sensor_data
        self.pub_tau = self.create_publisher(JointState, "/estimated_joint_torques", sd)
        self.pub_ext = {h: self.create_publisher(
            WrenchStamped, f"/wrench_estimator/external_wrench/{h}_hand", sd) for h in HANDS}
        self.pub_ext_root = {h: self.create_publisher(
            WrenchStamped, f"/wrench_estimator/external_wrench_root/{h}_hand", sd)
            for h in HANDS}
        self.pub_contact = {h: self.create_publisher(
            Bool, f"/wrench_estimator/contact/{h}_hand", sd) for h in HANDS}
        self.pub_pred = {h: self.create_publisher(
            WrenchStamped, f"/wrench_estimator/predicted_ft/{_FT_TOPIC[h]}", sd) for h in HANDS}
        # reusable messages
        self._tau_writer = RawJointStateWriter(list(self.names))
        # the decimated wrench outputs are serialised directly too (six per publication)
        self._ext_writer = {h: RawWrenchStampedWriter(self.estimator.spec.hand_frame(h))
                            for h in HANDS}
        self._ext_root_writer = RawWrenchStampedWriter(self.estimator.spec.root_frame)
        self._pred_writer = {h: RawWrenchStampedWriter(_FT_TOPIC[h]) for h in HANDS}
        self._bool = {h: Bool() for h in HANDS}

        # raw subscriptions: the stamp is read from the CDR bytes and only the samples that
        # are processed get deserialised (sample_every > 1 then costs little)
        if not in_process_inputs:
            self.create_subscription(JointState, "/joint_states", self._on_joint_state, sd,
                                     raw=True)
            for h in HANDS:
                self.create_subscription(WrenchStamped, f"/ft/{_FT_TOPIC[h]}",
                                         lambda m, h=h: self._on_ft(h, m), sd, raw=True)
        self._imu_sub = None
        self._update_imu_subscription(self.config)
        self.create_service(Trigger, "~/calibrate", self._srv_calibrate)
        self._calibration_said = ""  # the last start-up calibration outcome logged
        self.get_logger().info(
            f"wrench_estimator: {len(self.names)} joints, FT convention "
            f"{self.config.ft_convention}, gravity from {self.config.gravity_source}, "
            f"RFRR {'on' if self.config.rfrr_enabled else 'off'} "
            f"(D={self.config.rfrr_features}), same-stamp sync "
            f"{'on' if self.config.require_same_stamp else 'off'}")

    # ------------------------------------------------------------------ parameters
    @property
    def config(self) -> WrenchEstimatorConfig:
        """The current configuration (``config/wrench_estimator.yaml``, run-time changes)."""
        return self.params.config

    def _on_config_change(self, old: WrenchEstimatorConfig, new: WrenchEstimatorConfig,
                          changed: frozenset[str]) -> None:
        if changed <= _LIVE:
            self.estimator.apply_live_config(new)
        else:
            self.estimator = WrenchEstimator(new)
            self.get_logger().info(f"estimator rebuilt for {sorted(changed)}")
        self._update_imu_subscription(new)
        if "enabled" in changed:
            self.sync.reset()
            self.get_logger().warning(
                "estimator enabled: estimating again" if new.enabled else
                "estimator disabled (enabled: false): no sample processed, nothing published")

    def _update_imu_subscription(self, config: WrenchEstimatorConfig) -> None:
        """Subscribe to /imu only while the gravity comes from it (saves the 1 kHz traffic)."""
        want = config.gravity_source == "imu"
        if want and self._imu_sub is None:
            self._imu_sub = self.create_subscription(Imu, "/imu", self._on_imu,
                                                     qos_profile_sensor_data)
        elif not want and self._imu_sub is not None:
            self.destroy_subscription(self._imu_sub)
            self._imu_sub = None
            self._imu = None

    # ------------------------------------------------------------------ calibration
    def _srv_calibrate(self, req: Trigger.Request, resp: Trigger.Response) -> Trigger.Response:
        """~/calibrate (module doc). Runs on the executor thread, between two samples."""
        try:
            r = self.estimator.calibrate_from_recent()
        except CalibrationError as exc:
            resp.success, resp.message = False, str(exc)
            self.get_logger().warning(str(exc))
            return resp
        resp.success = True
        resp.message = _describe_offsets(r.offsets, r.samples, r.spread)
        self.get_logger().info(resp.message)
        return resp

    def _report_startup_calibration(self) -> None:
        """Log the start-up calibration once it is made, and (throttled) why it waits."""
        est = self.estimator
        if est.calibrated and self._calibration_said != "done":
            self._calibration_said = "done"
            off = est.offsets
            self.get_logger().info("start-up " + _describe_offsets(
                np.array([off[h] for h in HANDS]), est.config.calibration_samples, 0.0))
        elif est.calibration_error and self._calibration_said != est.calibration_error:
            self._calibration_said = est.calibration_error
            if est.startup_calibration_expired:
                self.get_logger().error(est.calibration_error)
            else:
                self.warn("calibration", f"start-up calibration waits: {est.calibration_error}")

    # ------------------------------------------------------------------ inputs
    def _warn(self, kind: str, text: str) -> None:
        self.dropped += 1
        self.warn(kind, text)

    def _on_ft(self, hand: str, data: bytes) -> None:
        if not self.config.enabled:
            return
        try:
            try:  # the numbers straight from the bytes (raw_messages), else deserialise
                ns, w = raw_wrench_stamped(data)
            except InvalidInput:
                m = deserialize_message(data, WrenchStamped)
                ns = m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec
                w = wrench_to_array(m.wrench)
        except Exception as exc:  # a corrupt serialised message
            self._warn("ft", f"{_FT_KEY[hand]}: message dropped: cannot read it: {exc}")
            return
        if not np.isfinite(w).all():
            self._warn("ft", f"{_FT_KEY[hand]}: message at t = {ns * 1e-9:.3f} s dropped: "
                       "NaN or infinite wrench")
            return
        self.sync.add(_FT_KEY[hand], ns, w)
        if self.config.require_same_stamp and self.sync.has_primary(ns):
            self._try(ns)

    def take_joint_state(self, data: bytes) -> None:
        """A /joint_states message (its CDR bytes) handed over in-process (module doc)."""
        self._on_joint_state(data)

    def take_ft(self, hand: str, data: bytes) -> None:
        """The /ft/{l,r}_arm_ft message (its CDR bytes) of ``hand`` (left, right) handed over
        in-process (module doc)."""
        self._on_ft(hand, data)

    def _on_imu(self, msg: Imu) -> None:
        a = msg.linear_acceleration
        acc = np.array([a.x, a.y, a.z])
        if np.all(np.isfinite(acc)):
            self._imu = acc

    def _read_joint_state(self, data: bytes) -> RawJointState:
        """The joint state of ``data``, checked (raises InvalidInput): every joint of the
        model named (checked once per distinct name list), fields as long as the names,
        finite values."""
        msg = read_joint_state(self._js_reader, data)
        if msg.name is not self._valid_names:
            joint_state_arrays(msg, self.names)  # names, lengths and values checked
            self._valid_names = msg.name
            return msg
        n = len(msg.name)
        if len(msg.position) != n or len(msg.velocity) not in (0, n):
            raise InvalidInput(f"JointState has {len(msg.position)} positions and "
                               f"{len(msg.velocity)} velocities for {n} names")
        if not (math.isfinite(msg.position @ msg.position)
                and math.isfinite(msg.velocity @ msg.velocity)):
            raise InvalidInput("JointState contains NaN or infinite values")
        return msg

    def _on_joint_state(self, data: bytes) -> None:
        if self.joint_state_listener is not None:
            self.joint_state_listener(data)
        if not self.config.enabled:
            return
        try:
            msg = self._read_joint_state(data)
        except IcubPmpError as exc:
            self._warn("joint_state", f"/joint_states: a message dropped on arrival: {exc}")
            return
        ns = msg.stamp_ns
        jump = self.clock.observe(ns)
        if jump is not None:
            self.sync.reset()
            self.estimator.clear_history()
            self._seen = 0
            self.jumps += 1
            self.get_logger().warning(
                f"{jump.describe()} (a simulator restart?): stamp synchroniser, filters and "
                "contact flags cleared; estimating again from this sample",
                throttle_duration_sec=1.0)
        if self.config.require_same_stamp:
            self.sync.add_primary(ns, msg)
            self._try(ns)
            return
        try:
            ft = self.sync.latest(ns, self.config.stale_timeout)
        except InvalidInput as exc:
            self._warn("pairing", f"joint state at t = {ns * 1e-9:.3f} s skipped: {exc}")
            return
        self._process(ns, msg, {h: ft[_FT_KEY[h]] for h in HANDS})

    def _try(self, ns: int) -> None:
        """Process stamp ``ns`` if the joint state and both FT wrenches are there."""
        sample = self.sync.match(ns)
        if sample is not None:
            self._process(ns, sample.primary, {h: sample.secondary[_FT_KEY[h]] for h in HANDS})

    # ------------------------------------------------------------------ processing
    def _process(self, ns: int, msg: RawJointState, ft: dict[str, np.ndarray]) -> None:
        """Process one synchronised, checked sample (one in ``sample_every``)."""
        if not self.sync.release(ns):  # processed already, or older than the last sample
            return
        self._seen += 1
        if (self._seen - 1) % self.config.sample_every:
            return
        try:
            if msg.name is not self._cached_names:  # the index of this name list
                self._idx, self._cached_names = None, msg.name
            q, v, self._idx = joint_state_arrays(msg, self.names, self._idx)
            imu = self._imu if self.config.gravity_source == "imu" else None
            if self.config.gravity_source == "imu" and imu is None:
                raise InvalidInput("gravity_source is imu but no /imu message arrived yet")
            est = self.estimator.update(ns * 1e-9, q, v, ft, imu)
        except IcubPmpError as exc:
            self._warn("sample", f"sample at t = {ns * 1e-9:.3f} s dropped: {exc}")
            return
        self.samples += 1
        if self.estimate_listener is not None:  # in-process: before anything is published
            self.estimate_listener(ns, self.names, est.tau)
        if self.config.calibrate_at_startup and self._calibration_said != "done":
            self._report_startup_calibration()
        # serialised directly (raw_messages): the names are encoded once
        self.pub_tau.publish(self._tau_writer.write(ns, effort=est.tau))
        if self.samples % self.config.publish_every:
            return
        for h in HANDS:
            self.pub_ext[h].publish(self._ext_writer[h].write(ns, est.ext_hand[h]))
            self.pub_ext_root[h].publish(self._ext_root_writer.write(ns, est.ext_root[h]))
            self.pub_pred[h].publish(self._pred_writer[h].write(ns, est.ft_predicted[h]))
            b = self._bool[h]
            b.data = bool(est.contact[h])
            self.pub_contact[h].publish(b)


def _describe_offsets(offsets: np.ndarray, samples: int, spread: float) -> str:
    """One line for a user: the offsets per sensor (force [N], torque [N m])."""
    parts = [f"{_FT_TOPIC[h]} force {np.round(offsets[k, :3], 3).tolist()} N, torque "
             f"{np.round(offsets[k, 3:], 4).tolist()} N m" for k, h in enumerate(HANDS)]
    return (f"FT offsets calibrated over {samples} samples (joint spread "
            f"{np.degrees(spread):.3f} deg): " + "; ".join(parts))


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp wrench_estimator``)."""
    spin_node(WrenchEstimatorNode, args, "wrench_estimator")


if __name__ == "__main__":
    main()
