"""The cartesian_solver node over DDS: started as a user starts it (scripts/cartesian_solver.sh)
with posture_publisher as the /joint_states source, in the test session's private domain."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from trajectory_msgs.msg import JointTrajectory

from icub_interfaces.srv import GoToPose, SolvePose
from icub_pmp.kinematics import IcubModel
from icub_pmp.ros.conversions import duration_to_sec, make_joint_state
from icub_pmp.testing import NodeProcess, repo_root

TARGET = (-0.30, 0.15, 0.05)  # in front of the right shoulder, root_link [m]


@pytest.fixture(scope="module")
def graph(ros_domain_id):
    """cartesian_solver + posture_publisher (rest posture) running in the test domain."""
    solver = NodeProcess(command=[str(repo_root() / "scripts/cartesian_solver.sh")])
    joints = NodeProcess("posture_publisher")
    try:
        yield solver, joints
    finally:
        solver.stop()
        joints.stop()


def _request(cls, chain="torso_right_arm", xyz=TARGET):
    req = cls.Request()
    req.chain = chain
    req.target.pose.position.x, req.target.pose.position.y, req.target.pose.position.z = xyz
    return req


def _ready(probe, solver) -> None:
    assert probe.wait_for_service("/cartesian/solve_pose", SolvePose, 90.0), solver.output()
    # the node needs a /joint_states sample before it can answer without start_state
    assert probe.wait_for(
        lambda: "no /joint_states" not in probe.call(
            "/cartesian/solve_pose", SolvePose, _request(SolvePose)).message,
        30.0,
    ), solver.output()


def test_solve_pose_over_dds(graph, ros_probe):
    """solve_pose answers joints, residual (< 0.51 mm) and solve time; the joints put the
    right hand on the target (checked with pinocchio); nothing is published (the next trajectory
on /joint_trajectory is the one of a later go_to_pose)."""
    solver, _ = graph
    _ready(ros_probe, solver)
    got: list[JointTrajectory] = []
    sub = ros_probe.node.create_subscription(
        JointTrajectory, "/joint_trajectory", got.append,
        QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
    resp = ros_probe.call("/cartesian/solve_pose", SolvePose, _request(SolvePose))
    assert resp.success, resp.message
    assert resp.position_error < 5.1e-4
    assert math.isnan(resp.orientation_error)
    assert resp.solve_time > 0 and resp.iterations > 0
    assert resp.solver_status == "Solve_Succeeded"
    model = IcubModel()
    q = model.q_from_dict(dict(zip(resp.solution.name, resp.solution.position)),
                          default=model.posture("rest"))
    assert np.linalg.norm(model.frame_position(q, "r_hand_dh_frame") - TARGET) < 5.1e-4
    assert list(resp.solution.name)[:3] == ["torso_pitch", "torso_roll", "torso_yaw"]
    # a go_to_pose after it publishes a trajectory: the first one to arrive must be that one
    # (one reliable publisher keeps its order), so solve_pose published nothing
    moved = ros_probe.call("/cartesian/go_to_pose", GoToPose, _request(GoToPose))
    assert moved.success, moved.message
    assert ros_probe.wait_for(lambda: len(got) >= 1, 10.0)
    assert got[0].header.stamp == moved.trajectory.header.stamp
    assert len(got) == 1
    ros_probe.destroy(sub)


def test_bad_requests_answer_false(graph, ros_probe):
    """NaN target, unknown chain, unknown frame, zero quaternion with orientation, an
    unreachable point and a too-short trajectory time: success=false with a message (and the
    residual when a solve ran); the node stays up."""
    solver, _ = graph
    _ready(ros_probe, solver)
    call = ros_probe.call
    r = call("/cartesian/solve_pose", SolvePose, _request(SolvePose, xyz=(math.nan, 0.1, 0.0)))
    assert not r.success and "NaN" in r.message
    r = call("/cartesian/solve_pose", SolvePose, _request(SolvePose, chain="tail"))
    assert not r.success and "unknown chain 'tail'" in r.message
    req = _request(SolvePose)
    req.target.header.frame_id = "map"
    r = call("/cartesian/solve_pose", SolvePose, req)
    assert not r.success and "map" in r.message
    req = _request(SolvePose)
    req.use_orientation = True
    req.target.pose.orientation.w = 0.0
    r = call("/cartesian/solve_pose", SolvePose, req)
    assert not r.success and "quaternion" in r.message
    r = call("/cartesian/solve_pose", SolvePose, _request(SolvePose, xyz=(-2.0, 0.0, 0.0)))
    assert not r.success and r.position_error > 1.0 and "not reached" in r.message
    g = _request(GoToPose, xyz=(-2.0, 0.0, 0.0))
    r = call("/cartesian/go_to_pose", GoToPose, g)
    assert not r.success and len(r.trajectory.points) == 0
    g = _request(GoToPose)
    g.trajectory_time = 0.01
    r = call("/cartesian/go_to_pose", GoToPose, g)
    assert not r.success and "trajectory_time" in r.message
    assert solver.alive()


def test_go_to_pose_publishes_a_min_jerk_trajectory(graph, ros_probe):
    """go_to_pose publishes on /joint_trajectory the trajectory it returns: chain joints,
    starting at the request's start state (the rest posture: an explicit start never
    continues a running trajectory), ending at the solution; a second goal during the motion
    continues from the running trajectory."""
    solver, _ = graph
    _ready(ros_probe, solver)
    got: list[JointTrajectory] = []
    sub = ros_probe.node.create_subscription(
        JointTrajectory, "/joint_trajectory", got.append,
        QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
    ros_probe.wait_for(lambda: ros_probe.node.count_publishers("/joint_trajectory") > 0, 10.0)
    model = IcubModel()
    rest = model.posture("rest")
    req = _request(GoToPose)
    req.start_state = make_joint_state(model.joint_names, position=rest)
    r = ros_probe.call("/cartesian/go_to_pose", GoToPose, req)
    assert r.success, r.message
    assert "continued" not in r.message
    assert ros_probe.wait_for(lambda: len(got) >= 1, 10.0)
    msg = got[0]
    assert list(msg.joint_names) == list(r.solution.name)
    assert len(msg.points) == len(r.trajectory.points) > 100
    np.testing.assert_allclose(msg.points[0].positions, rest[model.indices(msg.joint_names)],
                               atol=1e-9)
    np.testing.assert_allclose(msg.points[-1].positions, r.solution.position, atol=2e-4)
    assert duration_to_sec(msg.points[-1].time_from_start) > 2.0
    r2 = ros_probe.call("/cartesian/go_to_pose", GoToPose,
                        _request(GoToPose, xyz=(-0.28, 0.20, 0.10)))
    assert r2.success, r2.message
    assert "continued from the running one" in r2.message
    ros_probe.destroy(sub)


def test_parameters_validated_at_run_time(graph, ros_probe):
    """Setting a bad parameter (epsilon < 0, unknown chain) is refused with a reason; a good
    one (epsilon) is accepted and used by the next solve."""
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters

    solver, _ = graph
    _ready(ros_probe, solver)

    def set_param(name, value):
        if isinstance(value, str):
            pv = ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=value)
        else:
            pv = ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value)
        req = SetParameters.Request(parameters=[Parameter(name=name, value=pv)])
        return ros_probe.call("/cartesian_solver/set_parameters", SetParameters, req).results[0]

    bad = set_param("epsilon", -1.0)
    assert not bad.successful and "epsilon" in bad.reason
    bad = set_param("default_chain", "tail")
    assert not bad.successful and "tail" in bad.reason
    assert set_param("epsilon", 1e-4).successful  # 10 mm allowed
    r = ros_probe.call("/cartesian/solve_pose", SolvePose, _request(SolvePose))
    assert r.success and r.position_error > 2e-3  # the looser bound is used
    assert set_param("epsilon", 2.5e-7).successful
