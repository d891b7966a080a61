"""The new /pmp/reach fields over DDS: pmp_planner started as a user starts it
(scripts/pmp_planner.sh with config/pmp_planner.yaml) in the test's private domain, the test
the client. Plans are mental simulations from the rest posture (published on /joint_states),
judged by forward kinematics of the answered trajectory on the iCub model."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState

from icub_interfaces.action import Reach as ReachAction
from icub_interfaces.msg import Obstacle, Obstacles
from icub_interfaces.srv import Reach
from icub_pmp.kinematics.rotations import matrix_to_quat_wxyz
from icub_pmp.ros.conversions import make_joint_state
from icub_pmp.testing import NodeProcess, repo_root, run_icub

RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
TARGET = (-0.28, 0.10, 0.20)  # right hand target [m], root_link, ~0.2 m from the rest hand
#: the obstacle scene's target [m, root_link], 0.2 m from the rest hand, mostly sideways: the
#: obstacle on the hand's way leaves room for the forearm, which trails behind the hand (going
#: up to TARGET, the forearm ends where the hand passed half way: no room for the arm's volume)
OBSTACLE_TARGET = (-0.30, 0.0, 0.15)


@pytest.fixture(scope="module")
def node(ros_domain_id, ros_probe_module, model):
    """pmp_planner with a small posture memory (fast start), in the test domain, with the
    rest posture published on /joint_states (20 Hz) so every plan starts there."""
    proc = NodeProcess(command=[str(repo_root() / "scripts/pmp_planner.sh"), "--ros-args",
                                "-p", "posture_memory_size:=3000"])
    probe = ros_probe_module
    pub = probe.node.create_publisher(JointState, "/joint_states", 10)
    rest = make_joint_state(list(model.joint_names), position=model.posture("rest"))
    timer = probe.node.create_timer(0.05, lambda: pub.publish(rest))
    try:
        assert probe.wait_for_service("/pmp/reach", Reach, 90.0), proc.output()
        assert probe.wait_for(lambda: "rest posture" not in probe.call(
            "/pmp/reach", Reach, request()).message, 30.0), proc.output()
        yield proc
    finally:
        probe.destroy(timer, pub)
        proc.stop()


def set_xyz(msg, xyz) -> None:
    msg.x, msg.y, msg.z = (float(v) for v in xyz)


def request(hands=("right",), right=TARGET, left=(-0.28, -0.10, 0.20), kind=Reach.Request,
            **kw):
    req = kind()
    req.hands = list(hands)
    set_xyz(req.right_target.pose.position, right)
    set_xyz(req.left_target.pose.position, left)
    if kind is Reach.Request:
        req.simulate_only = True
    for k, v in kw.items():
        setattr(req, k, v)
    return req


def sphere(centre, radius: float) -> Obstacle:
    ob = Obstacle()
    ob.type = "sphere"
    set_xyz(ob.pose.position, centre)
    ob.radius = float(radius)
    return ob


def hand_path(model, resp, hand: str) -> np.ndarray:
    """(N, 3) forward kinematics of every trajectory point (other joints at rest)."""
    rest = model.posture("rest")
    names = list(resp.trajectory.joint_names)
    out = []
    for p in resp.trajectory.points:
        q = model.q_from_dict(dict(zip(names, p.positions)), default=rest)
        out.append(model.frame_position(q, f"{hand[0]}_hand_dh_frame"))
    return np.array(out)


def joint_path(resp, joint: str) -> np.ndarray:
    k = list(resp.trajectory.joint_names).index(joint)
    return np.array([p.positions[k] for p in resp.trajectory.points])


def call(probe, node, req) -> Reach.Response:
    assert probe.wait_for_service("/pmp/reach", Reach, 90.0), node.output()
    return probe.call("/pmp/reach", Reach, req)


def test_coupled_transport_keeps_the_grasp(node, ros_probe, model):
    """hold_object (Sect. 3.2, Fig 8): the object held between the hands goes to its goal and
    pulls both hands; the hand-to-hand distance stays within 5 mm of its start along the whole
    plan, the answered object path ends at the goal."""
    rest = model.posture("rest")
    hands0 = {h: model.frame_position(rest, f"{h[0]}_hand_dh_frame") for h in ("left", "right")}
    mid = 0.5 * (hands0["left"] + hands0["right"])
    goal = mid + np.array([0.06, 0.04, 0.10])
    req = request(hands=("left", "right"), hold_object=True, use_torso=True)
    set_xyz(req.object_goal.pose.position, goal)
    resp = call(ros_probe, node, req)
    assert resp.success, resp.message
    left, right = hand_path(model, resp, "left"), hand_path(model, resp, "right")
    dist = np.linalg.norm(left - right, axis=1)
    d0 = np.linalg.norm(hands0["left"] - hands0["right"])
    assert np.max(np.abs(dist - d0)) < 0.005, np.max(np.abs(dist - d0))
    assert np.linalg.norm(0.5 * (left[-1] + right[-1]) - goal) < 0.002
    obj = np.array([[p.x, p.y, p.z] for p in resp.object_path])
    assert len(obj) == len(resp.trajectory.points)
    assert np.linalg.norm(obj[0] - mid) < 1e-6 and np.linalg.norm(obj[-1] - goal) < 0.002


def test_obstacle_between_hand_and_target_is_avoided_with_the_clearance(node, ros_probe, model):
    """A sphere placed on the unconstrained path (which goes through it) is avoided: the plan
    reaches the target and every trajectory point keeps the asked clearance from the sphere,
    the hand's and the arm's volume's (hand, wrist, forearm hulls); the answer reports that
    clearance."""
    free = call(ros_probe, node, request(right=OBSTACLE_TARGET))
    assert free.success, free.message
    assert free.obstacle_clearance == -1.0 and len(free.object_path) == 0
    path = hand_path(model, free, "right")
    centre, radius, clearance = path[int(0.4 * (len(path) - 1))], 0.03, 0.02
    assert np.min(np.linalg.norm(path - centre, axis=1)) - radius < 0  # goes through it
    resp = call(ros_probe, node, request(right=OBSTACLE_TARGET, obstacles=[
        sphere(centre, radius)], obstacle_clearance=clearance))
    assert resp.success, resp.message
    path = hand_path(model, resp, "right")
    kept = np.min(np.linalg.norm(path - centre, axis=1)) - radius
    assert kept >= clearance - 1e-3, kept
    # the reported clearance is the arm volume's (not the hand frames' alone: decision 0063)
    assert resp.obstacle_clearance >= clearance and "obstacle clearance" in resp.message
    assert "hand frames only" not in resp.message, resp.message
    assert np.linalg.norm(path[-1] - OBSTACLE_TARGET) < 1e-3

    # a wall (a thin box 60 x 60 cm) across the way: no path, said so, not executed
    start = hand_path(model, free, "right")[0]
    z = (np.array(TARGET) - start) / np.linalg.norm(np.array(TARGET) - start)
    x = np.cross([1.0, 0.0, 0.0], z)
    x /= np.linalg.norm(x)
    wall = Obstacle(type="box")
    set_xyz(wall.pose.position, 0.5 * (start + np.array(TARGET)))
    o = wall.pose.orientation
    o.w, o.x, o.y, o.z = matrix_to_quat_wxyz(np.column_stack([x, np.cross(z, x), z]))
    set_xyz(wall.size, (0.6, 0.6, 0.02))
    resp = call(ros_probe, node, request(obstacles=[wall], simulate_only=False))
    assert not resp.success and "blocked by the obstacles" in resp.message, resp.message
    assert "not executed" in resp.message


def test_tight_torque_limit_with_force_target_is_respected(node, ros_probe):
    """A 10 N push down at the target (Sect. 2.3, Fig 3): the answer gives the joint torques at
    the final posture. With the elbow limited to half of what the unconstrained plan needs,
    the settled plan keeps the elbow within it (and says so) and still reaches the target."""
    req = request()
    req.right_force.z = -10.0
    free = call(ros_probe, node, req)
    assert free.success and free.torques_within_limits, free.message
    torques = dict(zip(free.torque_joints, free.torques))
    assert set(torques) == set(free.trajectory.joint_names)
    limit = 0.5 * abs(torques["r_elbow"])
    assert limit > 0.05
    req.torque_limit_joints, req.torque_limits = ["r_elbow"], [limit]
    resp = call(ros_probe, node, req)
    assert resp.success and resp.torques_within_limits, resp.message
    assert abs(dict(zip(resp.torque_joints, resp.torques))["r_elbow"]) <= limit
    assert abs(torques["r_elbow"]) > limit  # the unconstrained plan does not respect it
    assert resp.residuals[0] < 1e-3


def test_frozen_joint_and_stiff_trunk_do_not_move(node, ros_probe):
    """frozen_joints keeps a joint at its start along the plan (it moves without); a stiff
    trunk (grounded shoulders, Fig 7) keeps the torso still, a compliant one moves it more than
    the configured one."""
    far = (-0.20, 0.05, 0.30)
    free = call(ros_probe, node, request(right=far, use_torso=True))
    assert free.success, free.message
    assert np.ptp(joint_path(free, "r_wrist_prosup")) > 0.01
    frozen = call(ros_probe, node, request(right=far, use_torso=True,
                                           frozen_joints=["r_wrist_prosup"]))
    assert frozen.success, frozen.message
    assert np.ptp(joint_path(frozen, "r_wrist_prosup")) == 0.0
    torso = ("torso_pitch", "torso_roll", "torso_yaw")
    moved = {}
    for mode in ("", "stiff", "compliant"):
        resp = call(ros_probe, node, request(right=far, use_torso=True, trunk_admittance=mode))
        moved[mode] = sum(np.ptp(joint_path(resp, j)) for j in torso)
    assert moved["stiff"] == 0.0
    assert moved["compliant"] > moved[""] > 0.0


def test_obstacle_topic_is_merged_and_bad_fields_are_answered(node, ros_probe):
    """/pmp/obstacles adds its obstacles to every request (a sphere on the target rejects it,
    naming the topic; an empty scene clears it); a bad value of each new field answers
    success=false with a message naming the field, on the service and on the action, and the
    node keeps serving."""
    assert ros_probe.wait_for_service("/pmp/reach", Reach, 90.0), node.output()
    pub = ros_probe.node.create_publisher(Obstacles, "/pmp/obstacles", RELIABLE)
    assert ros_probe.wait_for(lambda: pub.get_subscription_count() > 0, 30.0)
    scene = Obstacles(obstacles=[sphere(TARGET, 0.04)])

    def rejected_by_scene():
        pub.publish(scene)
        return "/pmp/obstacles[0]" in ros_probe.call("/pmp/reach", Reach, request()).message

    assert ros_probe.wait_for(rejected_by_scene, 20.0), node.output()

    def cleared():
        pub.publish(Obstacles())
        return ros_probe.call("/pmp/reach", Reach, request()).success

    assert ros_probe.wait_for(cleared, 20.0), node.output()

    bad = {
        "hold_object": request(hold_object=True),
        "obstacles[0].radius": request(obstacles=[sphere((0.0, 0.3, 0.3), -0.1)]),
        "obstacles[0].type": request(obstacles=[Obstacle(type="cone")]),
        "encloses": request(obstacles=[sphere(TARGET, 0.05)]),
        "obstacle_clearance": request(obstacle_clearance=math.nan),
        "torque_limit_joints/torque_limits": request(torque_limit_joints=["r_elbow"]),
        "torque_limit_joints": request(torque_limit_joints=["r_elbo"], torque_limits=[1.0]),
        "trunk_admittance": request(use_torso=True, trunk_admittance="floppy"),
        "frozen_joints": request(frozen_joints=["no_joint"]),
        "admittance_scales": request(admittance_scale_joints=["r_elbow"],
                                     admittance_scales=[-1.0]),
    }
    req = request()
    req.right_force.x = math.inf
    bad["right_force"] = req
    req = request(hands=("left", "right"), hold_object=True)
    req.object_goal.header.frame_id = "no_such_frame"
    bad["object_goal.header.frame_id"] = req
    for needle, req in bad.items():
        resp = ros_probe.call("/pmp/reach", Reach, req)
        assert not resp.success and needle in resp.message, (needle, resp.message)

    client = ros_probe.action_client("/pmp/reach_action", ReachAction, 30.0)
    goal = request(kind=ReachAction.Goal, frozen_joints=["no_joint"])
    out = ros_probe.send_goal(client, goal, timeout=60.0)
    assert out.result.outcome == "rejected" and "frozen_joints" in out.result.message, \
        out.result.message
    ros_probe.destroy(client, pub)
    assert node.alive()
    assert ros_probe.call("/pmp/reach", Reach, request()).success


def _value(out: str, label: str) -> str:
    """The text after ``label`` on its line of the CLI's output."""
    line = next(x for x in out.splitlines() if x.startswith(label))
    return line[len(label):].strip()


def test_cli_flags_reach_the_planner(node, ros_probe, model):
    """``icub reach`` with --hold, --obstacle/--clearance, --force/--torque-limit, --trunk,
    --freeze and --scale (--simulate: the /pmp/reach service) prints the planner's answer: the
    object path ends at the held object's goal, the clearance kept, the torques within the
    tight limit; the planner's rejection (an obstacle on the target) exits 1 with its message."""
    assert ros_probe.wait_for_service("/pmp/reach", Reach, 90.0), node.output()
    rest = model.posture("rest")
    mid = 0.5 * sum(model.frame_position(rest, f"{h}_hand_dh_frame") for h in "lr")
    goal = mid + np.array([0.05, 0.0, 0.10])
    out = run_icub("reach", "--hold=" + ",".join(f"{v:.4f}" for v in goal), "--torso",
                   "--simulate")
    assert out.returncode == 0, out.stdout + out.stderr
    end = _value(out.stdout, "object path:").split("ends at (")[1].split(")")[0]
    assert np.linalg.norm(np.array([float(v) for v in end.split(",")]) - goal) < 0.002

    # the sphere on the hand's way to OBSTACLE_TARGET, with room for the arm's volume
    out = run_icub("reach", "right=-0.30,0.0,0.15", "--obstacle",
                   "sphere:-0.325,0.123,0.044,0.03", "--obstacle", "box:0.2,0.0,0.0,0.1,0.1,0.1",
                   "--clearance", "0.02", "--simulate")
    assert out.returncode == 0, out.stdout + out.stderr
    assert float(_value(out.stdout, "obstacle clearance:").split()[0]) >= 20.0
    assert "hand frames only" not in out.stdout, out.stdout

    out = run_icub("reach", "right=-0.28,0.10,0.20", "--force", "0,0,-10", "--torque-limit",
                   "r_elbow=0.25", "--simulate")
    assert out.returncode == 0, out.stdout + out.stderr
    assert _value(out.stdout, "torques within limits:") == "True"
    torques = _value(out.stdout, "torques at the final posture [N m]:")
    elbow = float(torques.split("r_elbow ")[1].split(",")[0])
    assert abs(elbow) <= 0.25

    out = run_icub("reach", "right=-0.20,0.05,0.30", "--trunk", "stiff", "--freeze",
                   "r_wrist_prosup", "--scale", "r_shoulder_yaw=2", "--simulate")
    assert out.returncode == 0 and "success: True" in out.stdout, out.stdout + out.stderr

    out = run_icub("reach", "right=-0.28,0.10,0.20", "--obstacle",
                   "sphere:-0.28,0.10,0.20,0.05", "--simulate")
    assert out.returncode == 1 and "encloses the right hand's target" in out.stdout, \
        out.stdout + out.stderr


@pytest.mark.parametrize("args, expected", [
    (["right=-0.3,0.1,0.1", "--obstacle", "sphere:0,0,0,-0.1"], "sizes must be > 0"),
    (["right=-0.3,0.1,0.1", "--obstacle", "cone:0,0,0"], "--obstacle 'cone:0,0,0'"),
    (["right=-0.3,0.1,0.1", "--force", "0,0"], "--force"),
    (["right=-0.3,0.1,0.1", "--force", "left=0,0,-10"], "the left hand has no target"),
    (["right=-0.3,0.1,0.1", "--torque-limit", "r_elbow=-1"], "--torque-limit"),
    (["right=-0.3,0.1,0.1", "--trunk", "floppy"], "--trunk"),
    (["right=-0.3,0.1,0.1", "--freeze", "r_elbo"], "--freeze"),
    (["right=-0.3,0.1,0.1", "--hold", "0,0,0"], "--hold"),
    (["--hold", "0,0,nan"], "NaN"),
])
def test_cli_bad_flags_exit_with_one_line(args, expected):
    """Bad PMP flags: exit 2 or 1 with a one-line error before anything is sent."""
    out = run_icub("reach", *args, "--simulate", "--timeout", "1")
    assert out.returncode != 0
    err = out.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("icub: error:") and expected in err[0], out.stderr


def test_a_transport_starts_from_the_controllers_set_point(node, ros_probe, model):
    """A held object is carried from the commanded grasp: with a recent set-point on
    /impedance_controller/state (the elbows bent 0.1 rad more than measured, as a squeeze
    leaves them), the transport's first point is that set-point and the message says so; with
    a set-point 5 s older than the joint states, the plan starts from the measured joints."""
    from builtin_interfaces.msg import Time

    rest = model.posture("rest")
    commanded = rest.copy()
    for j in ("l_elbow", "r_elbow"):
        commanded[model.indices([j])[0]] += 0.1
    names = list(model.joint_names)
    pub = ros_probe.node.create_publisher(JointState, "/impedance_controller/state", 10)
    mid = 0.5 * (model.frame_position(rest, "l_hand_dh_frame")
                 + model.frame_position(rest, "r_hand_dh_frame"))

    def transport() -> Reach.Response:
        req = request(hands=("left", "right"), hold_object=True, use_torso=True)
        set_xyz(req.object_goal.pose.position, mid + [0.0, 0.0, 0.05])
        return call(ros_probe, node, req)

    try:
        recent = make_joint_state(names, position=commanded)
        timer = ros_probe.node.create_timer(0.05, lambda: pub.publish(recent))
        assert ros_probe.wait_for(lambda: "from the controller's set-point" in
                                  transport().message, 30.0)
        resp = transport()
        assert resp.success and "controller's set-point" in resp.message, resp.message
        assert abs(joint_path(resp, "r_elbow")[0] - commanded[model.indices(["r_elbow"])[0]]) \
            < 1e-6
        ros_probe.destroy(timer)
        old = make_joint_state(names, position=commanded, stamp=Time(sec=5))
        timer = ros_probe.node.create_timer(0.05, lambda: pub.publish(old))
        assert ros_probe.wait_for(lambda: "no recent controller set-point" in
                                  transport().message, 30.0)
        resp = transport()
        assert abs(joint_path(resp, "r_elbow")[0] - rest[model.indices(["r_elbow"])[0]]) < 1e-6
    finally:
        ros_probe.destroy(timer, pub)
