"""Visualization: link transforms from pinocchio (core) and the robot_state_publisher node
(/robot_description, /tf_static, /tf over DDS, started through its script)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pinocchio as pin
import pytest
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

from icub_pmp.kinematics.link_transforms import LinkTransform, LinkTransforms
from icub_pmp.nodes.robot_state_publisher import LATCHED_QOS, TF_QOS
from icub_pmp.testing import NodeProcess, repo_root


@pytest.fixture(scope="module")
def links():
    return LinkTransforms()


def _compose(transforms: list[LinkTransform], frame: str) -> pin.SE3:
    """T_root_frame by walking the parent chain of ``transforms``."""
    by_child = {t.child: t for t in transforms}
    T = pin.SE3.Identity()
    while frame in by_child:
        t = by_child[frame]
        x, y, z, w = t.quat_xyzw
        T = pin.SE3(pin.Quaternion(w, x, y, z).matrix(), np.array(t.translation)) * T
        frame = t.parent
    assert frame == "root_link"
    return T


def test_link_tree_is_complete(links):
    """Every URDF link except root_link is the child of exactly one transform; 20 move."""
    all_t = links.static() + links.moving(links.model.posture("zero"))
    children = [t.child for t in all_t]
    assert len(children) == len(set(children)) == len(links.links) - 1
    assert "root_link" not in children and len(links.moving_joints) == 20


@pytest.mark.parametrize("frame", ["r_hand_dh_frame", "l_hand_dh_frame", "r_arm_ft", "head"])
def test_chained_transforms_equal_forward_kinematics(links, frame):
    """Chaining the published parent->child transforms from root_link reproduces pinocchio's
    frame pose at random configurations (what a tf listener / Foxglove computes)."""
    rng = np.random.default_rng(3)
    static = links.static()
    for _ in range(5):
        q = links.model.random_q(rng)
        T = _compose(static + links.moving(q), frame)
        np.testing.assert_allclose(T.homogeneous, links.model.frame_pose(q, frame).homogeneous,
                                   atol=1e-9)


def test_static_transforms_do_not_depend_on_q(links):
    """The /tf_static set is the same whatever the configuration was before."""
    a = links.static()
    links.moving(links.model.random_q(np.random.default_rng(0)))
    b = links.static()
    for x, y in zip(a, b):
        np.testing.assert_allclose(x.translation, y.translation)


def test_urdf_text_mesh_uris(links):
    """The description keeps package:// URIs or points them at this install's meshes."""
    assert "package://iCub/" in links.urdf_text()
    text = links.urdf_text(links.mesh_file_prefix())
    assert "package://iCub/" not in text and "file://" in text


def test_node_publishes_description_static_and_tf(ros_probe, links):
    """Over DDS: the latched URDF and /tf_static reach a late subscriber, /tf carries the joint
    state's stamp, and chaining /tf_static + /tf gives the model's hand pose. A malformed joint
    state is dropped and the node keeps working."""
    node = NodeProcess(command=[str(repo_root() / "scripts/robot_state_publisher.sh")])
    pub = ros_probe.node.create_publisher(JointState, "/joint_states", 10)
    q = links.model.posture("zero").copy()
    names = list(links.model.joint_names) + ["eyes_vergence"]
    q[links.model.indices(["r_elbow", "r_shoulder_pitch", "torso_yaw"])] = [0.9, -0.5, 0.3]
    good = JointState(name=names, position=[*q.tolist(), 0.2])
    good.header.stamp.sec, good.header.stamp.nanosec = 12, 345
    bad = JointState(name=names, position=[1.0])  # length mismatch
    stop = threading.Event()

    def feed() -> None:
        while not stop.is_set():
            pub.publish(bad)
            pub.publish(good)
            time.sleep(0.01)

    feeder = threading.Thread(target=feed, daemon=True)
    try:
        assert ros_probe.wait_for_topic("/tf", 60), node.output()
        feeder.start()
        desc = ros_probe.collect("/robot_description", String, 1, 20, qos=LATCHED_QOS)
        static = ros_probe.collect("/tf_static", TFMessage, 1, 20, qos=LATCHED_QOS)
        tf = ros_probe.collect("/tf", TFMessage, 3, 20, qos=TF_QOS)
        assert node.alive(), node.output()
    finally:
        stop.set()
        feeder.join(2)
        ros_probe.destroy(pub)
        node.stop()
    assert desc and "<robot" in desc[0].data and "file://" in desc[0].data
    assert static and len(static[0].transforms) == len(links.static())
    assert len(tf) == 3
    last = tf[-1]
    assert {(t.header.stamp.sec, t.header.stamp.nanosec) for t in last.transforms} == {(12, 345)}
    as_links = [
        LinkTransform(t.header.frame_id, t.child_frame_id,
                      np.array([t.transform.translation.x, t.transform.translation.y,
                                t.transform.translation.z]),
                      np.array([t.transform.rotation.x, t.transform.rotation.y,
                                t.transform.rotation.z, t.transform.rotation.w]))
        for t in static[0].transforms + last.transforms
    ]
    T = _compose(as_links, "r_hand_dh_frame")
    np.testing.assert_allclose(T.homogeneous,
                               links.model.frame_pose(q, "r_hand_dh_frame").homogeneous, atol=1e-9)
    assert "dropping /joint_states" in node.output()
