"""motion_segmenter node over DDS (issue 7): masks, blobs and the 3-D target; bad images.

The node runs as a subprocess (scripts/run_node.sh with config/motion_segmenter.yaml) in the
session's private ROS domain; the test publishes real MuJoCo renders of the simulator's eye
cameras (icub_pmp.vision.sequence_generator) with matching /joint_states and reads what the
node publishes. The last test runs it against the simulator node itself.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from geometry_msgs.msg import PointStamped
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import CameraInfo, Image

from icub_interfaces.msg import MotionBlobs
from icub_pmp.config import config_dir
from icub_pmp.nodes.conversions import array_to_image, make_joint_state, sec_to_time
from icub_pmp.testing import NodeProcess
from icub_pmp.vision.sequence_generator import SequenceGenerator, SequenceSpec

PARAMS = config_dir() / "motion_segmenter.yaml"


@pytest.fixture(scope="module")
def frames():
    """14 stereo frames: an 8 cm ball moving parallel to the image plane at 40 cm/s, 0.47 m
    in front of the eyes, head still."""
    gen = SequenceGenerator()
    try:
        out = list(gen.frames(SequenceSpec(speed=0.4, direction="parallel", n_frames=14,
                                           seed=3)))
    finally:
        gen.close()
    return out


@pytest.fixture(scope="module")
def segmenter_node(ros_domain_id):
    node = NodeProcess("motion_segmenter", params_file=PARAMS)
    try:
        assert node.wait_for_output("motion_segmenter: 320x240", 60.0), node.output()
        yield node
    finally:
        node.stop()


def _publish_frames(probe, frames, period=0.08):
    node = probe.node
    sd = qos_profile_sensor_data
    pubs = {s: node.create_publisher(Image, f"/cam/{s}/image_raw", sd) for s in ("left", "right")}
    info = {s: node.create_publisher(CameraInfo, f"/cam/{s}/camera_info", sd)
            for s in ("left", "right")}
    joints = node.create_publisher(type(make_joint_state([])), "/joint_states", sd)
    assert probe.wait_for(lambda: all(p.get_subscription_count() > 0 for p in pubs.values()),
                          30.0)
    for f in frames:
        stamp = sec_to_time(1.0 + f.index / 30.0)
        names = list(f.joints)
        joints.publish(make_joint_state(names, position=[f.joints[n] for n in names],
                                        stamp=stamp))
        for s in ("left", "right"):
            ci = CameraInfo(width=320, height=240)
            ci.k = [343.12, 0.0, 160.0, 0.0, 343.12, 120.0, 0.0, 0.0, 1.0]
            info[s].publish(ci)
            img = f.left if s == "left" else f.right
            pubs[s].publish(array_to_image(img, "rgb8", stamp, f"{s[0]}_eye_optical"))
        time.sleep(period)


def test_node_publishes_masks_blobs_and_target(segmenter_node, ros_probe, frames):
    """From rendered stereo frames the node publishes mono8 320x240 masks in the camera frame,
    blobs (largest first) near the ball, and /motion/target in root_link within 2 cm of the
    ball's centre at 0.47 m."""
    masks, blobs, targets = [], [], []
    n = ros_probe.node
    subs = [
        n.create_subscription(Image, "/motion/left/mask", masks.append, qos_profile_sensor_data),
        n.create_subscription(MotionBlobs, "/motion/left/blobs", blobs.append, 10),
        n.create_subscription(PointStamped, "/motion/target", targets.append, 10),
    ]
    assert ros_probe.wait_for_topic("/motion/target", 30.0)
    _publish_frames(ros_probe, frames)
    ros_probe.wait_for(lambda: len(masks) >= len(frames) - 2 and len(targets) >= 5, 10.0)
    for s in subs:
        n.destroy_subscription(s)
    assert segmenter_node.alive()
    assert len(masks) >= len(frames) - 2, segmenter_node.output()
    m = masks[-1]
    assert (m.encoding, m.width, m.height, m.header.frame_id) == ("mono8", 320, 240,
                                                                  "l_eye_optical")
    assert max(np.frombuffer(bytes(x.data), np.uint8).max() for x in masks) == 255
    with_blobs = [b for b in blobs if b.blobs]
    assert len(with_blobs) >= len(frames) - 4
    for b in with_blobs:
        sizes = [x.size for x in b.blobs]
        assert sizes == sorted(sizes, reverse=True)
    assert len(targets) >= 5, segmenter_node.output()
    gt = {round(1.0 + f.index / 30.0, 6): f.target_position for f in frames}
    errs = []
    for t in targets:
        assert t.header.frame_id == "root_link"
        key = round(t.header.stamp.sec + t.header.stamp.nanosec * 1e-9, 6)
        p = np.array([t.point.x, t.point.y, t.point.z])
        errs.append(np.linalg.norm(p - gt[key]))
    assert np.median(errs) < 0.02, errs


def test_node_rejects_bad_images(segmenter_node, ros_probe, frames):
    """A wrong encoding (32FC1) and a wrong size (160x120) are dropped with a warning naming
    the problem; the node stays up and still processes good images afterwards."""
    pub = ros_probe.node.create_publisher(Image, "/cam/left/image_raw", qos_profile_sensor_data)
    assert ros_probe.wait_for(lambda: pub.get_subscription_count() > 0, 30.0)
    bad = Image(height=240, width=320, encoding="32FC1", step=320 * 4)
    bad.data = bytes(320 * 240 * 4)
    pub.publish(bad)
    assert segmenter_node.wait_for_output("32FC1", 10.0), segmenter_node.output()
    small = array_to_image(np.zeros((120, 160, 3), np.uint8), "rgb8")
    time.sleep(5.2)  # the warning is throttled (5 s)
    pub.publish(small)
    assert segmenter_node.wait_for_output("160x120", 10.0), segmenter_node.output()
    assert segmenter_node.alive()
    got = []
    sub = ros_probe.node.create_subscription(Image, "/motion/left/mask", got.append,
                                             qos_profile_sensor_data)
    for f in frames[:3]:
        pub.publish(array_to_image(f.left, "rgb8", sec_to_time(50.0 + f.index / 30.0)))
        time.sleep(0.1)
    ros_probe.wait_for(lambda: len(got) >= 2, 10.0)
    ros_probe.node.destroy_subscription(sub)
    assert len(got) >= 2
