"""motion_segmenter: independent-motion blobs from the eye cameras (motionCUT), a 3-D target.

A thin adapter over :mod:`icub_pmp.vision`:

subscribes  /cam/left/image_raw, /cam/right/image_raw (sensor_msgs/Image rgb8/bgr8/mono8 of
            ``image_width`` x ``image_height``; others are dropped with a throttled warning),
            /cam/left/camera_info, /cam/right/camera_info (intrinsics; until one arrives:
            fx = fy = 343.12, principal point at the image centre),
            /joint_states (on a thread of its own, the last second kept: the head, eyes and
            arms at each image's stamp)
publishes   /motion/left/mask, /motion/right/mask (sensor_msgs/Image mono8, 255 = moving),
            /motion/left/blobs, /motion/right/blobs (icub_interfaces/MotionBlobs),
            /motion/target (geometry_msgs/PointStamped in root_link): the centre of the object
            the eyes follow, stamped with the images it is about, every stereo pair while
            there is a target (:class:`~icub_pmp.vision.stereo_target.StereoTarget`: the
            eyes' blobs paired, the object measured by stereo matching, tracked; an object
            that stops is kept and measured in its own image region),
            /motion/target/estimate (icub_interfaces/VisualTarget): the same with its
            covariance, top face, size, velocity and state.
services    /motion/reset_target (std_srvs/Trigger): forget the followed object (the next
            object seen moving becomes the target), e.g. before a new object is shown.

Parameters: the fields of :class:`~icub_pmp.vision.MotionSegmenterConfig`, of
:class:`~icub_pmp.vision.StereoTargetConfig` and of
:class:`~icub_pmp.body_schema.eye_hand_target.EyeHandTargetConfig`
(``config/motion_segmenter.yaml``); a change resets the segmenters and the target.
``target_source: eye_hand_map`` makes the object's pixel pairs points through the eye-hand map
learned from babbling (force paper eq 12) instead of ray triangulation; a map that cannot be
used (no file, another camera setup) is a warning and the node stays on triangulation.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from geometry_msgs.msg import PointStamped
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import CameraInfo, Image, RegionOfInterest
from std_srvs.srv import Trigger

from icub_interfaces.msg import MotionBlob as MotionBlobMsg
from icub_interfaces.msg import MotionBlobs as MotionBlobsMsg
from icub_interfaces.msg import VisualTarget
from icub_pmp.body_schema.eye_hand_target import EyeHandPoints, EyeHandTargetConfig
from icub_pmp.config import repo_root
from icub_pmp.errors import IcubPmpError
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics
from icub_pmp.ros.conversions import (
    array_to_image,
    image_to_array,
    sec_to_time,
    time_to_sec,
)
from icub_pmp.ros.joint_state_cache import JointStateCache
from icub_pmp.ros.node_runner import run_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.vision import (
    MotionBlobs,
    MotionSegmenter,
    MotionSegmenterConfig,
    StereoTarget,
    StereoTargetConfig,
    TrackedObject,
)
from icub_pmp.vision.arm_segments import arm_segments
from icub_pmp.vision.eye_calibration import EyeCalibration
from icub_pmp.vision.head_cameras import HeadCameras

__all__ = ["MotionSegmenterNode", "main", "blobs_to_msg"]

SIDES = ("left", "right")
ROOT_FRAME = "root_link"


def blobs_to_msg(blobs: MotionBlobs, header, width: int, height: int) -> MotionBlobsMsg:
    """MotionBlobs (core result) -> icub_interfaces/MotionBlobs."""
    msg = MotionBlobsMsg()
    msg.header = header
    msg.image_width, msg.image_height = width, height
    for b in blobs.blobs:
        u0, v0, u1, v1 = b.bbox
        u0, v0 = max(u0, 0), max(v0, 0)
        roi = RegionOfInterest(
            x_offset=u0, y_offset=v0, width=max(min(u1, width - 1) - u0 + 1, 0),
            height=max(min(v1, height - 1) - v0 + 1, 0), do_rectify=False,
        )
        msg.blobs.append(
            MotionBlobMsg(
                centroid_u=b.centroid[0], centroid_v=b.centroid[1], size=b.size, area=b.area,
                bbox=roi, flow_u=b.mean_flow[0], flow_v=b.mean_flow[1],
            )
        )
    return msg


class MotionSegmenterNode(Node):
    """Segment both eye images, publish masks, blobs and the stereo target."""

    def __init__(self) -> None:
        super().__init__("motion_segmenter")
        self.params = ConfigParameters(
            self, (MotionSegmenterConfig, StereoTargetConfig, EyeHandTargetConfig),
            on_change=self._on_config_change)
        self.cameras = HeadCameras()
        self.nominal = {s: CameraIntrinsics() for s in SIDES}
        self._reset(self.config, self.stereo_config, self.params.get(EyeHandTargetConfig))
        sd = qos_profile_sensor_data
        self.pub_mask = {s: self.create_publisher(Image, f"/motion/{s}/mask", sd) for s in SIDES}
        self.pub_blobs = {
            s: self.create_publisher(MotionBlobsMsg, f"/motion/{s}/blobs", 10) for s in SIDES
        }
        self.pub_target = self.create_publisher(PointStamped, "/motion/target", 10)
        self.pub_estimate = self.create_publisher(VisualTarget, "/motion/target/estimate", 10)
        self.subs = [
            self.create_subscription(
                Image, f"/cam/{s}/image_raw", lambda m, s=s: self._on_image(s, m), sd
            )
            for s in SIDES
        ]
        self.sub_info = [
            self.create_subscription(
                CameraInfo, f"/cam/{s}/camera_info", lambda m, s=s: self._on_info(s, m), sd
            )
            for s in SIDES
        ]
        self.joints = JointStateCache(self, history=1.0)
        self.srv_reset = self.create_service(Trigger, "/motion/reset_target",
                                             self._on_reset_target)
        c = self.config
        self.get_logger().info(
            f"motion_segmenter: {c.image_width}x{c.image_height}, grid step {c.grid_step} px, "
            f"window {c.win_size}, theta_m {c.theta_m}; stereo target: depth "
            f"{self.stereo_config.min_depth}-{self.stereo_config.max_depth} m"
        )

    def _on_reset_target(self, _req: Trigger.Request, res: Trigger.Response
                         ) -> Trigger.Response:
        """/motion/reset_target: drop the followed object."""
        had = self.target.tracker.target.valid
        self.target.reset()
        res.success = True
        res.message = "target dropped" if had else "no target was followed"
        self.get_logger().info(f"/motion/reset_target: {res.message}")
        return res

    # ------------------------------------------------------------------ parameters
    @property
    def config(self) -> MotionSegmenterConfig:
        """The segmenter's configuration (``config/motion_segmenter.yaml``)."""
        return self.params.get(MotionSegmenterConfig)

    @property
    def stereo_config(self) -> StereoTargetConfig:
        """The stereo target's configuration."""
        return self.params.get(StereoTargetConfig)

    def _reset(self, config: MotionSegmenterConfig, stereo: StereoTargetConfig,
               eye_hand: EyeHandTargetConfig) -> None:
        """Fresh segmenters, target, intrinsics and eye-hand map for these configurations."""
        self.segmenters = {s: MotionSegmenter(config) for s in SIDES}
        cam = CameraIntrinsics(width=config.image_width, height=config.image_height,
                               cx=config.image_width / 2.0, cy=config.image_height / 2.0)
        self.nominal = {s: cam for s in SIDES}
        self.calibration = self._load_calibration(stereo.eye_calibration_file)
        self.intrinsics = self._calibrated_intrinsics()
        self.target = StereoTarget(stereo, self.intrinsics["left"],
                                   self.intrinsics["right"])
        self.eye_hand = self._load_eye_hand(eye_hand, cam)
        self._latest: dict[str, tuple[float, np.ndarray, MotionBlobs] | None] = {
            s: None for s in SIDES}
        self._paired_stamp: float | None = None

    def _load_calibration(self, path: str) -> EyeCalibration | None:
        """The eye calibration of ``path`` (None = nominal cameras); a file that cannot be
        read is reported and the nominal cameras are used (the node keeps running)."""
        if not path:
            return None
        file = Path(path) if Path(path).is_absolute() else repo_root() / path
        try:
            calib = EyeCalibration.load(file)
        except IcubPmpError as exc:
            self.get_logger().error(f"eye_calibration_file: {exc}; using the nominal cameras "
                                    "(camera_info), 3-D targets may be centimetres off")
            return None
        self.get_logger().info(f"eye calibration {file}: {calib.samples} marker observations, "
                               f"reprojection {calib.rms_px:.2f} px (nominal "
                               f"{calib.nominal_rms_px:.2f} px)")
        return calib

    def _calibrated_intrinsics(self) -> dict[str, CameraIntrinsics]:
        """Each eye's intrinsics: camera_info's, corrected by the eye calibration if any."""
        if self.calibration is None:
            return dict(self.nominal)
        left, right = self.calibration.intrinsics(self.nominal["left"], self.nominal["right"])
        return {"left": left, "right": right}

    def _load_eye_hand(self, c: EyeHandTargetConfig, cam: CameraIntrinsics
                       ) -> EyeHandPoints | None:
        """The eye-hand map of ``target_source: eye_hand_map`` (None: triangulation; a map that
        cannot be used is a warning, and triangulation stays)."""
        if c.target_source != "eye_hand_map":
            return None
        try:
            points = EyeHandPoints.from_file(c.eye_hand_map_file, cam)
        except IcubPmpError as exc:
            self.get_logger().warn(f"target_source eye_hand_map: {exc}; the 3-D target stays "
                                   "on triangulation")
            return None
        self.get_logger().info(f"3-D target from the eye-hand map {c.eye_hand_map_file}")
        return points

    def _on_config_change(self, old: tuple, new: tuple, changed: frozenset[str]) -> None:
        if new != old:  # called before the new values are stored: build from ``new``
            self._reset(*new)
            self.get_logger().info("parameters changed: segmenters and target reset")

    # ------------------------------------------------------------------ callbacks
    def _on_info(self, side: str, msg: CameraInfo) -> None:
        k = [float(v) for v in msg.k]
        if not (k[0] > 0 and k[4] > 0 and all(v == v for v in k)):
            self.get_logger().warn(
                f"dropping /cam/{side}/camera_info: bad K {k}", throttle_duration_sec=5.0
            )
            return
        cam = CameraIntrinsics(width=int(msg.width), height=int(msg.height), fx=k[0], fy=k[4],
                               cx=k[2], cy=k[5])
        if cam != self.nominal[side]:
            self.nominal[side] = cam
            self.intrinsics = self._calibrated_intrinsics()
            self.target.left, self.target.right = self.intrinsics["left"], \
                self.intrinsics["right"]
            if self.eye_hand is not None:
                try:
                    EyeHandPoints(self.eye_hand.map, cam)
                except IcubPmpError as exc:
                    self.eye_hand = None
                    self.get_logger().warn(f"/cam/{side}/camera_info: {exc}; the 3-D target "
                                           "goes back to triangulation")

    def _on_image(self, side: str, msg: Image) -> None:
        c = self.config
        stamp = time_to_sec(msg.header.stamp)
        last = self._latest[side]
        if last is not None and stamp < last[0] - 0.5:
            # time went back (simulation reset, bag loop): start this camera afresh
            self.get_logger().info(f"/cam/{side}: time went back {last[0]:.3f} -> {stamp:.3f} s,"
                                   " segmenter reset")
            self.segmenters[side].reset()
            self.target.reset()
            self._latest = {s: None for s in SIDES}
            self._paired_stamp = None
        try:
            img = image_to_array(msg, c.image_width, c.image_height)
            result = self.segmenters[side].process(img)
        except IcubPmpError as exc:
            self.get_logger().warn(
                f"dropping /cam/{side}/image_raw: {exc}", throttle_duration_sec=5.0
            )
            return
        self.pub_mask[side].publish(
            array_to_image(result.mask, "mono8", msg.header.stamp, msg.header.frame_id)
        )
        self.pub_blobs[side].publish(
            blobs_to_msg(result, msg.header, c.image_width, c.image_height)
        )
        self._latest[side] = (stamp, img, result)
        self._stereo(stamp)

    def _stereo(self, stamp: float) -> None:
        """Process the stereo pair of ``stamp`` once both images are there."""
        sc = self.stereo_config
        left, right = self._latest["left"], self._latest["right"]
        if left is None or right is None or abs(left[0] - right[0]) > sc.stereo_sync_tolerance:
            return
        if self._paired_stamp is not None and stamp <= self._paired_stamp:
            return
        self._paired_stamp = max(left[0], right[0])
        state = self.joints.at(left[0])
        if state is None or abs(state.t - left[0]) > sc.joint_state_timeout:
            age = "none" if state is None else f"{abs(state.t - left[0]):.3f} s away"
            self.get_logger().warn(f"no /joint_states at the images' stamp ({age}): no 3-D "
                                   "target", throttle_duration_sec=5.0)
            return
        try:
            poses = self.cameras.poses(state.positions)
            if self.calibration is not None:
                poses = self.calibration.poses(poses)
            segments = arm_segments(self.cameras.model, state.positions)
            points_fn = None
            if self.eye_hand is not None:
                eyes = [state.positions[j] for j in ("eyes_tilt", "eyes_version",
                                                     "eyes_vergence")]
                points_fn = self.eye_hand.points_fn(self.cameras.head_pose(state.positions),
                                                    eyes)
            res = self.target.process(left[0], left[1], right[1], left[2], right[2], poses,
                                      segments, points_fn)
        except IcubPmpError as exc:
            self.get_logger().warn(f"no 3-D target: {exc}", throttle_duration_sec=5.0)
            return
        if res.measurement is None and (res.note or len(left[2].blobs) or len(right[2].blobs)):
            # why moving blobs gave no measurement (unpaired, refused as the robot's own arm,
            # another object, no object in the region): `--log-level motion_segmenter:=debug`
            self.get_logger().debug(
                f"t={left[0]:.3f}: blobs {len(left[2].blobs)}/{len(right[2].blobs)}, "
                f"pairs {len(res.pairs)}, target {'held' if res.target.valid else 'none'}: "
                f"{res.note or 'nothing measured'}")
        if res.target.valid:
            self._publish(res.target, res.source, 0 if res.measurement is None
                          else res.measurement.n_points)

    def _publish(self, t: TrackedObject, source: str, points: int) -> None:
        stamp = sec_to_time(t.stamp)
        out = PointStamped()
        out.header.stamp = stamp
        out.header.frame_id = ROOT_FRAME
        out.point.x, out.point.y, out.point.z = (float(v) for v in t.position)
        self.pub_target.publish(out)
        m = VisualTarget()
        m.header = out.header
        m.state, m.source = t.state, source
        m.position = out.point
        m.covariance = [float(v) for v in t.covariance.ravel()]
        m.top.x, m.top.y, m.top.z = (float(v) for v in t.top)
        m.velocity.x, m.velocity.y, m.velocity.z = (float(v) for v in t.velocity)
        m.radius, m.height = float(t.radius), float(t.height)
        m.last_measured = sec_to_time(t.last_measured)
        m.points = int(points)
        self.pub_estimate.publish(m)

    def destroy_node(self) -> None:
        """Stop the joint-state thread, then destroy the node."""
        self.joints.close()
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp motion_segmenter``)."""
    run_node(MotionSegmenterNode, args, "motion_segmenter")

if __name__ == "__main__":
    main()
