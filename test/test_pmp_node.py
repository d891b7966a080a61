"""The pmp_planner node over DDS: started as a user starts it (scripts/pmp_planner.sh, with
config/pmp_planner.yaml) in the test session's private domain; the test is the client."""

from __future__ import annotations

import math

import numpy as np
import pytest
from nav_msgs.msg import Path
from rclpy.qos import QoSProfile, ReliabilityPolicy
from trajectory_msgs.msg import JointTrajectory

from icub_interfaces.srv import Reach
from icub_pmp.ros.conversions import duration_to_sec, make_joint_state
from icub_pmp.testing import NodeProcess, repo_root

RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


@pytest.fixture(scope="module")
def node(ros_domain_id):
    """pmp_planner with a small posture memory (fast start), in the test domain."""
    proc = NodeProcess(command=[str(repo_root() / "scripts/pmp_planner.sh"), "--ros-args",
                                "-p", "posture_memory_size:=3000"])
    try:
        yield proc
    finally:
        proc.stop()


def request(hands=("right",), right=(-0.30, 0.15, 0.05), left=(-0.30, -0.15, 0.05), **kw):
    req = Reach.Request()
    req.hands = list(hands)
    for target, xyz in ((req.right_target, right), (req.left_target, left)):
        target.pose.position.x, target.pose.position.y, target.pose.position.z = xyz
    for k, v in kw.items():
        setattr(req, k, v)
    return req


def final_hand(model, resp, start, hand="right"):
    """Forward kinematics of the trajectory's last point (other joints at ``start``)."""
    q = model.q_from_dict(dict(zip(resp.trajectory.joint_names,
                                   resp.trajectory.points[-1].positions)), default=start)
    return model.frame_position(q, f"{hand[0]}_hand_dh_frame")


class Collector:
    """Messages of a topic received since creation."""

    def __init__(self, probe, topic, msg_type):
        self.msgs = []
        self.sub = probe.node.create_subscription(msg_type, topic, self.msgs.append, RELIABLE)


def test_reach_service_over_dds(node, ros_probe, model):
    """Without /joint_states the node plans from the rest posture and says so without
    executing; with /joint_states it plans from them, answers residual < 1 mm and a
    JointTrajectory from the current posture to the target at tau, publishes it on
    /joint_trajectory and the predicted hand path on /pmp/predicted_path/right_hand;
    simulate_only plans without publishing the trajectory; start_state overrides."""
    assert ros_probe.wait_for_service("/pmp/reach", Reach, 90.0), node.output()
    traj = Collector(ros_probe, "/joint_trajectory", JointTrajectory)
    paths = Collector(ros_probe, "/pmp/predicted_path/right_hand", Path)
    rest = model.posture("rest")

    # 1. no joint states yet: planned from rest, said so, not executed
    resp = ros_probe.call("/pmp/reach", Reach, request(tau=1.5))
    assert resp.success, resp.message
    assert "rest posture" in resp.message and "not executed" in resp.message
    assert list(resp.hands) == ["right"] and resp.residuals[0] < 1e-3
    assert np.linalg.norm(final_hand(model, resp, rest) - [-0.30, 0.15, 0.05]) < 1e-3
    pts = resp.trajectory.points
    assert duration_to_sec(pts[-1].time_from_start) == pytest.approx(1.5)
    assert duration_to_sec(pts[0].time_from_start) == 0.0
    assert "r_elbow" in resp.trajectory.joint_names and "torso_pitch" not in \
        resp.trajectory.joint_names

    # 2. with /joint_states: plans from them and executes
    current = rest.copy()
    current[model.indices(["r_elbow", "r_shoulder_pitch"])] = [1.0, -0.6]
    names = list(model.joint_names)
    pub = ros_probe.node.create_publisher(type(make_joint_state([])), "/joint_states", 10)
    state = make_joint_state(names, position=current)
    assert ros_probe.wait_for(lambda: pub.get_subscription_count() > 0, 20.0)

    def planned_from_state():
        pub.publish(state)
        r = ros_probe.call("/pmp/reach", Reach, request(use_torso=True, simulate_only=True))
        return "rest posture" not in r.message

    assert ros_probe.wait_for(planned_from_state, 20.0), node.output()
    n_traj = len(traj.msgs)
    resp = ros_probe.call("/pmp/reach", Reach, request(use_torso=True))
    assert resp.success and "sent on /joint_trajectory" in resp.message, resp.message
    first = dict(zip(resp.trajectory.joint_names, resp.trajectory.points[0].positions))
    for j in ("r_elbow", "r_shoulder_pitch", "torso_pitch"):
        assert first[j] == pytest.approx(current[names.index(j)], abs=1e-9)
    assert np.linalg.norm(final_hand(model, resp, current) - [-0.30, 0.15, 0.05]) < 1e-3
    assert ros_probe.wait_for(lambda: len(traj.msgs) > n_traj, 10.0)
    sent = traj.msgs[-1]
    assert list(sent.joint_names) == list(resp.trajectory.joint_names)
    assert len(sent.points) == len(resp.trajectory.points)
    assert ros_probe.wait_for(lambda: len(paths.msgs) > 0, 10.0)
    assert paths.msgs[-1].header.frame_id == "root_link"
    end = paths.msgs[-1].poses[-1].pose.position
    assert math.dist((end.x, end.y, end.z), (-0.30, 0.15, 0.05)) < 1e-3

    # 3. simulate_only: answered, not published
    n_traj = len(traj.msgs)
    resp = ros_probe.call("/pmp/reach", Reach, request(hands=("left", "right"),
                                                       simulate_only=True, use_torso=True))
    assert resp.success and list(resp.hands) == ["left", "right"], resp.message
    _next_published_is(ros_probe, traj, n_traj)

    # 4. start_state given: the trajectory starts there
    start = make_joint_state(["r_elbow"], position=[0.5])
    resp = ros_probe.call("/pmp/reach", Reach, request(start_state=start, simulate_only=True))
    first = dict(zip(resp.trajectory.joint_names, resp.trajectory.points[0].positions))
    assert first["r_elbow"] == pytest.approx(0.5)
    assert first["r_shoulder_pitch"] == pytest.approx(-0.6)  # from /joint_states
    ros_probe.destroy(pub)


def _next_published_is(probe, traj, n: int) -> None:
    """Nothing was published after the first ``n`` trajectories: a plan executed now is the
    next to arrive (one reliable publisher keeps its order). Its start_state makes it
    executable with or without /joint_states."""
    start = make_joint_state(["r_elbow"], position=[0.5])
    resp = probe.call("/pmp/reach", Reach, request(start_state=start))
    assert resp.success and "sent on /joint_trajectory" in resp.message, resp.message
    assert probe.wait_for(lambda: len(traj.msgs) > n, 10.0)
    sent = traj.msgs[n]
    assert len(traj.msgs) == n + 1
    assert [p.positions for p in sent.points] == [p.positions for p in resp.trajectory.points]


def test_bad_goals_answer_false_and_node_survives(node, ros_probe):
    """NaN target, unknown hand, duplicate hand, no hand, negative or huge tau, unknown frame,
    a zero quaternion with use_orientation, a malformed start_state: success=false with a message
    naming the problem. An unreachable target answers success=false with its residual (the
    distance left), is not executed, and the node keeps serving."""
    assert ros_probe.wait_for_service("/pmp/reach", Reach, 90.0), node.output()
    traj = Collector(ros_probe, "/joint_trajectory", JointTrajectory)
    bad = {
        "NaN": request(right=(math.nan, 0.1, 0.0)),
        "head": request(hands=("head",)),
        "twice": request(hands=("right", "right")),
        "empty": request(hands=()),
        "tau": request(tau=-1.0),
        "max_tau": request(tau=1e9),
    }
    req = request()
    req.right_target.header.frame_id = "no_such_frame"
    bad["no_such_frame"] = req
    req = request(use_orientation=True)
    req.right_target.pose.orientation.w = 0.0
    bad["zero quaternion"] = req
    bad["position has"] = request(start_state=make_joint_state(["r_elbow", "r_wrist_yaw"],
                                                               position=[0.3]))
    for needle, req in bad.items():
        resp = ros_probe.call("/pmp/reach", Reach, req)
        assert not resp.success, needle
        assert needle in resp.message, (needle, resp.message)
    resp = ros_probe.call("/pmp/reach", Reach, request(right=(-0.9, 0.6, 0.5)))
    assert not resp.success and "out of reach" in resp.message and "not executed" in resp.message
    assert resp.residuals[0] > 0.2  # the gap a tool would have to bridge [m]
    _next_published_is(ros_probe, traj, 0)
    assert node.alive()
    resp = ros_probe.call("/pmp/reach", Reach, request(simulate_only=True))
    assert resp.success, resp.message
