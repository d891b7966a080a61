"""The sim_bridge node over real DDS (node as a subprocess, started as a user does): streams
every 1 ms of sim time, cameras at 30 Hz, bad commands rejected while the node keeps running,
services, lockstep."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from geometry_msgs.msg import Pose, PoseStamped, WrenchStamped
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, Imu, JointState
from std_srvs.srv import SetBool

from icub_interfaces.msg import SelfContacts
from icub_interfaces.srv import ApplyWrench, ResetSim, SetObjectPose
from icub_pmp.config import config_dir
from icub_pmp.kinematics import RobotSpec
from icub_pmp.testing import NodeProcess, ros_environment

CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)


def _ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def _start(domain: int, **params) -> NodeProcess:
    return NodeProcess("sim_bridge", env=ros_environment(domain),
                       params_file=config_dir() / "sim_bridge.yaml", parameters=params)


@pytest.fixture(scope="module")
def bridge(ros_domain_id):
    proc = _start(ros_domain_id, cameras_enabled=True)
    try:
        yield proc
    finally:
        rc = proc.stop()
        assert rc == 0, proc.output()[-3000:]


def _call(probe, service: str, srv_type, request, idempotent: bool = True):
    """Call through one long-lived client per service. A fresh Fast DDS client can lose the
    response of its very first call while its reply reader is still being matched; idempotent
    requests are retried, a non-idempotent one must follow a warm-up call on its client."""
    clients = probe.__dict__.setdefault("sim_clients", {})  # one probe per test
    client = clients.get(service)
    if client is None:
        client = clients[service] = probe.node.create_client(srv_type, service)
    assert client.wait_for_service(timeout_sec=60.0), service
    for _ in range(3 if idempotent else 1):
        future = client.call_async(request)
        if probe.wait_for(future.done, 15.0):
            return future.result()
    raise TimeoutError(f"{service}: no answer")


def _wait_up(probe, proc: NodeProcess) -> None:
    assert probe.wait_for_topic("/joint_states", timeout=60.0), proc.output()[-3000:]


def test_joint_states_and_ft_every_step(bridge, ros_probe):
    """/joint_states (23 URDF joint names, position/velocity/effort) and /ft/l_arm_ft arrive
    every 1 ms of simulated time (consecutive stamps 1 ms apart); /clock runs, every
    clock_decimation steps (10 ms of simulated time by default)."""
    _wait_up(ros_probe, bridge)
    js = ros_probe.collect("/joint_states", JointState, 200)
    assert len(js) == 200, bridge.output()[-2000:]
    assert tuple(js[-1].name) == RobotSpec.load().actuated_joints
    assert len(js[-1].position) == len(js[-1].velocity) == len(js[-1].effort) == 23
    d = np.diff([_ns(m.header.stamp) for m in js])
    assert np.median(d) == 1_000_000 and np.all(d % 1_000_000 == 0)
    ft = ros_probe.collect("/ft/l_arm_ft", WrenchStamped, 100)
    assert len(ft) == 100 and ft[0].header.frame_id == "l_arm_ft"
    assert np.median(np.diff([_ns(m.header.stamp) for m in ft])) == 1_000_000
    clock = ros_probe.collect("/clock", Clock, 20, qos=CLOCK_QOS)
    assert _ns(clock[-1].clock) > _ns(clock[0].clock)
    assert np.all(np.diff([_ns(c.clock) for c in clock]) % 10_000_000 == 0)
    for topic, typ in (("/ft/r_arm_ft", WrenchStamped), ("/ft/l_leg_ft", WrenchStamped),
                       ("/ft/r_leg_ft", WrenchStamped), ("/imu", Imu),
                       ("/ground_truth/contact_wrench/left_hand", WrenchStamped),
                       ("/ground_truth/objects/box", PoseStamped)):
        assert len(ros_probe.collect(topic, typ, 3)) == 3, topic


def test_cameras_at_30hz(bridge, ros_probe):
    """Both cameras publish rgb8 320x240 images 1/30 s of sim time apart, with CameraInfo
    fx = fy = 343.12, cx = 160, cy = 120 in the optical frames."""
    _wait_up(ros_probe, bridge)
    for side, frame in (("left", "l_eye_optical"), ("right", "r_eye_optical")):
        imgs = ros_probe.collect(f"/cam/{side}/image_raw", Image, 4, timeout=30.0)
        assert len(imgs) == 4
        m = imgs[-1]
        assert (m.width, m.height, m.encoding, m.step, len(m.data)) == (
            320, 240, "rgb8", 960, 320 * 240 * 3)
        assert m.header.frame_id == frame
        d = np.diff([_ns(i.header.stamp) for i in imgs]) / 1e9
        assert np.min(d) == pytest.approx(1 / 30, abs=1.1e-3)
        info = ros_probe.collect(f"/cam/{side}/camera_info", CameraInfo, 1)[0]
        assert list(info.k) == [343.12, 0.0, 160.0, 0.0, 343.12, 120.0, 0.0, 0.0, 1.0]
        assert info.header.frame_id == frame


def _effort(probe, joint: str) -> float:
    msg = probe.collect("/joint_states", JointState, 1)[0]
    return msg.effort[list(msg.name).index(joint)]


def test_bad_commands_rejected_node_keeps_running(bridge, ros_probe):
    """Effort commands with an unknown name, NaN, inf or mismatched lengths are dropped with a
    warning and change nothing; the node keeps running and then applies a valid command,
    saturated at the torque limit (l_elbow: 20 N m)."""
    _wait_up(ros_probe, bridge)
    from rclpy.qos import qos_profile_sensor_data

    pub = ros_probe.node.create_publisher(JointState, "/effort_command",
                                          qos_profile_sensor_data)
    assert ros_probe.wait_for(lambda: pub.get_subscription_count() > 0, 30.0)
    bad = [
        JointState(name=["l_elbow", "nose"], effort=[1.0, 2.0]),
        JointState(name=["l_elbow"], effort=[math.nan]),
        JointState(name=["l_elbow"], effort=[math.inf]),
        JointState(name=["l_elbow", "r_elbow"], effort=[1.0]),
        JointState(name=[], effort=[]),
    ]
    before = _effort(ros_probe, "r_elbow")
    for _ in range(3):
        for m in bad:
            pub.publish(m)
        time.sleep(0.05)
    assert bridge.wait_for_output("rejected", 10.0), bridge.output()[-2000:]
    assert bridge.alive()
    assert _effort(ros_probe, "r_elbow") == pytest.approx(before, abs=0.5)  # still held
    ok = JointState(name=["l_elbow"], effort=[100.0])
    assert ros_probe.wait_for(lambda: (pub.publish(ok), _effort(ros_probe, "l_elbow"))[1]
                              == 20.0, 20.0)
    assert bridge.alive()
    resp = _call(ros_probe, "/sim/reset", ResetSim, ResetSim.Request(posture="rest"))
    assert resp.success, resp.message
    ros_probe.destroy(pub)


def test_services(bridge, ros_probe):
    """reset (a bad posture is refused with the valid names), set_object_pose (ground truth
    follows; unknown objects refused), apply_wrench (ground-truth hand wrench shows it),
    set_paused (the clock stops and resumes)."""
    _wait_up(ros_probe, bridge)
    r = _call(ros_probe, "/sim/reset", ResetSim, ResetSim.Request(posture="dance"))
    assert not r.success and "rest" in r.message
    pose = Pose()
    pose.position.x, pose.position.y, pose.position.z = -0.5, -0.2, -0.05
    pose.orientation.w = 1.0
    r = _call(ros_probe, "/sim/set_object_pose", SetObjectPose,
              SetObjectPose.Request(name="box", pose=pose))
    assert r.success, r.message
    gt = ros_probe.collect("/ground_truth/objects/box", PoseStamped, 5)[-1]
    assert (gt.pose.position.x, gt.pose.position.y) == pytest.approx((-0.5, -0.2), abs=1e-3)
    r = _call(ros_probe, "/sim/set_object_pose", SetObjectPose,
              SetObjectPose.Request(name="ball", pose=pose))
    assert not r.success and "box" in r.message
    r = _call(ros_probe, "/sim/apply_wrench", ApplyWrench,
              ApplyWrench.Request(target="nowhere", duration=1.0))  # also warms the client up
    assert not r.success and "nowhere" in r.message
    req = ApplyWrench.Request(target="r_hand_dh_frame", duration=30.0)
    req.wrench.force.z = -3.0
    r = _call(ros_probe, "/sim/apply_wrench", ApplyWrench, req, idempotent=False)
    assert r.success, r.message
    w = ros_probe.collect("/ground_truth/contact_wrench/right_hand", WrenchStamped, 5)[-1]
    assert w.wrench.force.z == pytest.approx(-3.0, abs=1e-6)
    assert _call(ros_probe, "/sim/set_paused", SetBool, SetBool.Request(data=True)).success
    assert ros_probe.collect("/joint_states", JointState, 1, timeout=1.0) == []  # paused
    assert _call(ros_probe, "/sim/set_paused", SetBool, SetBool.Request(data=False)).success
    assert len(ros_probe.collect("/joint_states", JointState, 5)) == 5
    assert _call(ros_probe, "/sim/reset", ResetSim, ResetSim.Request(posture="")).success


def test_self_contacts_when_the_arms_meet(bridge, ros_probe):
    """/ground_truth/self_contacts (root_link) is an empty list at rest; driving both arms
    inwards (constant shoulder torques, objects moved off the table) brings the hands
    together and the topic reports an arm-arm contact, left link first, with a force."""
    _wait_up(ros_probe, bridge)
    assert _call(ros_probe, "/sim/reset", ResetSim, ResetSim.Request(posture="rest")).success
    for name, (x, y, z) in (("box", (-0.5, 0.35, -0.05)), ("cylinder", (-0.5, -0.35, -0.03))):
        pose = Pose()
        pose.position.x, pose.position.y, pose.position.z = x, y, z
        pose.orientation.w = 1.0
        r = _call(ros_probe, "/sim/set_object_pose", SetObjectPose,
                  SetObjectPose.Request(name=name, pose=pose))
        assert r.success, r.message
    rest = ros_probe.collect("/ground_truth/self_contacts", SelfContacts, 3)
    assert len(rest) == 3 and rest[-1].header.frame_id == "root_link"
    assert all(len(m.contacts) == 0 for m in rest)
    from rclpy.qos import qos_profile_sensor_data

    got = []
    sub = ros_probe.node.create_subscription(
        SelfContacts, "/ground_truth/self_contacts",
        lambda m: got.append(m) if any(c.kind == "arm-arm" for c in m.contacts) else None,
        qos_profile_sensor_data)
    pub = ros_probe.node.create_publisher(JointState, "/effort_command",
                                          qos_profile_sensor_data)
    assert ros_probe.wait_for(lambda: pub.get_subscription_count() > 0, 30.0)
    cmd = JointState(name=[f"{s}_shoulder_{j}" for s in "lr" for j in ("pitch", "yaw", "roll")],
                     effort=[-5.0, 4.0, -3.0] * 2)
    assert ros_probe.wait_for(lambda: (pub.publish(cmd), bool(got))[1], 30.0), \
        bridge.output()[-2000:]
    c = next(c for c in got[0].contacts if c.kind == "arm-arm")
    assert c.body1.startswith("l_") and c.body2.startswith("r_") and c.normal_force > 0.0
    assert math.hypot(c.force.x, c.force.y, c.force.z) > 0.0
    ros_probe.destroy(sub)
    ros_probe.destroy(pub)


def test_object_contacts_when_the_cylinder_drops_on_the_hand(bridge, ros_probe):
    """/ground_truth/object_contacts (root_link) is an empty list while no link touches an
    object; the cylinder dropped onto the resting right hand is reported as robot-object
    contacts (icub_interfaces/ObjectContacts): the right arm's link and the cylinder, with a
    normal force."""
    from rclpy.qos import qos_profile_sensor_data

    from icub_pmp.kinematics import IcubModel

    _wait_up(ros_probe, bridge)
    assert _call(ros_probe, "/sim/reset", ResetSim, ResetSim.Request(posture="rest")).success
    from icub_interfaces.msg import ObjectContacts

    rest = ros_probe.collect("/ground_truth/object_contacts", ObjectContacts, 3)
    assert len(rest) == 3 and rest[-1].header.frame_id == "root_link"
    assert all(len(m.contacts) == 0 for m in rest)
    model = IcubModel()
    hand = model.frame_position(model.posture("rest"), "r_hand_dh_frame")
    got = []
    sub = ros_probe.node.create_subscription(
        ObjectContacts, "/ground_truth/object_contacts",
        lambda m: got.append(m) if m.contacts else None, qos_profile_sensor_data)
    pose = Pose()
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in hand + [0, 0, 0.09])
    pose.orientation.w = 1.0
    r = _call(ros_probe, "/sim/set_object_pose", SetObjectPose,
              SetObjectPose.Request(name="cylinder", pose=pose))
    assert r.success, r.message
    assert ros_probe.wait_for(lambda: bool(got), 30.0), bridge.output()[-2000:]
    c = got[0].contacts[0]
    assert c.object == "cylinder" and c.body.startswith("r_") and c.arm == "right"
    assert max(c.normal_force for m in got for c in m.contacts) > 0.0
    ros_probe.destroy(sub)
    assert _call(ros_probe, "/sim/reset", ResetSim, ResetSim.Request(posture="rest")).success


def test_runtime_parameters_validated(bridge, ros_probe):
    """Run-time parameter changes are validated: a bad mode and a model-shaping parameter are
    refused with a reason, a valid real_time_factor is accepted; the node keeps running."""
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters

    def set_param(name, value):
        if isinstance(value, str):
            v = ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=value)
        else:
            v = ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value)
        req = SetParameters.Request(parameters=[Parameter(name=name, value=v)])
        return _call(ros_probe, "/sim_bridge/set_parameters", SetParameters, req).results[0]

    _wait_up(ros_probe, bridge)
    r = set_param("mode", "warp")
    assert not r.successful and "mode" in r.reason
    r = set_param("box_mass", 1.0)
    assert not r.successful
    r = set_param("real_time_factor", 1.0)
    assert r.successful, r.reason
    assert bridge.alive()
