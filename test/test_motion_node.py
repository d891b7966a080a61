"""motion_segmenter node over DDS: masks, blobs and the 3-D target; bad images.

The node runs as a subprocess (scripts/run_node.sh with config/motion_segmenter.yaml) in the
session's private ROS domain; the test publishes real MuJoCo renders of the simulator's eye
cameras (icub_sim_bridge.harness.sequence_generator) with matching /joint_states and reads what the
node publishes. The last test runs it against the simulator node itself.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from geometry_msgs.msg import PointStamped, Pose
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import CameraInfo, Image, JointState

from icub_interfaces.msg import MotionBlobs
from icub_interfaces.srv import SetObjectPose
from icub_pmp.config import config_dir
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics, project_point
from icub_pmp.ros.conversions import array_to_image, make_joint_state, sec_to_time
from icub_pmp.testing import NodeProcess, ros_environment
from icub_pmp.vision.head_cameras import HeadCameras

PARAMS = config_dir() / "motion_segmenter.yaml"


@pytest.fixture(scope="module")
def frames():
    """14 stereo frames of the simulator's scene: the cylinder (r 3 cm, 12 cm tall) sliding
    across the table at 20 cm/s about 0.5 m in front of the eyes, head still looking down."""
    import math
    from types import SimpleNamespace

    from icub_sim_bridge.harness.table_scene import TableScene

    scene = TableScene()
    head = {"neck_pitch": math.radians(-20.0), "eyes_tilt": math.radians(-30.0),
            "eyes_version": 0.0, "eyes_vergence": math.radians(4.0)}
    out = []
    try:
        for k in range(14):
            centre = np.array([-0.38, -0.08 + 0.2 * k / 30.0, -0.03])
            scene.pose(head, {"cylinder": centre, "box": [-0.52, -0.40, -0.05]})
            f = scene.render()
            out.append(SimpleNamespace(index=k, left=f.left, right=f.right, joints=f.joints,
                                       target_position=f.objects["cylinder"]))
    finally:
        scene.close()
    return out


@pytest.fixture(scope="module")
def segmenter_node(ros_domain_id):
    # the frames below are rendered by the nominal cameras (camera_info), not by the shipped
    # icub robot's miscalibrated ones that config's eye_calibration_file describes
    node = NodeProcess("motion_segmenter", params_file=PARAMS,
                       parameters={"eye_calibration_file": ""})
    try:
        assert node.wait_for_output("motion_segmenter: 320x240", 60.0), node.output()
        yield node
    finally:
        node.stop()


def _publish_frames(probe, frames, period=0.08, t0=1.0, processed=None):
    """Publish ``frames`` (joint state, camera info, both images) every ``period`` s.
    ``processed(k)``: True once the node has answered frame k; then the next frame waits for
    it (up to 10 s), so a loaded machine slows the test down instead of dropping frames from
    the node's sensor-data queue."""
    node = probe.node
    sd = qos_profile_sensor_data
    pubs = {s: node.create_publisher(Image, f"/cam/{s}/image_raw", sd) for s in ("left", "right")}
    info = {s: node.create_publisher(CameraInfo, f"/cam/{s}/camera_info", sd)
            for s in ("left", "right")}
    joints = node.create_publisher(type(make_joint_state([])), "/joint_states", sd)
    assert probe.wait_for(lambda: all(p.get_subscription_count() > 0 for p in pubs.values()),
                          30.0)
    for k, f in enumerate(frames):
        stamp = sec_to_time(t0 + f.index / 30.0)
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
        if processed is not None:
            probe.wait_for(lambda k=k: processed(k), 10.0)


def test_node_publishes_masks_blobs_and_target(segmenter_node, ros_probe, frames):
    """From rendered stereo frames the node publishes mono8 320x240 masks in the camera frame,
    blobs (largest first) near the cylinder, and /motion/target in root_link within 1 cm of
    the cylinder's centre at each image's stamp, with /motion/target/estimate beside it."""
    masks, blobs, targets = [], [], []
    n = ros_probe.node
    subs = [
        n.create_subscription(Image, "/motion/left/mask", masks.append, qos_profile_sensor_data),
        n.create_subscription(MotionBlobs, "/motion/left/blobs", blobs.append, 10),
        n.create_subscription(PointStamped, "/motion/target", targets.append, 10),
    ]
    assert ros_probe.wait_for_topic("/motion/target", 30.0)
    _publish_frames(ros_probe, frames, processed=lambda k: len(masks) >= k - 1)
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
    assert np.median(errs) < 0.01 and max(errs) < 0.02, errs


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
    # the warning is throttled (5 s): publish until it is logged
    deadline = time.monotonic() + 20.0
    while not segmenter_node.wait_for_output("160x120", 0.5) and time.monotonic() < deadline:
        pub.publish(small)
    assert segmenter_node.wait_for_output("160x120", 1.0), segmenter_node.output()
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


def _set_params(probe, node: str, **values):
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters

    params = []
    for name, v in values.items():
        if isinstance(v, bool):
            pv = ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=v)
        elif isinstance(v, int):
            pv = ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=v)
        elif isinstance(v, str):
            pv = ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=v)
        else:
            pv = ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=v)
        params.append(Parameter(name=name, value=pv))
    return probe.call(f"/{node}/set_parameters", SetParameters,
                      SetParameters.Request(parameters=params)).results


def test_node_eye_calibration_file(segmenter_node, ros_probe, tmp_path):
    """``eye_calibration_file`` at run time: a missing file is an error in the log and the
    node goes on with the nominal cameras; a calibration file is loaded and said so; back to
    '' (the nominal cameras) the node keeps segmenting."""
    from icub_pmp.vision.eye_calibration import CameraCorrection, EyeCalibration

    res = _set_params(ros_probe, "motion_segmenter",
                      eye_calibration_file=str(tmp_path / "missing.yaml"))
    assert res[0].successful, res[0].reason
    assert segmenter_node.wait_for_output("no such file; using the nominal cameras", 10.0), \
        segmenter_node.output()
    assert segmenter_node.alive()
    calib = EyeCalibration(CameraCorrection(1.01, 161.0, 119.0, (0.0, 0.01, 0.0)),
                           CameraCorrection(0.99, 159.0, 121.0, (0.01, 0.0, 0.0)), samples=42,
                           rms_px=0.4, nominal_rms_px=2.0)
    path = calib.save(tmp_path / "eyes.yaml")
    res = _set_params(ros_probe, "motion_segmenter", eye_calibration_file=str(path))
    assert res[0].successful, res[0].reason
    assert segmenter_node.wait_for_output("42 marker observations", 10.0), \
        segmenter_node.output()
    res = _set_params(ros_probe, "motion_segmenter", eye_calibration_file="")
    assert res[0].successful and segmenter_node.alive()


def test_node_with_simulator(segmenter_node, ros_probe, ros_domain_id):
    """With the simulator node (sim_bridge, cameras on) the segmenter turns /cam/*/image_raw
    into masks and blobs at the camera rate, in the cameras' optical frames. The still scene
    (robot holding its posture) gives no blob. The simulator's scene is flat-coloured, so a
    moving object fails LK only along its outline (1-node lines, which the shipped neighbour
    filter drops): with thresholds set at run time for that (adj_nodes_thres 2, no temporal
    confirmation, blobs over 4 nodes; an out-of-range value is refused), the box teleported
    back and forth 0.5 m in front of the left eye, falling in between, gives blobs below where
    it was put (where it falls).
    Runs last: the simulator's clock restarts at 0."""
    sim = NodeProcess("sim_bridge", env=ros_environment(ros_domain_id),
                      params_file=config_dir() / "sim_bridge.yaml",
                      parameters={"cameras_enabled": True})
    try:
        assert ros_probe.wait_for_topic("/cam/left/image_raw", 90.0), sim.output()[-3000:]
        js = ros_probe.collect("/joint_states", JointState, 1, timeout=30.0)
        assert js, sim.output()[-3000:]
        T = HeadCameras().poses(dict(zip(js[0].name, js[0].position))).T_root_left
        still = ros_probe.collect("/motion/left/blobs", MotionBlobs, 30, timeout=30.0,
                                  qos=10)
        assert len(still) >= 20, segmenter_node.output()[-3000:]
        assert not any(b.blobs for b in still)
        assert all(b.header.frame_id == "l_eye_optical" for b in still)

        bad = _set_params(ros_probe, "motion_segmenter", adj_nodes_thres=9)
        assert not bad[0].successful and "adj_nodes_thres" in bad[0].reason
        bad = _set_params(ros_probe, "motion_segmenter", accum_decay=1.0)
        assert not bad[0].successful and "accum_decay" in bad[0].reason
        ok = _set_params(ros_probe, "motion_segmenter", adj_nodes_thres=2, confirm_frames=1,
                         blob_min_size=4)
        assert all(r.successful for r in ok), [r.reason for r in ok]
        masks, blobs = [], []
        n = ros_probe.node
        subs = [
            n.create_subscription(Image, "/motion/left/mask", masks.append,
                                  qos_profile_sensor_data),
            n.create_subscription(MotionBlobs, "/motion/left/blobs", blobs.append, 10),
        ]
        centre = T[:3, 3] + 0.5 * T[:3, 2]
        placed = []
        t_end = time.monotonic() + 6.0
        k = 0
        while time.monotonic() < t_end:
            p = centre + (0.05 if k % 2 else -0.05) * T[:3, 0]
            pose = Pose()
            pose.position.x, pose.position.y, pose.position.z = (float(v) for v in p)
            pose.orientation.w = 1.0
            r = ros_probe.call("/sim/set_object_pose", SetObjectPose,
                               SetObjectPose.Request(name="box", pose=pose), timeout=10.0)
            assert r.success, r.message
            placed.append(p)
            k += 1
            time.sleep(0.3)
        for s in subs:
            n.destroy_subscription(s)
        assert sim.alive() and segmenter_node.alive(), segmenter_node.output()[-3000:]
        assert len(masks) >= 10, segmenter_node.output()[-3000:]
        assert all((m.width, m.height, m.encoding, m.header.frame_id)
                   == (320, 240, "mono8", "l_eye_optical") for m in masks)
        seen = [b for b in blobs if b.blobs]
        assert len(seen) >= 3, (len(blobs), segmenter_node.output()[-2000:])
        # the box (20 cm wide, about 140 px) falls vertically in the image from where it is put
        uv = np.array([project_point(T, p, CameraIntrinsics()) for p in placed[:2]])
        cu = np.array([b.blobs[0].centroid_u for b in seen])
        cv = np.array([b.blobs[0].centroid_v for b in seen])
        assert np.all((cu > uv[:, 0].min() - 90) & (cu < uv[:, 0].max() + 90)), (cu, uv)
        assert np.all(cv > uv[:, 1].min() - 60), (cv, uv)
    finally:
        rc = sim.stop()
        assert rc == 0, sim.output()[-3000:]


def test_reset_target_forgets_the_followed_object(segmenter_node, ros_probe, frames):
    """/motion/reset_target drops the target the frames gave (no /motion/target until an
    object moves again); a second call says there was none."""
    from std_srvs.srv import Trigger

    targets, masks = [], []
    sub = ros_probe.node.create_subscription(PointStamped, "/motion/target", targets.append, 10)
    msub = ros_probe.node.create_subscription(Image, "/motion/left/mask", masks.append,
                                              qos_profile_sensor_data)
    # after the other tests' frames and clock
    _publish_frames(ros_probe, frames, t0=50.0, processed=lambda k: len(masks) >= k - 1)
    assert ros_probe.wait_for(lambda: len(targets) >= 5, 10.0), segmenter_node.output()
    # every frame answered before the reset: a frame still queued in the node would give the
    # target back before the second call (seen on a loaded machine)
    count = -1
    while count != len(masks):
        count = len(masks)
        time.sleep(1.0)
    ros_probe.node.destroy_subscription(msub)
    first = ros_probe.call("/motion/reset_target", Trigger, Trigger.Request(), timeout=30.0)
    assert first.success and first.message == "target dropped", first.message
    again = ros_probe.call("/motion/reset_target", Trigger, Trigger.Request(), timeout=30.0)
    assert again.success and again.message == "no target was followed", again.message
    ros_probe.node.destroy_subscription(sub)
