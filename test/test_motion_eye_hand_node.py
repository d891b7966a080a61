"""motion_segmenter with ``target_source: eye_hand_map`` over DDS: the 3-D target comes from a
real eye-hand map (force paper eq 12) learned for the scene's cameras; a map that cannot be used
is a warning and the node keeps running on triangulation.

The node runs as a subprocess with config/motion_segmenter.yaml and the source overridden; the
test publishes the same MuJoCo renders of the table scene as test_motion_node (the cylinder
sliding across the table, head still) with matching /joint_states and camera_info."""

from __future__ import annotations

import math

import numpy as np
import pytest
from geometry_msgs.msg import PointStamped
from test_motion_node import _publish_frames, frames  # noqa: F401 - the shared fixture

from icub_pmp.body_schema import (
    EyeHandMap,
    LmTrainer,
    LmTrainerConfig,
    view_samples,
)
from icub_pmp.config import config_dir
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics
from icub_pmp.testing import NodeProcess
from icub_pmp.vision.head_cameras import HeadCameras

pytestmark = [pytest.mark.integration, pytest.mark.slow]

PARAMS = config_dir() / "motion_segmenter.yaml"


@pytest.fixture(scope="module")
def map_file(tmp_path_factory):
    """An eye-hand map learned for the scene's head (neck pitch -20 deg, eyes tilt -30 deg,
    vergence 4 deg, tilt and version jittered 3 deg) from 1,500 points in view of both nominal
    cameras at 0.3-0.8 m, 0.3 px pixel noise."""
    heads = HeadCameras()
    T = heads.head_pose({"neck_pitch": math.radians(-20.0)})
    cam = CameraIntrinsics()
    s = view_samples(1500, 5, heads.eyes, T, np.radians([-30.0, 0.0, 4.0]),
                     {"left": cam, "right": cam}, np.eye(3), 0.3)
    m, _ = EyeHandMap.train(s.inputs, (s.hands - T[:3, 3]) @ T[:3, :3], "head",
                            trainer=LmTrainer(LmTrainerConfig(max_evaluations=200)),
                            camera={"width": cam.width, "height": cam.height, "fx": cam.fx,
                                    "fy": cam.fy})
    return m.save(tmp_path_factory.mktemp("maps") / "eye_hand.npz")


def test_target_from_the_eye_hand_map(ros_domain_id, ros_probe, frames, map_file):  # noqa: F811
    """With the learned map as the target source, /motion/target stays within 1.5 cm of the
    cylinder's centre (median over the frames; triangulation gets within 1 cm in
    test_motion_node), and the node says which source it uses. The frames and the map are
    the nominal cameras', not the shipped icub robot's calibrated ones."""
    node = NodeProcess("motion_segmenter", params_file=PARAMS,
                       parameters={"target_source": "eye_hand_map",
                                   "eye_hand_map_file": str(map_file),
                                   "eye_calibration_file": ""})
    try:
        assert node.wait_for_output("3-D target from the eye-hand map", 90.0), node.output()
        targets: list[PointStamped] = []
        sub = ros_probe.node.create_subscription(PointStamped, "/motion/target",
                                                 targets.append, 10)
        assert ros_probe.wait_for_topic("/motion/target", 30.0)
        _publish_frames(ros_probe, frames)
        ros_probe.wait_for(lambda: len(targets) >= 5, 20.0)
        ros_probe.node.destroy_subscription(sub)
        assert node.alive() and len(targets) >= 5, node.output()[-3000:]
        gt = {round(1.0 + f.index / 30.0, 6): f.target_position for f in frames}
        errs = [np.linalg.norm(np.array([t.point.x, t.point.y, t.point.z]) - gt[round(
            t.header.stamp.sec + t.header.stamp.nanosec * 1e-9, 6)]) for t in targets]
        assert np.median(errs) < 0.015, errs
    finally:
        node.stop()


def test_missing_map_keeps_triangulation(ros_domain_id, tmp_path):
    """A map file that does not exist: a warning naming it and saying the target stays on
    triangulation; the node keeps running."""
    missing = tmp_path / "none.npz"
    node = NodeProcess("motion_segmenter", params_file=PARAMS,
                       parameters={"target_source": "eye_hand_map",
                                   "eye_hand_map_file": str(missing)})
    try:
        assert node.wait_for_output("stays on triangulation", 90.0), node.output()
        assert "none.npz" in node.output() and "Traceback" not in node.output()
        assert node.wait_for_output("motion_segmenter: 320x240", 30.0)
        assert node.alive()
    finally:
        node.stop()
