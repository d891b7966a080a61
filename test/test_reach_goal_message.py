"""reach_goal_message: the Reach goal the demo, benchmarks and tests send."""

import pytest

from icub_pmp.ros.reach_goal_message import reach_goal_message


def test_each_hand_gets_its_own_target_in_the_frame():
    g = reach_goal_message({"right": [-0.3, 0.15, 0.05], "left": (-0.31, -0.16, 0.06)}, 1.5,
                           use_torso=True, frozen_joints=["r_wrist_prosup"])
    assert list(g.hands) == ["left", "right"]
    assert (g.right_target.pose.position.x, g.right_target.pose.position.y) == (-0.3, 0.15)
    assert g.left_target.pose.position.z == pytest.approx(0.06)
    assert g.left_target.header.frame_id == g.right_target.header.frame_id == "root_link"
    assert g.tau == 1.5 and g.use_torso and list(g.frozen_joints) == ["r_wrist_prosup"]


def test_one_hand_leaves_the_other_target_empty():
    g = reach_goal_message({"left": [-0.3, -0.15, 0.05]})
    assert list(g.hands) == ["left"]
    assert g.right_target.header.frame_id == ""


def test_an_unknown_hand_is_refused():
    with pytest.raises(ValueError, match="unknown hand"):
        reach_goal_message({"middle": [0.0, 0.0, 0.0]})
