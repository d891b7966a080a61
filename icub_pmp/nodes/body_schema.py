"""body_schema: motor babbling in the running graph, the data the learned body schema needs.

A thin adapter over :mod:`icub_pmp.body_schema` (:class:`MotorBabbling`, :class:`MarkerDetector`)
and the vision cores (:class:`HeadCameras`, :class:`StereoTriangulator`):

services    /body_schema/start_babbling (icub_interfaces/StartBabbling): babble an arm (7
            joints) or torso + arm (10) for a sample budget; answers at once.
            /body_schema/stop_babbling (std_srvs/Trigger): stop now and save what was kept.
publishes   /body_schema/progress (icub_interfaces/BabblingProgress, reliable, transient
            local): samples, budget, attempts, dropped, visible fraction, rates, dataset.
            /joint_trajectory (trajectory_msgs/JointTrajectory): the babbled arm's min-jerk
            moves, executed by the impedance controller.
calls       /gaze/look_at (icub_interfaces/LookAt, the gaze_controller): the head looks at
            where the URDF model expects the hand, so the hand stays in view.
subscribes  /joint_states (own thread, 2 s of history), /cam/{left,right}/image_raw,
            /cam/{left,right}/camera_info.

Per posture: a random target within the URDF limits, a look at the hand's expected position,
the move, ``settle_time``, then the first stereo pair stamped after it: the marker's centroid
in each image (OpenCV colour threshold), triangulated with the camera poses at the image's
stamp. Postures whose marker is not seen in both images are dropped and counted. The ground
truth (the marker's position by forward kinematics of the measured joints at the image stamp,
with the simulator's ``marker_offset``) is stored apart, for evaluation only. The dataset is
written to ``data_dir`` when the budget is reached or babbling is stopped.

Parameters: :class:`~icub_pmp.body_schema.BabblingConfig` and
:class:`~icub_pmp.body_schema.MarkerDetectorConfig` (``config/body_schema.yaml``).
"""

from __future__ import annotations

import datetime
import math
import threading
import time
from pathlib import Path

import numpy as np
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from sensor_msgs.msg import CameraInfo, Image
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from icub_interfaces.msg import BabblingProgress
from icub_interfaces.srv import LookAt, StartBabbling
from icub_pmp.body_schema import BabblingConfig, MarkerDetector, MarkerDetectorConfig
from icub_pmp.body_schema.babbling import (
    HEAD_JOINTS,
    BabblingSample,
    MotorBabbling,
    min_jerk_move,
)
from icub_pmp.config import repo_root
from icub_pmp.errors import IcubPmpError, InvalidInput
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics
from icub_pmp.kinematics.robot_model import IcubModel
from icub_pmp.kinematics.robot_spec import HANDS, RobotSpec
from icub_pmp.ros.conversions import arrays_to_trajectory, image_to_array, time_to_sec
from icub_pmp.ros.joint_state_cache import JointStateCache
from icub_pmp.ros.node_runner import run_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.vision.head_cameras import HeadCameras
from icub_pmp.vision.stereo_triangulator import StereoTriangulator

__all__ = ["BodySchemaNode", "main"]

SIDES = ("left", "right")
_LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)


class _Stopped(Exception):
    """The run was stopped (service, shutdown)."""


class BodySchemaNode(Node):
    """Serve babbling; publish its progress (module doc)."""

    def __init__(self) -> None:
        super().__init__("body_schema")
        self.params = ConfigParameters(self, (BabblingConfig, MarkerDetectorConfig))
        self.spec = RobotSpec.load()
        self.model = IcubModel(self.spec)
        self.cameras = HeadCameras(self.model)
        self.joints = JointStateCache(self, history=2.0)
        self.intrinsics = {s: CameraIntrinsics() for s in SIDES}
        self._images: dict[str, Image | None] = {s: None for s in SIDES}
        self._image_lock = threading.Lock()
        sd = qos_profile_sensor_data
        self.subs = [self.create_subscription(Image, f"/cam/{s}/image_raw",
                                              lambda m, s=s: self._on_image(s, m), sd)
                     for s in SIDES]
        self.subs += [self.create_subscription(CameraInfo, f"/cam/{s}/camera_info",
                                               lambda m, s=s: self._on_info(s, m), sd)
                      for s in SIDES]
        self.pub_traj = self.create_publisher(JointTrajectory, "/joint_trajectory", 10)
        self.pub_progress = self.create_publisher(BabblingProgress, "/body_schema/progress",
                                                  _LATCHED)
        self.gaze = self.create_client(LookAt, "/gaze/look_at")
        self.create_service(StartBabbling, "/body_schema/start_babbling", self._on_start)
        self.create_service(Trigger, "/body_schema/stop_babbling", self._on_stop)
        self._run_lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._runs = 0
        self._progress = BabblingProgress(message="idle")
        self.pub_progress.publish(self._progress)
        self.get_logger().info("body_schema: serving /body_schema/start_babbling and "
                               "/body_schema/stop_babbling")

    # ------------------------------------------------------------------ parameters
    @property
    def config(self) -> BabblingConfig:
        """Babbling parameters (``config/body_schema.yaml``)."""
        return self.params.get(BabblingConfig)

    def data_dir(self) -> Path:
        """Folder of the datasets (``data_dir`` or ``data/body_schema`` in the repository)."""
        return Path(self.config.data_dir) if self.config.data_dir else (
            repo_root() / "data" / "body_schema")

    # ------------------------------------------------------------------ sensors
    def _on_image(self, side: str, msg: Image) -> None:
        with self._image_lock:
            self._images[side] = msg

    def _on_info(self, side: str, msg: CameraInfo) -> None:
        k = [float(v) for v in msg.k]
        if not (k[0] > 0 and k[4] > 0 and all(math.isfinite(v) for v in k)):
            self.get_logger().warning(f"dropping /cam/{side}/camera_info: bad K {k}",
                                      throttle_duration_sec=5.0)
            return
        self.intrinsics[side] = CameraIntrinsics(int(msg.width), int(msg.height), k[0], k[4],
                                                 k[2], k[5])

    # ------------------------------------------------------------------ services
    def _on_start(self, req: StartBabbling.Request, res: StartBabbling.Response
                  ) -> StartBabbling.Response:
        c = self.config
        try:
            arm = req.arm or c.arm
            if arm not in HANDS:
                raise InvalidInput(f"arm: expected one of {HANDS}, got {arm!r}")
            budget = int(req.samples) or c.samples
            name = req.dataset_name or (
                f"babble_{arm}_{datetime.datetime.now().strftime('%Y%m%d_%H%M%S')}")
            if "/" in name or name.startswith("."):
                raise InvalidInput(f"dataset_name: a plain file name expected, got {name!r}")
            path = self.data_dir() / (name if name.endswith(".npz") else name + ".npz")
            with self._run_lock:
                if self._thread is not None and self._thread.is_alive():
                    raise InvalidInput("babbling is already running; stop it first "
                                       "(/body_schema/stop_babbling)")
                use_torso = bool(req.use_torso or c.use_torso)
                joints = (self.spec.torso_joints if use_torso else ()) + self.spec.arm_joints(arm)
                idx = self.model.indices(joints)
                babbling = MotorBabbling(joints, self.model.lower[idx], self.model.upper[idx],
                                         arm, seed=c.seed + self._runs, limit_margin=c.limit_margin)
                self._runs += 1
                self._stop.clear()
                self._thread = threading.Thread(
                    target=self._run, args=(babbling, budget, path, c), daemon=True,
                    name="body_schema-babbling")
                self._thread.start()
            res.success, res.dataset_path = True, str(path)
            res.message = (f"babbling the {arm} arm ({len(joints)} joints) for {budget} "
                           f"samples; dataset {path}")
            self.get_logger().info(res.message)
        except IcubPmpError as exc:
            res.success, res.message = False, str(exc)
            self.get_logger().warning(f"/body_schema/start_babbling rejected: {exc}")
        return res

    def _on_stop(self, req: Trigger.Request, res: Trigger.Response) -> Trigger.Response:
        thread = self._thread
        if thread is None or not thread.is_alive():
            res.success, res.message = False, "not babbling"
            return res
        self._stop.set()
        res.success = True
        res.message = f"stopping; the dataset goes to {self._progress.dataset_path}"
        return res

    # ------------------------------------------------------------------ the run
    def _run(self, babbling: MotorBabbling, budget: int, path: Path, c: BabblingConfig) -> None:
        wall0 = time.monotonic()
        first = self.joints.latest() if self.joints.wait_for_first(30.0) else None
        sim0 = first.t if first is not None else 0.0
        note = "budget reached"
        self._publish(babbling, budget, path, True, wall0, sim0, "started")
        try:
            if first is None:
                raise InvalidInput("no /joint_states within 30 s")
            while len(babbling.samples) < budget:
                if self._stop.is_set():
                    raise _Stopped
                reason = self._attempt(babbling, c)
                self._publish(babbling, budget, path, True, wall0, sim0,
                              reason or "sample kept")
        except _Stopped:
            note = "stopped"
        except IcubPmpError as exc:
            note = f"failed: {exc}"
            self.get_logger().error(f"babbling {note}")
        except Exception as exc:  # never let the run kill the node
            note = f"failed: {type(exc).__name__}: {exc}"
            self.get_logger().error(f"babbling {note}")
        meta = {"budget": budget, "end": note, "hand_frame": self.spec.hand_frame(babbling.arm),
                "marker_offset": list(c.marker_offset), "wall_s": time.monotonic() - wall0,
                "sim_s": self._sim_now() - sim0, "move_time": c.move_time,
                "settle_time": c.settle_time, "look_at_hand": c.look_at_hand,
                "intrinsics": {s: list(self.intrinsics[s].K.ravel()) for s in SIDES},
                "fixed": {j: v for j, v in (first.positions.items() if first else ())
                          if j not in babbling.joint_names and j in self.spec.upper_body_joints}}
        saved = babbling.save(path, meta)
        self._publish(babbling, budget, saved, False, wall0, sim0,
                      f"{note}: {len(babbling.samples)} samples saved to {saved}")
        self.get_logger().info(f"babbling {note}: {len(babbling.samples)} samples, "
                               f"{babbling.dropped} dropped, saved to {saved}")

    def _sim_now(self) -> float:
        s = self.joints.latest()
        return s.t if s is not None else 0.0

    def _wait_sim(self, t_end: float, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while self._sim_now() < t_end:
            if self._stop.is_set():
                raise _Stopped
            if time.monotonic() > deadline:
                raise InvalidInput(f"simulated time did not reach {t_end:.2f} s within "
                                   f"{timeout:.0f} s (is the simulator running?)")
            time.sleep(0.01)

    def _attempt(self, babbling: MotorBabbling, c: BabblingConfig) -> str | None:
        """One babbled posture; the drop reason, or None when the sample was kept."""
        now = self.joints.latest()
        arm_frame = self.spec.hand_frame(babbling.arm)
        target = babbling.next_target()
        q_now = np.array([now.positions.get(j, 0.0) for j in babbling.joint_names])
        if c.look_at_hand:
            q_model = self.model.q_from_dict(now.positions)
            q_model[self.model.indices(babbling.joint_names)] = target
            expected = self.model.frame_pose(q_model, arm_frame).translation
            self._look_at(expected, c.look_duration)
        vmax = np.array([self.spec.velocity_limit(j) for j in babbling.joint_names])
        amax = np.array([self.spec.acceleration_limit(j) for j in babbling.joint_names])
        t, q, qd = min_jerk_move(q_now, target, vmax, amax, c.move_time)
        self.pub_traj.publish(arrays_to_trajectory(babbling.joint_names, t, q, qd))
        t_settled = now.t + t[-1] + c.settle_time
        self._wait_sim(t_settled, c.move_timeout + t[-1])
        pair = self._stereo_after(t_settled, c.image_timeout)
        if pair is None:
            babbling.drop("no fresh stereo pair")
            return "no fresh stereo pair"
        stamp, images = pair
        state = self.joints.at(stamp)
        if state is None or abs(state.t - stamp) > 0.05:
            babbling.drop("no joint state at the image stamp")
            return "no joint state at the image stamp"
        det = self.detector.detect(images["left"]), self.detector.detect(images["right"])
        if not (det[0].found and det[1].found):
            babbling.drop("marker not seen in both images")
            return "marker not seen in both images"
        poses = self.cameras.poses(state.positions)
        tri = StereoTriangulator(self.intrinsics["left"], self.intrinsics["right"])
        seen = tri.triangulate((det[0].u, det[0].v), (det[1].u, det[1].v), poses.T_root_left,
                               poses.T_root_right).position
        pose = self.model.frame_pose(self.model.q_from_dict(state.positions), arm_frame)
        truth = pose.translation + pose.rotation @ np.asarray(c.marker_offset, dtype=float)
        babbling.record(BabblingSample(
            t=stamp,
            q=np.array([state.positions[j] for j in babbling.joint_names]),
            head=np.array([state.positions.get(j, 0.0) for j in HEAD_JOINTS]),
            pixels=np.array([det[0].u, det[0].v, det[1].u, det[1].v]),
            hand_seen=seen, ground_truth=truth))
        return None

    @property
    def detector(self) -> MarkerDetector:
        """The marker detector of the current parameters."""
        cfg = self.params.get(MarkerDetectorConfig)
        if getattr(self, "_detector", None) is None or self._detector.config != cfg:
            self._detector = MarkerDetector(cfg)
        return self._detector

    def _look_at(self, point: np.ndarray, duration: float) -> None:
        """Ask the gaze controller to look at ``point`` (no wait; a failure is logged)."""
        if not self.gaze.service_is_ready():
            self.get_logger().warning("/gaze/look_at not available: the head does not follow "
                                      "the hand", throttle_duration_sec=10.0)
            return
        req = LookAt.Request()
        req.target.header.frame_id = "root_link"
        req.target.point.x, req.target.point.y, req.target.point.z = (float(v) for v in point)
        req.duration = float(duration)
        req.wait = False
        self.gaze.call_async(req)

    def _stereo_after(self, t: float, timeout: float
                      ) -> tuple[float, dict[str, np.ndarray]] | None:
        """The first stereo pair (same stamp) stamped at or after ``t`` [s]: (stamp, RGB)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self._stop.is_set():
                raise _Stopped
            with self._image_lock:
                left, right = self._images["left"], self._images["right"]
            if left is not None and right is not None:
                tl, tr = time_to_sec(left.header.stamp), time_to_sec(right.header.stamp)
                if tl >= t and abs(tl - tr) < 1e-3:
                    try:
                        return tl, {"left": image_to_array(left), "right": image_to_array(right)}
                    except IcubPmpError as exc:
                        self.get_logger().warning(f"image dropped: {exc}",
                                                  throttle_duration_sec=5.0)
                        return None
            time.sleep(0.01)
        return None

    def _publish(self, babbling: MotorBabbling, budget: int, path: Path, active: bool,
                 wall0: float, sim0: float, message: str) -> None:
        n = len(babbling.samples)
        wall = time.monotonic() - wall0
        sim = self._sim_now() - sim0
        msg = BabblingProgress(
            active=active, arm=babbling.arm, samples=n, budget=budget,
            attempts=babbling.attempts, dropped=babbling.dropped,
            visible_fraction=babbling.visible_fraction,
            rate_sim=n / sim if sim > 0 else 0.0, rate_wall=n / wall if wall > 0 else 0.0,
            dataset_path=str(path), message=message)
        msg.header.stamp = self.get_clock().now().to_msg()
        self._progress = msg
        self.pub_progress.publish(msg)

    def destroy_node(self) -> None:
        """Stop a run (its dataset is saved) and the joint-state thread."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        self.joints.close()
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp body_schema``)."""
    run_node(BodySchemaNode, args, name="body_schema")


if __name__ == "__main__":
    main()
