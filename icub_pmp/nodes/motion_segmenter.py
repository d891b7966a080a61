"""motion_segmenter: independent-motion blobs from the eye cameras (motionCUT), a 3-D target.

A thin adapter over :mod:`icub_pmp.vision`:

subscribes  /cam/left/image_raw, /cam/right/image_raw (sensor_msgs/Image rgb8/bgr8/mono8 of
            ``image_width`` x ``image_height``; others are dropped with a throttled warning),
            /cam/left/camera_info, /cam/right/camera_info (intrinsics for triangulation;
            until one arrives: fx = fy = 343.12, principal point at the image centre),
            /joint_states (torso, neck and eye joints -> camera poses)
publishes   /motion/left/mask, /motion/right/mask (sensor_msgs/Image mono8, 255 = moving),
            /motion/left/blobs, /motion/right/blobs (icub_interfaces/MotionBlobs),
            /motion/target (geometry_msgs/PointStamped in root_link): the largest blob tracked
            in both eyes, triangulated with the current head/eye kinematics.

Parameters: the fields of :class:`~icub_pmp.vision.MotionSegmenterConfig`
(``config/motion_segmenter.yaml``); a change resets the segmenters.
"""

from __future__ import annotations

from geometry_msgs.msg import PointStamped
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import CameraInfo, Image, JointState, RegionOfInterest

from icub_interfaces.msg import MotionBlob as MotionBlobMsg
from icub_interfaces.msg import MotionBlobs as MotionBlobsMsg
from icub_pmp.errors import IcubPmpError
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics
from icub_pmp.ros.conversions import (
    array_to_image,
    image_to_array,
    joint_state_field,
    time_to_sec,
    validate_joint_state,
)
from icub_pmp.ros.node_runner import run_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.vision import (
    MotionBlobs,
    MotionSegmenter,
    MotionSegmenterConfig,
    StereoTriangulator,
    TargetTracker,
    TrackedTarget,
)
from icub_pmp.vision.head_cameras import HEAD_JOINTS, HeadCameras

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
    """Segment both eye images, publish masks, blobs and the triangulated target."""

    def __init__(self) -> None:
        super().__init__("motion_segmenter")
        self.params = ConfigParameters(self, MotionSegmenterConfig,
                                       on_change=self._on_config_change)
        self._reset(self.config)

        self.cameras = HeadCameras()
        self._joints: dict[str, float] = {}
        self._joint_stamp: float | None = None
        sd = qos_profile_sensor_data
        self.pub_mask = {s: self.create_publisher(Image, f"/motion/{s}/mask", sd) for s in SIDES}
        self.pub_blobs = {
            s: self.create_publisher(MotionBlobsMsg, f"/motion/{s}/blobs", 10) for s in SIDES
        }
        self.pub_target = self.create_publisher(PointStamped, "/motion/target", 10)
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
        self.sub_joints = self.create_subscription(
            JointState, "/joint_states", self._on_joints, sd
        )
        c = self.config
        self.get_logger().info(
            f"motion_segmenter: {c.image_width}x{c.image_height}, grid step {c.grid_step} px, "
            f"window {c.win_size}, theta_m {c.theta_m}"
        )

    # ------------------------------------------------------------------ parameters
    @property
    def config(self) -> MotionSegmenterConfig:
        """The current configuration (``config/motion_segmenter.yaml``, run-time changes)."""
        return self.params.config

    def _reset(self, config: MotionSegmenterConfig) -> None:
        """Fresh segmenters, trackers and default intrinsics for ``config``."""
        self.segmenters = {s: MotionSegmenter(config) for s in SIDES}
        self.trackers = {s: TargetTracker(config) for s in SIDES}
        cam = CameraIntrinsics(width=config.image_width, height=config.image_height,
                               cx=config.image_width / 2.0, cy=config.image_height / 2.0)
        self.intrinsics = {s: cam for s in SIDES}
        self._latest: dict[str, tuple[float, TrackedTarget] | None] = {s: None for s in SIDES}
        self._paired_stamp: float | None = None

    def _on_config_change(self, old: MotionSegmenterConfig, new: MotionSegmenterConfig,
                          changed: frozenset[str]) -> None:
        if new != old:
            self._reset(new)
            self.get_logger().info("parameters changed: segmenters reset")

    # ------------------------------------------------------------------ callbacks
    def _on_info(self, side: str, msg: CameraInfo) -> None:
        k = [float(v) for v in msg.k]
        if not (k[0] > 0 and k[4] > 0 and all(v == v for v in k)):
            self.get_logger().warn(
                f"dropping /cam/{side}/camera_info: bad K {k}", throttle_duration_sec=5.0
            )
            return
        self.intrinsics[side] = CameraIntrinsics(
            width=int(msg.width), height=int(msg.height), fx=k[0], fy=k[4], cx=k[2], cy=k[5]
        )

    def _on_joints(self, msg: JointState) -> None:
        try:
            validate_joint_state(msg)
        except IcubPmpError as exc:
            self.get_logger().warn(f"dropping /joint_states: {exc}", throttle_duration_sec=5.0)
            return
        pos = joint_state_field(msg, "position")
        self._joints.update({j: v for j, v in pos.items() if j in HEAD_JOINTS})
        self._joint_stamp = time_to_sec(msg.header.stamp)

    def _on_image(self, side: str, msg: Image) -> None:
        c = self.config
        stamp = time_to_sec(msg.header.stamp)
        last = self._latest[side]
        if last is not None and stamp < last[0] - 0.5:
            # time went back (simulation reset, bag loop): start this camera afresh
            self.get_logger().info(f"/cam/{side}: time went back {last[0]:.3f} -> {stamp:.3f} s,"
                                   " segmenter reset")
            self.segmenters[side].reset()
            self.trackers[side].reset()
            self._latest[side] = None
            self._paired_stamp = None
        try:
            img = image_to_array(msg, c.image_width, c.image_height)
            result = self.segmenters[side].process(img)
        except IcubPmpError as exc:
            self.get_logger().warn(
                f"dropping /cam/{side}/image_raw: {exc}", throttle_duration_sec=5.0
            )
            return
        target = self.trackers[side].update(result)
        self.pub_mask[side].publish(
            array_to_image(result.mask, "mono8", msg.header.stamp, msg.header.frame_id)
        )
        self.pub_blobs[side].publish(
            blobs_to_msg(result, msg.header, c.image_width, c.image_height)
        )
        self._latest[side] = (stamp, target)
        self._triangulate(stamp, msg)

    def _triangulate(self, stamp: float, msg: Image) -> None:
        c = self.config
        left, right = self._latest["left"], self._latest["right"]
        if left is None or right is None or abs(left[0] - right[0]) > c.stereo_sync_tolerance:
            return
        if self._paired_stamp is not None and stamp <= self._paired_stamp:
            return
        tl, tr = left[1], right[1]
        if not (tl.valid and tr.valid and tl.missing_frames == 0 and tr.missing_frames == 0):
            return
        if self._joint_stamp is None:
            self.get_logger().warn(
                "no /joint_states yet: no 3-D target", throttle_duration_sec=5.0
            )
            return
        if abs(stamp - self._joint_stamp) > c.joint_state_timeout:
            self.get_logger().warn(
                f"/joint_states {abs(stamp - self._joint_stamp):.3f} s away from the images: "
                "no 3-D target", throttle_duration_sec=5.0,
            )
            return
        self._paired_stamp = max(left[0], right[0])
        try:
            poses = self.cameras.poses(self._joints)
            p = StereoTriangulator(self.intrinsics["left"], self.intrinsics["right"]).triangulate(
                tl.position, tr.position, poses.T_root_left, poses.T_root_right
            )
        except IcubPmpError as exc:
            self.get_logger().warn(f"no 3-D target: {exc}", throttle_duration_sec=5.0)
            return
        if p.ray_gap > c.stereo_max_ray_gap or not 0.0 < p.depth_left <= c.max_target_depth:
            return
        out = PointStamped()
        out.header.stamp = msg.header.stamp
        out.header.frame_id = ROOT_FRAME
        out.point.x, out.point.y, out.point.z = (float(v) for v in p.position)
        self.pub_target.publish(out)


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp motion_segmenter``)."""
    run_node(MotionSegmenterNode, args, "motion_segmenter")

if __name__ == "__main__":
    main()
