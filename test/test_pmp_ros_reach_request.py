"""The Reach request validation (icub_pmp/ros/reach_request.py) on real request messages:
what each new field builds into the ReachGoal, and one clear rejection per bad input, the
message naming the field. Fast: no body model (frames and hand positions given)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from icub_interfaces.action import Reach as ReachAction
from icub_interfaces.msg import Obstacle
from icub_interfaces.srv import Reach
from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics import RobotSpec
from icub_pmp.ros.reach_request import FramePose, ReachRequestConfig, parse_reach_request

SPEC = RobotSpec.load()
JOINTS = SPEC.actuated_joints
HANDS_AT = {"left": np.array([-0.30, -0.20, 0.02]), "right": np.array([-0.30, 0.20, 0.02])}
CHEST = FramePose(np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
                  np.array([0.0, 0.0, 0.10]))
CONFIG = ReachRequestConfig()


def frames(name: str) -> FramePose:
    if name != "chest":
        raise UnknownName("frame", name, ["chest", "root_link"])
    return CHEST


def parse(req):
    return parse_reach_request(req, frames=frames, hand_positions=HANDS_AT,
                               joint_names=JOINTS, config=CONFIG)


def set_xyz(msg, xyz) -> None:
    msg.x, msg.y, msg.z = (float(v) for v in xyz)


def request(hands=("right",), right=(-0.25, 0.10, 0.20), left=(-0.25, -0.10, 0.20),
            kind=Reach.Request, **kw):
    req = kind()
    req.hands = list(hands)
    set_xyz(req.right_target.pose.position, right)
    set_xyz(req.left_target.pose.position, left)
    for k, v in kw.items():
        setattr(req, k, v)
    return req


def obstacle(kind="sphere", centre=(-0.30, 0.15, 0.10), radius=0.03, length=0.0,
             size=(0.0, 0.0, 0.0), frame=""):
    ob = Obstacle()
    ob.type = kind
    ob.header.frame_id = frame
    set_xyz(ob.pose.position, centre)
    ob.radius = radius
    ob.length = length
    set_xyz(ob.size, size)
    return ob


def held(goal=(-0.25, 0.0, 0.15), **kw):
    req = request(hands=("left", "right"), hold_object=True, use_torso=True, **kw)
    set_xyz(req.object_goal.pose.position, goal)
    return req


def test_old_requests_build_the_same_goal():
    """A request using none of the new fields gives the goal it gave before: targets only, no
    obstacle, object, force, limit or admittance change, trunk scale 1."""
    parsed = parse(request(use_torso=True))
    g = parsed.goal
    assert list(g.targets) == ["right"] and np.allclose(g.targets["right"], [-0.25, 0.10, 0.20])
    assert g.obstacles == () and g.held_object is None and not g.target_forces
    assert not g.torque_limits and not g.admittance_scales and g.frozen_joints == ()
    assert g.trunk_admittance_scale == 1.0 and not parsed.report_torques


def test_the_action_goal_is_parsed_by_the_same_code():
    """The action's goal has the same fields: the same goal comes out."""
    a = parse(request(kind=ReachAction.Goal, use_torso=True)).goal
    b = parse(request(use_torso=True)).goal
    assert np.allclose(a.targets["right"], b.targets["right"])


def test_held_object_from_the_hands_and_with_grasp_points():
    """hold_object with no pose and no grasp points: the object is the hands' midpoint and the
    grasps where the hands are; given grasp points are rotated by the object's orientation
    and the hands' final targets are the goal plus them (Sect. 3.2)."""
    g = parse(held()).goal
    ho = g.held_object
    assert np.allclose(ho.position, [-0.30, 0.0, 0.02])
    assert np.allclose(ho.grasp_offsets["right"], [0.0, 0.20, 0.0])
    assert np.allclose(ho.hand_targets()["left"], [-0.25, -0.20, 0.15])
    assert g.targets == {} and sorted(g.hands) == ["left", "right"]

    req = held()
    req.object_pose.header.frame_id = "chest"  # rotated 90 deg about z, 0.1 m up
    req.object_pose.pose.position.x = 0.0
    req.object_goal.header.frame_id = "chest"
    set_xyz(req.right_grasp, (0.15, 0.0, 0.0))
    set_xyz(req.left_grasp, (-0.15, 0.0, 0.0))
    ho = parse(req).goal.held_object
    assert np.allclose(ho.position, [0.0, 0.0, 0.10])
    assert np.allclose(ho.grasp_offsets["right"], [0.0, 0.15, 0.0])
    assert np.allclose(ho.goal, CHEST.rotation @ [-0.25, 0.0, 0.15] + CHEST.translation)


def test_a_held_object_with_use_orientation_keeps_the_hands_start_orientations():
    """hold_object + use_orientation: each grasping hand's orientation target is its frame's
    rotation at the start (a rigid grasp in translation does not turn the hands); without
    use_orientation the hands are free to turn; without the hands' frames it is refused."""
    assert parse(held()).goal.orientations == {}
    g = parse_reach_request(held(use_orientation=True), frames=frames, hand_positions=HANDS_AT,
                            joint_names=JOINTS, config=CONFIG,
                            hand_frames={"left": "chest", "right": "chest"}).goal
    assert sorted(g.orientations) == ["left", "right"]
    assert np.allclose(g.orientations["right"], CHEST.rotation)
    with pytest.raises(InvalidInput, match="use_orientation with hold_object"):
        parse(held(use_orientation=True))


def test_obstacles_are_built_in_root_link_and_grown_by_the_clearance():
    """Each primitive becomes a field in root_link; the fields keep clearance + margin; the
    default clearance comes from the configuration."""
    req = request(obstacles=[
        obstacle(),
        obstacle("capsule", (0.0, 0.0, 0.0), 0.02, length=0.2, frame="chest"),
        obstacle("box", (-0.2, 0.35, 0.0), size=(0.1, 0.1, 0.1)),
    ], obstacle_clearance=0.03)
    parsed = parse(req)
    sphere, capsule, box = parsed.goal.obstacles
    assert parsed.clearance == 0.03
    assert sphere.inflation == pytest.approx(0.03 + CONFIG.obstacle_margin)
    assert np.allclose(capsule.center, [0.0, 0.0, 0.10])
    assert np.allclose(sorted([capsule.a[2], capsule.b[2]]), [0.0, 0.2])
    assert box.surface_distance([-0.2, 0.35, 0.10]) == pytest.approx(0.05)
    assert parse(request(obstacles=[obstacle()])).clearance == CONFIG.obstacle_clearance


def test_force_torque_limits_trunk_freeze_and_scales():
    """Forces, torque limits, trunk modes, frozen joints and admittance factors reach the goal."""
    req = request(use_torso=True, trunk_admittance="compliant", frozen_joints=["r_wrist_prosup"],
                  torque_limit_joints=["r_elbow"], torque_limits=[0.5],
                  admittance_scale_joints=["r_shoulder_yaw"], admittance_scales=[2.0])
    set_xyz(req.right_force, (0.0, 0.0, -10.0))
    parsed = parse(req)
    g = parsed.goal
    assert np.allclose(g.target_forces["right"], [0, 0, -10]) and parsed.report_torques
    assert dict(g.torque_limits) == {"r_elbow": 0.5}
    assert g.trunk_admittance_scale == CONFIG.trunk_compliant_scale
    assert g.frozen_joints == ("r_wrist_prosup",)
    assert dict(g.admittance_scales) == {"r_shoulder_yaw": 2.0}
    assert parse(request(use_torso=True, trunk_admittance="stiff")).goal \
        .trunk_admittance_scale == 0.0
    assert parse(request(use_torso=True, trunk_admittance="stiff",
                         trunk_admittance_scale=0.5)).goal.trunk_admittance_scale == 0.5


def _bad_requests() -> dict[str, tuple[object, str]]:
    """name -> (request, text its rejection must contain)."""
    nan, inf = math.nan, math.inf
    bad: dict[str, tuple[object, str]] = {}
    # held object
    bad["held one hand"] = (request(hands=("right",), hold_object=True), "hold_object")
    r = held()
    r.object_goal.pose.position.x = nan
    bad["held goal NaN"] = (r, "object_goal.pose.position")
    r = held()
    r.object_pose.pose.position.y = inf
    bad["held pose inf"] = (r, "object_pose.pose.position")
    r = held()
    r.object_goal.header.frame_id = "no_such_frame"
    bad["held goal frame"] = (r, "object_goal.header.frame_id")
    r = held()
    r.object_goal.pose.orientation.w, r.object_goal.pose.orientation.z = 0.0, 1.0
    bad["held rotation"] = (r, "object_goal.pose.orientation")
    r = held()
    r.object_goal.pose.orientation.w = 0.0
    bad["held zero quaternion"] = (r, "zero quaternion")
    r = held()
    set_xyz(r.left_grasp, (0.0, 0.1, 0.0))
    set_xyz(r.right_grasp, (0.0, 0.1, 0.0))
    bad["grasps coincide"] = (r, "left_grasp/right_grasp")
    r = held()
    r.right_grasp.z = nan
    bad["grasp NaN"] = (r, "right_grasp")
    r = held()
    r.right_force.z = -5.0
    bad["force with object"] = (r, "right_force")
    # obstacles
    bad["obstacle type"] = (request(obstacles=[obstacle("cone")]), "obstacles[0].type")
    bad["obstacle NaN"] = (request(obstacles=[obstacle(centre=(nan, 0, 0))]),
                           "obstacles[0].pose.position")
    bad["obstacle frame"] = (request(obstacles=[obstacle(frame="nowhere")]),
                             "obstacles[0].header.frame_id")
    bad["negative radius"] = (request(obstacles=[obstacle(radius=-0.1)]), "obstacles[0].radius")
    bad["zero radius"] = (request(obstacles=[obstacle(radius=0.0)]), "obstacles[0].radius")
    bad["capsule length"] = (request(obstacles=[obstacle("capsule", length=-1.0)]),
                             "obstacles[0].length")
    bad["box size"] = (request(obstacles=[obstacle(), obstacle("box", size=(0.1, -0.1, 0.1))]),
                       "obstacles[1].size")
    ob = obstacle("box", size=(0.1, 0.1, 0.1))
    ob.pose.orientation.w = 0.0
    bad["box quaternion"] = (request(obstacles=[ob]), "obstacles[0].pose")
    bad["encloses target"] = (request(obstacles=[obstacle(centre=(-0.25, 0.10, 0.20))]),
                              "encloses the right hand's target")
    bad["within clearance"] = (request(obstacles=[obstacle(centre=(-0.25, 0.10, 0.25))],
                                       obstacle_clearance=0.05), "obstacles[0]")
    bad["starts inside"] = (request(obstacles=[obstacle(centre=(-0.30, 0.20, 0.03))]),
                            "right hand starts")
    bad["clearance"] = (request(obstacles=[obstacle()], obstacle_clearance=-0.01),
                        "obstacle_clearance")
    bad["clearance NaN"] = (request(obstacle_clearance=nan), "obstacle_clearance")
    # forces and torque limits
    r = request()
    r.right_force.x = nan
    bad["force NaN"] = (r, "right_force")
    r = request()
    r.left_force.z = -10.0
    bad["force other hand"] = (r, "left_force")
    bad["limits lengths"] = (request(torque_limit_joints=["r_elbow", "r_wrist_pitch"],
                                     torque_limits=[1.0]), "wrong lengths")
    bad["limit unknown"] = (request(torque_limit_joints=["r_elbo"], torque_limits=[1.0]),
                            "torque_limit_joints")
    bad["limit negative"] = (request(torque_limit_joints=["r_elbow"], torque_limits=[-1.0]),
                             "torque_limits")
    bad["limit NaN"] = (request(torque_limit_joints=["r_elbow"], torque_limits=[nan]),
                        "torque_limits")
    bad["limit twice"] = (request(torque_limit_joints=["r_elbow", "r_elbow"],
                                  torque_limits=[1.0, 2.0]), "named twice")
    # admittances
    bad["trunk mode"] = (request(use_torso=True, trunk_admittance="floppy"), "trunk_admittance")
    bad["trunk no torso"] = (request(trunk_admittance="stiff"), "use_torso")
    bad["trunk scale"] = (request(use_torso=True, trunk_admittance_scale=-1.0),
                          "trunk_admittance_scale")
    bad["trunk scale NaN"] = (request(use_torso=True, trunk_admittance_scale=nan),
                              "trunk_admittance_scale")
    bad["freeze unknown"] = (request(frozen_joints=["r_wrist_twist"]), "frozen_joints")
    bad["scale lengths"] = (request(admittance_scale_joints=["r_elbow"], admittance_scales=[]),
                            "wrong lengths")
    bad["scale negative"] = (request(admittance_scale_joints=["r_elbow"],
                                     admittance_scales=[-2.0]), "admittance_scales")
    bad["scale unknown"] = (request(admittance_scale_joints=["elbow"], admittance_scales=[1.0]),
                            "admittance_scale_joints")
    return bad


BAD = _bad_requests()


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_input_is_rejected_with_a_message_naming_the_field(name):
    """Each bad field: InvalidInput (never another exception), one line naming the field."""
    req, needle = BAD[name]
    with pytest.raises(InvalidInput) as err:
        parse(req)
    text = str(err.value)
    assert needle in text, text
    assert "\n" not in text and len(text) < 600


def test_unknown_names_list_the_valid_choices():
    """An unknown joint's message gives the closest valid names."""
    with pytest.raises(InvalidInput, match="r_elbow"):
        parse(request(frozen_joints=["r_elbo"]))
