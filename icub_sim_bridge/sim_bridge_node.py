"""sim_bridge: the simulated iCub on ROS 2 (stands in for iCub_SIM / gazebo-yarp-plugins).

A thin adapter over :class:`icub_sim_bridge.Simulator` (all physics there). Topics, services
and frames:

publishes  /clock (every ``clock_decimation`` steps: 100 Hz of simulated time by default, as
           Gazebo publishes it at a low rate; /joint_states carries every step's stamp),
           /joint_states (every step: position [rad], velocity [rad/s],
           effort = applied torque [N m], stamp = sim time), /ft/{l_arm_ft,r_arm_ft,l_leg_ft,
           r_leg_ft} (WrenchStamped every step, frame = the URDF FT frame, child_to_parent:
           the wrench the distal link exerts on the proximal one), /imu (head_imu_0),
           /cam/{left,right}/image_raw + camera_info (rgb8 at camera_rate of sim time,
           frame l_eye_optical / r_eye_optical), /ground_truth/contact_wrench/{left,right}_hand
           (root_link, about the hand frame), /ground_truth/objects/{box,cylinder} (PoseStamped),
           /ground_truth/self_contacts (icub_interfaces/SelfContacts: the arms touching each
           other or the torso, root_link; an empty list when nothing touches)
           /ground_truth/object_contacts (icub_interfaces/ObjectContacts: robot links touching
           movable objects, and whether the object is the hand's grasped one)
subscribes /effort_command (JointState name + effort [N m]; any subset of joints; rejected
           whole with a throttled warning on unknown names, NaN/inf, length mismatch)
           /sim/status (icub_interfaces/SimStatus, reliable + transient local: running,
           holding or paused and why, divergences; on change and every wall second)
services   /sim/reset (ResetSim), /sim/set_object_pose (SetObjectPose), /sim/move_object
           (MoveObject: an object moved at constant velocity in simulated time), /sim/set_paused
           (std_srvs/SetBool), /sim/apply_wrench (ApplyWrench: bounded force, torque and
           duration; a request beyond the bounds is answered success=false with the reason),
           /sim/grasp (Grasp: the emulated grasp of a tabletop cube, a weld switched on only
           when the palm touches it, else success=false with the reason; or its release)

Modes (parameter ``mode``): ``free_run`` paced at ``real_time_factor`` (0 = as fast as
possible) or ``lockstep``: after publishing the state stamped t, the next step waits (up to
``lockstep_timeout`` s of wall time) for an /effort_command stamped exactly t.

Missing commands (:class:`~icub_sim_bridge.command_watchdog.CommandWatchdog`): when the
lockstep answer does not come in time, or in free run no command came for
``command_timeout`` of wall time, every joint goes on the simulator's hold at the posture it
had (never the last torques: a dead controller is a safe hold); said once in the log and on
/sim/status, and the next command hands the joints back (said too). Divergences of the
physics (``Simulator`` doc) are recovered from in the simulator; each is logged and reported
on /sim/status (``pause_on_divergence`` then pauses the simulation).

Streams other than /clock and /joint_states (FT, IMU, ground truth, cameras) are only filled
and published while they have subscribers (checked every 100 steps), as Gazebo's lazy
publishers do.

In-process (``in_process_commands=True``, the composed ``robot_loop`` process,
:mod:`icub_sim_bridge.robot_loop_node`, as gazebo_ros2_control runs the controller manager inside
the simulator): the node does not subscribe to /effort_command; every step's state is still
published, then handed to ``state_listener(stamp_ns, joint_states_bytes, {l_arm_ft,
r_arm_ft: bytes})`` on the physics thread, and commands come back by :meth:`take_effort`
(same checks, the same lockstep answer).

Threads: the physics loop runs on its own thread and is the only one touching MuJoCo; the
``EventsExecutor`` spins on the main thread (``spin_once`` in a loop: the Jazzy wheel's
``spin()`` ignores SIGINT): the effort callback validates and hands the command over, service
handlers queue a request that the physics loop executes between two steps and wait for its
answer (synchronous handlers). Cameras render on their own worker thread.

Before a joint is first named in an effort command (and after each reset) the simulator holds
it at its posture (``Simulator`` doc); the state published before a lockstep controller
subscribed goes unanswered: the loop steps on after ``lockstep_timeout``.
"""

from __future__ import annotations

import collections
import math
import threading
import time
from typing import Any, Callable, Mapping

import numpy as np
from geometry_msgs.msg import PoseStamped, WrenchStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, Imu, JointState
from std_srvs.srv import SetBool

from icub_interfaces.msg import ObjectContact as ObjectContactMsg
from icub_interfaces.msg import ObjectContacts, SelfContacts, SimStatus
from icub_interfaces.msg import SelfContact as SelfContactMsg
from icub_interfaces.srv import ApplyWrench, Grasp, MoveObject, ResetSim, SetObjectPose
from icub_pmp.errors import IcubPmpError, InvalidInput
from icub_pmp.ros.conversions import (
    pose_to_arrays,
    sec_to_time,
    validate_joint_state,
    wrench_to_array,
)
from icub_pmp.ros.node_runner import spin_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.ros.qos import LATCHED_QOS
from icub_pmp.ros.raw_messages import (
    RawJointState,
    RawJointStateReader,
    RawJointStateWriter,
    RawWrenchStampedWriter,
    read_joint_state,
)
from icub_sim_bridge import CameraRenderer, SimConfig, Simulator
from icub_sim_bridge.command_watchdog import CommandWatchdog
from icub_sim_bridge.lockstep_gate import LockstepGate
from icub_sim_bridge.realism_config import RealismConfig
from icub_sim_bridge.simulator import FT_SENSORS
from icub_sim_bridge.step_pacer import StepPacer

__all__ = ["SimBridge", "main"]

#: parameters that may change while running (the others shape the model: restart)
_RUNTIME_PARAMS = {"mode", "real_time_factor", "lockstep_timeout", "clock_decimation",
                   "imu_decimation", "ground_truth_decimation", "start_paused",
                   "command_timeout", "pause_on_divergence"}
#: the FT sensors whose samples go to an in-process ``state_listener`` (the arm sensors the
#: wrench estimator reads)
_IN_PROCESS_FT = ("l_arm_ft", "r_arm_ft")
_CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)


def _set_stamp(stamp: Any, ns: int) -> None:
    stamp.sec = ns // 1_000_000_000
    stamp.nanosec = ns % 1_000_000_000


def _set_vec(v: Any, a: np.ndarray) -> None:
    v.x, v.y, v.z = float(a[0]), float(a[1]), float(a[2])


def _check_command_values(msg: RawJointState) -> None:
    """The value checks of validate_joint_state for a command whose names were validated:
    effort as long as the names and finite, position and velocity empty or likewise."""
    n = len(msg.name)
    for field in ("position", "velocity", "effort"):
        values = getattr(msg, field)
        if len(values) != n and (field == "effort" or len(values)):
            raise InvalidInput(f"JointState.{field} has {len(values)} values for {n} names")
        if len(values) and not math.isfinite(values @ values):
            raise InvalidInput(f"JointState.{field} contains NaN or infinite values")


class _Command:
    """An accepted effort command: stamp [ns], joint indices, torques [N m]."""

    __slots__ = ("stamp_ns", "idx", "tau")

    def __init__(self, stamp_ns: int, idx: np.ndarray, tau: np.ndarray):
        self.stamp_ns, self.idx, self.tau = stamp_ns, idx, tau


class SimBridge(Node):
    """The sim_bridge node (module doc)."""

    def __init__(self, in_process_commands: bool = False) -> None:
        """``in_process_commands``: effort commands come by direct calls
        (:meth:`take_effort`), not from /effort_command (module doc)."""
        super().__init__("sim_bridge")
        self.params = ConfigParameters(
            self, (SimConfig, RealismConfig),
            read_only=(set(SimConfig.field_names()) - _RUNTIME_PARAMS)
            | set(RealismConfig.field_names()),
            reject=_keep_wall_time, on_change=self._on_config_change)
        self.sim = Simulator(self.config, realism=self.params.get(RealismConfig))
        self._names = list(self.sim.joint_names)
        self._valid_names = frozenset(self._names)
        # --- publishers
        sd = qos_profile_sensor_data
        self.pub_clock = self.create_publisher(Clock, "/clock", _CLOCK_QOS)
        self.pub_js = self.create_publisher(JointState, "/joint_states", sd)
        self.pub_ft = {n: self.create_publisher(WrenchStamped, f"/ft/{n}", sd)
                       for n in FT_SENSORS}
        self.pub_imu = self.create_publisher(Imu, "/imu", sd)
        self.pub_gt = {h: self.create_publisher(
            WrenchStamped, f"/ground_truth/contact_wrench/{h}_hand", sd)
            for h in ("left", "right")}
        self.pub_obj = {o: self.create_publisher(PoseStamped, f"/ground_truth/objects/{o}", sd)
                        for o in self.sim.object_names}
        self.pub_self = self.create_publisher(SelfContacts, "/ground_truth/self_contacts", sd)
        self.pub_objc = self.create_publisher(ObjectContacts, "/ground_truth/object_contacts",
                                              sd)
        # --- reusable messages (filled in place every step)
        self._clock_msg = Clock()
        self._js_writer = RawJointStateWriter(list(self._names))
        # the FT wrenches are serialised directly too (two or four per 1 kHz step)
        self._ft_writers = {n: RawWrenchStampedWriter(n) for n in FT_SENSORS}
        self._imu_msg = Imu()
        self._imu_msg.header.frame_id = "head_imu_0"
        self._gt_writer = RawWrenchStampedWriter("root_link")
        self._self_msg = SelfContacts()
        self._self_msg.header.frame_id = "root_link"
        self._objc_msg = ObjectContacts()
        self._objc_msg.header.frame_id = "root_link"
        self._obj_msgs = {}
        for o in self.sim.object_names:
            m = PoseStamped()
            m.header.frame_id = "root_link"
            self._obj_msgs[o] = m
        # --- cameras
        self.cameras: CameraRenderer | None = None
        if self.config.cameras_enabled:
            self._setup_cameras()
        # --- commands and requests (handed from the executor thread to the loop)
        self._cmd_lock = threading.Lock()
        self._pending: collections.deque[_Command] = collections.deque()
        self.lockstep = LockstepGate()
        self.pacer = StepPacer()
        self._requests: collections.deque[tuple[Callable[[], Any], list, threading.Event]] = \
            collections.deque()
        self._wake = threading.Event()
        self._active_cache: dict[int, bool] = {}
        self.rejected = 0
        self.paused = self.config.start_paused
        self.watchdog = CommandWatchdog()
        self._divergences_seen = 0
        self._pause_reason = "start_paused" if self.paused else ""
        self.pub_status = self.create_publisher(SimStatus, "/sim/status", LATCHED_QOS)
        self._status_msg = SimStatus()
        self._status_sent: tuple | None = None
        self._status_wall = 0.0
        # read from its bytes (raw_messages): the 1 kHz input of the lockstep loop
        self._effort_reader = RawJointStateReader()
        self._effort_names: list[str] | None = None  # names of the last valid command
        self._effort_idx = np.zeros(0, dtype=int)
        # in-process (module doc): the composed robot_loop process sets state_listener
        self.state_listener: Callable[[int, bytes, dict[str, bytes]], None] | None = None
        self._take_names: list[str] | None = None  # the name list of the last take_effort
        self._take_idx = np.zeros(0, dtype=int)
        if not in_process_commands:
            self.create_subscription(JointState, "/effort_command", self._on_effort, sd,
                                     raw=True)
        self.create_service(ResetSim, "/sim/reset", self._srv_reset)
        self.create_service(SetObjectPose, "/sim/set_object_pose", self._srv_set_object_pose)
        self.create_service(MoveObject, "/sim/move_object", self._srv_move_object)
        self.create_service(SetBool, "/sim/set_paused", self._srv_set_paused)
        self.create_service(ApplyWrench, "/sim/apply_wrench", self._srv_apply_wrench)
        self.create_service(Grasp, "/sim/grasp", self._srv_grasp)
        self.get_logger().info(
            f"sim_bridge: {len(self._names)} actuated joints, mode {self.config.mode}, "
            f"real_time_factor {self.config.real_time_factor}, cameras "
            f"{'on' if self.cameras else 'off'}, FT sign convention child_to_parent, realism "
            f"preset {self.params.get(RealismConfig).preset!r} (seed "
            f"{self.params.get(RealismConfig).seed})")

    # ------------------------------------------------------------------ parameters
    @property
    def config(self) -> SimConfig:
        """The current configuration (``config/sim_bridge.yaml``, run-time changes)."""
        return self.params.get(SimConfig)

    def _on_config_change(self, old: tuple, new: tuple, changed: frozenset[str]) -> None:
        if "start_paused" in changed:
            self._set_paused(new[0].start_paused, "start_paused parameter")

    def _set_paused(self, paused: bool, why: str) -> None:
        if paused != self.paused:
            self.get_logger().info(f"{'paused' if paused else 'running'} at t = "
                                   f"{self.sim.time:.3f} s ({why})")
        self.paused = paused
        self._pause_reason = why if paused else ""
        self.watchdog.restart()

    # ------------------------------------------------------------------ cameras
    def _setup_cameras(self) -> None:
        cam = self.sim.built.camera
        sd = qos_profile_sensor_data
        self.pub_img = {s: self.create_publisher(Image, f"/cam/{s}/image_raw", sd)
                        for s in ("left", "right")}
        self.pub_info = {s: self.create_publisher(CameraInfo, f"/cam/{s}/camera_info", sd)
                         for s in ("left", "right")}
        self._info = {}
        for side, frame in (("left", "l_eye_optical"), ("right", "r_eye_optical")):
            info = CameraInfo()
            info.header.frame_id = frame
            info.width, info.height = cam.width, cam.height
            info.distortion_model = "plumb_bob"
            info.d = [0.0] * 5
            info.k = [cam.fx, 0.0, cam.cx, 0.0, cam.fy, cam.cy, 0.0, 0.0, 1.0]
            info.r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
            info.p = [cam.fx, 0.0, cam.cx, 0.0, 0.0, cam.fy, cam.cy, 0.0, 0.0, 0.0, 1.0, 0.0]
            self._info[side] = info
        self.cameras = CameraRenderer(self.sim.model, cam, self.config.camera_threaded,
                                      on_frame=self._publish_images)
        self._cam_period_ns = int(round(1e9 / self.config.camera_rate))
        self._next_cam_ns = 0

    def _publish_images(self, t: float, images: dict[str, np.ndarray]) -> None:
        ns = int(round(t * 1e9))
        imp = self.sim.imperfections
        for side, img in images.items():
            if imp is not None:  # realism: pixel noise (camera_info stays nominal)
                img = imp.noisy_image(img)
            msg = Image()
            _set_stamp(msg.header.stamp, ns)
            msg.header.frame_id = self._info[side].header.frame_id
            msg.height, msg.width = img.shape[0], img.shape[1]
            msg.encoding = "rgb8"
            msg.step = img.shape[1] * 3
            msg.data = img.tobytes()
            self.pub_img[side].publish(msg)
            info = self._info[side]
            _set_stamp(info.header.stamp, ns)
            self.pub_info[side].publish(info)

    # ------------------------------------------------------------------ effort commands
    def _on_effort(self, data: bytes) -> None:
        try:
            msg = read_joint_state(self._effort_reader, data)
        except IcubPmpError as exc:
            self.rejected += 1
            self.get_logger().warning(f"/effort_command rejected ({self.rejected} so far): "
                                      f"{exc}", throttle_duration_sec=1.0)
            return
        stamp_ns = msg.stamp_ns
        try:
            if msg.name is self._effort_names:  # same names as the last valid command
                _check_command_values(msg)
                idx = self._effort_idx
            else:
                validate_joint_state(msg, required=("effort",), valid_names=self._valid_names)
                idx = self.sim.indices(msg.name)
                self._effort_names, self._effort_idx = msg.name, idx
            tau = msg.effort
        except IcubPmpError as exc:
            self.rejected += 1
            self.get_logger().warning(f"/effort_command rejected ({self.rejected} so far): "
                                      f"{exc}", throttle_duration_sec=1.0)
            self.lockstep.answer(stamp_ns)  # answered, with nothing usable: keep the last one
            return
        with self._cmd_lock:
            self._pending.append(_Command(stamp_ns, idx, tau))
        self.watchdog.command()
        self.lockstep.answer(stamp_ns)

    def take_effort(self, stamp_ns: int, names: list[str], tau: np.ndarray) -> None:
        """An effort command (torques ``tau`` [N m] of ``names``, answering the state stamped
        ``stamp_ns`` [ns]) handed over in-process (module doc); checked as /effort_command."""
        try:
            if names is not self._take_names:  # a new name list: check and index it once
                idx = self.sim.indices(list(names))
                self._take_names, self._take_idx = names, idx
            tau = np.array(tau, dtype=float)
            if tau.shape != self._take_idx.shape or not math.isfinite(tau @ tau):
                raise InvalidInput(f"effort command of {tau.size} values for "
                                   f"{len(names)} names, or NaN/inf")
        except IcubPmpError as exc:
            self._take_names = None
            self.rejected += 1
            self.get_logger().warning(f"in-process effort command rejected ({self.rejected} "
                                      f"so far): {exc}", throttle_duration_sec=1.0)
            self.lockstep.answer(stamp_ns)
            return
        with self._cmd_lock:
            self._pending.append(_Command(stamp_ns, self._take_idx, tau))
        self.watchdog.command()
        self.lockstep.answer(stamp_ns)

    def _apply_pending(self) -> None:
        if not self._pending:
            return
        with self._cmd_lock:
            cmds = list(self._pending)
            self._pending.clear()
        for c in cmds:
            self.sim.command_indices(c.idx, c.tau)
        if self.watchdog.resume():
            self.get_logger().info(f"/effort_command is back at t = {self.sim.time:.3f} s: "
                                   "the commanded torques drive the joints again")
            self._publish_status(force=True)

    def _hold(self, reason: str | None) -> None:
        """Put every joint on the simulator's hold (a missing command, ``reason`` from the
        watchdog; None: already holding)."""
        if reason is None:
            return
        with self._cmd_lock:
            self._pending.clear()  # late answers to earlier states are not applied
        self.sim.hold()
        self.get_logger().warning(f"{reason}: every joint on the simulator's hold at its "
                                  "current posture (not the last torques) until commands "
                                  "come back")
        self._publish_status(force=True)

    # ------------------------------------------------------------------ services
    def _run_in_loop(self, fn: Callable[[], Any], timeout: float = 10.0) -> tuple[bool, str]:
        """Queue ``fn`` for the physics loop and wait for it: (success, message)."""
        result: list = []
        done = threading.Event()
        self._requests.append((fn, result, done))
        self._wake.set()
        if not done.wait(timeout):
            return False, f"the simulation loop did not answer within {timeout} s"
        return result[0]

    def _drain_requests(self) -> None:
        while self._requests:
            fn, result, done = self._requests.popleft()
            try:
                msg = fn()
                result.append((True, msg or "ok"))
            except IcubPmpError as exc:
                result.append((False, str(exc)))
            except Exception as exc:  # never let a request kill the loop
                result.append((False, f"{type(exc).__name__}: {exc}"))
            done.set()

    def _srv_reset(self, req: ResetSim.Request, resp: ResetSim.Response) -> ResetSim.Response:
        posture = req.posture or self.config.initial_posture

        def do() -> str:
            self.sim.reset(posture)
            with self._cmd_lock:
                self._pending.clear()
            return f"reset to posture {posture!r} at t = {self.sim.time:.3f} s"

        resp.success, resp.message = self._run_in_loop(do)
        return resp

    def _srv_set_object_pose(self, req: SetObjectPose.Request, resp: SetObjectPose.Response
                             ) -> SetObjectPose.Response:
        def do() -> str:
            p, q = pose_to_arrays(req.pose)
            self.sim.set_object_pose(req.name, p, q)
            return f"{req.name} at {np.round(p, 4).tolist()}"

        resp.success, resp.message = self._run_in_loop(do)
        return resp

    def _srv_move_object(self, req: MoveObject.Request, resp: MoveObject.Response
                         ) -> MoveObject.Response:
        times: list[float] = []

        def do() -> str:
            p, q = pose_to_arrays(req.pose)
            v = [req.velocity.x, req.velocity.y, req.velocity.z]
            times.extend(self.sim.move_object(req.name, p, v, req.duration, q))
            return (f"{req.name} moves from {np.round(p, 4).tolist()} at "
                    f"{np.round(v, 4).tolist()} m/s for {req.duration:g} s of simulated time "
                    f"(t = {times[0]:.3f} to {times[1]:.3f} s)")

        resp.success, resp.message = self._run_in_loop(do)
        if times:
            resp.start, resp.end = sec_to_time(times[0]), sec_to_time(times[1])
        return resp

    def _srv_set_paused(self, req: SetBool.Request, resp: SetBool.Response) -> SetBool.Response:
        def do() -> str:
            self._set_paused(bool(req.data), "/sim/set_paused")
            self._publish_status(force=True)
            return f"{'paused' if self.paused else 'running'} at t = {self.sim.time:.3f} s"

        resp.success, resp.message = self._run_in_loop(do)
        return resp

    def _srv_apply_wrench(self, req: ApplyWrench.Request, resp: ApplyWrench.Response
                          ) -> ApplyWrench.Response:
        def do() -> str:
            w = wrench_to_array(req.wrench)
            self.sim.apply_wrench(req.target, w[:3], w[3:], req.duration)
            return f"wrench {w.tolist()} on {req.target} for {req.duration} s"

        resp.success, resp.message = self._run_in_loop(do)
        return resp

    def _srv_grasp(self, req: Grasp.Request, resp: Grasp.Response) -> Grasp.Response:
        def do() -> str:
            if req.attach:
                self.sim.grasp(req.object, req.hand)
                return f"{req.object} attached to the {req.hand} palm (emulated grasp)"
            held = self.sim.grasped.get(req.hand)
            if held is not None and req.object and held != req.object:
                raise InvalidInput(f"release {req.object!r}: the {req.hand} hand holds {held!r}")
            released = self.sim.release(req.hand)
            return (f"{released} released by the {req.hand} hand" if released else
                    f"the {req.hand} hand held nothing")

        resp.success, resp.message = self._run_in_loop(do)
        return resp

    # ------------------------------------------------------------------ publishing
    def _active(self, pub: Any) -> bool:
        """Whether ``pub`` has subscribers (refreshed every 100 steps): streams nobody reads
        are not filled (/clock and /joint_states always are)."""
        key = id(pub)
        if self.sim.steps % 100 == 0 or key not in self._active_cache:
            self._active_cache[key] = pub.get_subscription_count() > 0
        return self._active_cache[key]

    def _publish_state(self) -> None:
        sim = self.sim
        ns = int(round(sim.time * 1e9))
        self.lockstep.expect(ns)
        if sim.steps % self.config.clock_decimation == 0:
            _set_stamp(self._clock_msg.clock, ns)
            self.pub_clock.publish(self._clock_msg)
        st = sim.joint_state()
        # serialised directly (raw_messages): the names are encoded once, not per message
        js = self._js_writer.write(ns, st.position, st.velocity, st.effort)
        self.pub_js.publish(js)
        ft = sim.ft_all()
        listener = self.state_listener
        ft_bytes: dict[str, bytes] = {}
        for k, n in enumerate(FT_SENSORS):
            if listener is not None and n in _IN_PROCESS_FT:
                ft_bytes[n] = self._ft_writers[n].write(ns, ft[k])
                if self._active(self.pub_ft[n]):
                    self.pub_ft[n].publish(ft_bytes[n])
            elif self._active(self.pub_ft[n]):
                self.pub_ft[n].publish(self._ft_writers[n].write(ns, ft[k]))
        step = sim.steps
        if step % self.config.imu_decimation == 0 and self._active(self.pub_imu):
            imu = sim.imu()
            m = self._imu_msg
            _set_stamp(m.header.stamp, ns)
            q = imu.orientation
            m.orientation.w, m.orientation.x, m.orientation.y, m.orientation.z = (
                float(q[0]), float(q[1]), float(q[2]), float(q[3]))
            _set_vec(m.angular_velocity, imu.angular_velocity)
            _set_vec(m.linear_acceleration, imu.linear_acceleration)
            self.pub_imu.publish(m)
        if step % self.config.ground_truth_decimation == 0:
            for h, pub in self.pub_gt.items():
                if self._active(pub):
                    w = sim.contact_wrench(h)
                    pub.publish(self._gt_writer.write(ns, np.r_[w.force, w.torque]))
            for o, pub in self.pub_obj.items():
                if not self._active(pub):
                    continue
                pose = sim.object_pose(o)
                m = self._obj_msgs[o]
                _set_stamp(m.header.stamp, ns)
                _set_vec(m.pose.position, pose.position)
                q = pose.quaternion
                m.pose.orientation.w, m.pose.orientation.x = float(q[0]), float(q[1])
                m.pose.orientation.y, m.pose.orientation.z = float(q[2]), float(q[3])
                pub.publish(m)
            if self._active(self.pub_self):
                self._publish_contacts(ns, self._self_msg, self.sim.self_contacts(),
                                       self.pub_self)
            if self._active(self.pub_objc):
                self._publish_object_contacts(ns)
        if self.cameras is not None and ns >= self._next_cam_ns and (
                self._active(self.pub_img["left"]) or self._active(self.pub_img["right"])
                or self._active(self.pub_info["left"]) or self._active(self.pub_info["right"])):
            self._next_cam_ns = ns + self._cam_period_ns
            self.cameras.request(sim.data)
        if listener is not None:  # in-process (module doc): estimator, controller, command
            listener(ns, js, ft_bytes)

    def _publish_contacts(self, ns: int, m: SelfContacts, found: list, pub: Any) -> None:
        """Publish the contact records ``found`` (Simulator.self_contacts/object_contacts)."""
        _set_stamp(m.header.stamp, ns)
        contacts = []
        for c in found:
            cm = SelfContactMsg()
            cm.body1, cm.body2, cm.kind = c.body1, c.body2, c.kind
            _set_vec(cm.position, c.position)
            _set_vec(cm.force, c.force)
            cm.normal_force, cm.depth = c.normal_force, c.depth
            contacts.append(cm)
        m.contacts = contacts
        pub.publish(m)

    def _publish_object_contacts(self, ns: int) -> None:
        m = self._objc_msg
        _set_stamp(m.header.stamp, ns)
        contacts = []
        for c in self.sim.object_contacts():
            cm = ObjectContactMsg()
            cm.object, cm.body, cm.arm, cm.grasped = c.object, c.body, c.arm, c.grasped
            _set_vec(cm.position, c.position)
            cm.normal_force = c.normal_force
            contacts.append(cm)
        m.contacts = contacts
        self.pub_objc.publish(m)

    # ------------------------------------------------------------------ status
    def _check_divergence(self) -> None:
        """Say so once per divergence the simulator recovered from (and pause if asked)."""
        d = self.sim.last_divergence
        if d is None or d.count == self._divergences_seen:
            return
        new = d.count - self._divergences_seen
        self._divergences_seen = d.count
        with self._cmd_lock:
            self._pending.clear()
        more = f" ({new} since the last report)" if new > 1 else ""
        self.get_logger().error(
            f"the physics diverged at t = {d.time:.3f} s{more}: {d.reason}; restored the "
            f"state of t = {d.restored_time:.3f} s at rest, scripted wrenches cleared, every "
            "joint on the simulator's hold until commanded again (simulated time goes on)",
            throttle_duration_sec=1.0)
        if self.config.pause_on_divergence:
            self._set_paused(True, f"pause_on_divergence after the divergence at t = "
                                   f"{d.time:.3f} s")
        self._publish_status(force=True)

    def _publish_status(self, force: bool = False) -> None:
        """/sim/status when something changed, and every second of wall time."""
        w = self.watchdog
        status = "paused" if self.paused else "holding" if w.holding else "running"
        message = self._pause_reason if self.paused else w.reason
        key = (status, message, self.config.mode, self.sim.divergences)
        now = time.monotonic()
        if not force and key == self._status_sent and now - self._status_wall < 1.0:
            return
        self._status_sent, self._status_wall = key, now
        m = self._status_msg
        _set_stamp(m.header.stamp, int(round(self.sim.time * 1e9)))
        m.status, m.message, m.mode = status, message, self.config.mode
        m.command_wall_age = w.command_age()
        m.steps = self.sim.steps
        m.lockstep_timeouts = self.lockstep.timeouts
        m.rejected_commands = self.rejected
        d = self.sim.last_divergence
        m.divergences = self.sim.divergences
        m.last_divergence_time = -1.0 if d is None else d.time
        m.last_divergence = "" if d is None else (
            f"{d.reason}: restored the state of t = {d.restored_time:.3f} s at rest, "
            "scripted wrenches cleared")
        self.pub_status.publish(m)

    # ------------------------------------------------------------------ the loop
    def run(self, should_stop: Callable[[], bool]) -> None:
        """Step, publish, pace / lockstep until ``should_stop()`` (the physics thread)."""
        self._publish_state()
        self._publish_status(force=True)
        while not should_stop():
            if self._requests:
                self._drain_requests()
            if self.paused:
                self._wake.wait(0.05)
                self._wake.clear()
                self.pacer.restart(self.sim.time)
                self.watchdog.restart()
                self._publish_status()
                continue
            cfg = self.config
            if cfg.mode == "lockstep":
                if not self.lockstep.wait(cfg.lockstep_timeout):
                    if should_stop():
                        break
                    self._hold(self.watchdog.missed_answer(self.sim.time,
                                                           cfg.lockstep_timeout))
                self.pacer.restart(self.sim.time)
            else:
                self._hold(self.watchdog.check(cfg.command_timeout))
            self._apply_pending()
            self.sim.step()
            if self.sim.divergences != self._divergences_seen:
                self._check_divergence()
            self._publish_state()
            if self.sim.steps % 100 == 0:
                self._publish_status()
            if cfg.mode == "free_run":
                wait = self.pacer.wait_time(self.sim.time, cfg.real_time_factor)
                if wait > 0:
                    self._wake.wait(wait)
                    self._wake.clear()

    def destroy_node(self) -> None:
        """Stop the camera worker, then destroy the node."""
        if self.cameras is not None:
            self.cameras.close()
            self.cameras = None
        super().destroy_node()

    @property
    def timeouts(self) -> int:
        """Lockstep steps taken without their answer."""
        return self.lockstep.timeouts


def _keep_wall_time(params: Mapping[str, Any]) -> str | None:
    """The simulator is the clock: it never runs on /clock itself."""
    if params.get("use_sim_time"):
        return "sim_bridge is the clock: use_sim_time must stay false"
    return None


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp sim_bridge``): the executor spins on the main thread,
    the physics loop (:meth:`SimBridge.run`) on its own; a failure of the loop is logged and
    ends the process (status 1)."""
    spin_node(SimBridge, args, "sim_bridge", worker=SimBridge.run)


if __name__ == "__main__":
    main()
