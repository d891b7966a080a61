"""The demo's vision reach is judged against the object's ground truth, not the estimate."""

from __future__ import annotations

import numpy as np

from icub_pmp.demo.scenario import VISION_ARRIVAL_TOLERANCE, cylinder_height, judge_vision_reach
from icub_pmp.pmp.pre_grasp import PreGrasp

CYL = np.array([-0.38, 0.05, -0.03])


def _goal(clearance: float = 0.06) -> np.ndarray:
    return CYL + [0.0, 0.0, 0.5 * cylinder_height() + clearance]


def test_judge_fails_when_the_hand_ends_5cm_from_the_object():
    """A hand 5 cm from the point above the cylinder's true top fails the phase (as a stereo
    estimate biased by 5 cm would make it end), however close the hand is to the estimate;
    within 1.5 cm it passes; a 2 cm estimate error or a pushed object fail too."""
    for bias in ([0.05, 0.0, 0.0], [0.0, 0.05, 0.0], [0.0, 0.0, 0.05]):
        ok, msg, fig = judge_vision_reach(_goal() + bias, CYL, cylinder_height(), 0.06,
                                          0.004, 0.0)
        assert not ok and "5.0 cm from the point above" in msg
        assert abs(fig["arrival_vs_object_m"] - 0.05) < 1e-9
    ok, msg, _ = judge_vision_reach(_goal() + [0.0, 0.015, 0.0], CYL, cylinder_height(), 0.06,
                                    0.004, 0.0)
    assert ok and VISION_ARRIVAL_TOLERANCE == 0.02, msg
    ok, msg, _ = judge_vision_reach(_goal(), CYL, cylinder_height(), 0.06, 0.02, 0.0)
    assert not ok and "stereo estimate" in msg
    ok, msg, _ = judge_vision_reach(_goal(), CYL, cylinder_height(), 0.06, 0.004, 0.03)
    assert not ok and "pushed" in msg


def test_pre_grasp_goes_over_the_object_not_through_it():
    """From beside and below the top the hand goes through a via point above the goal; from
    beside and above the goal too (the fingers hang 4-8 cm below the hand frame: arriving from
    the side at the goal's height they knocked the cylinder over in the vision bench), and it
    descends from there; from over the object it goes straight down; the goal is 6 cm above
    the top."""
    pre = PreGrasp()
    top = CYL + [0.0, 0.0, 0.06]
    low = pre.waypoints(CYL + [0.12, 0.0, 0.0], top, 0.03, 0.12)
    assert len(low) == 2 and low[0][2] >= low[1][2] + 0.079
    assert np.allclose(low[-1], top + [0.0, 0.0, 0.06])
    for hand in (top + [0.0, 0.2, 0.12], top + [0.14, 0.23, 0.06]):  # beside, above the goal
        high = pre.waypoints(hand, top, 0.03, 0.12)
        assert len(high) == 2 and np.allclose(high[0][:2], top[:2])
        assert high[0][2] >= max(hand[2], high[1][2] + 0.079) - 1e-9
    over = pre.waypoints(top + [0.01, 0.0, 0.15], top, 0.03, 0.12)
    assert len(over) == 1 and np.allclose(over[0], top + [0.0, 0.0, 0.06])


def _visual_target(t: float, state: str, x: float, points: int = 2000) -> object:
    from icub_interfaces.msg import VisualTarget

    m = VisualTarget()
    m.header.stamp.sec, m.header.stamp.nanosec = int(t), int(round((t - int(t)) * 1e9))
    m.state, m.points = state, points
    m.position.x, m.position.y, m.position.z = x, 0.05, -0.03
    return m


def test_the_reach_goal_waits_for_the_still_target_to_settle():
    """The goal is the first still estimate after the stop that agrees within 3 mm with the
    still estimate before it: after the bench's fastest motion the first still estimates lagged
    15 and 9 mm behind the stopped cylinder (a reach there missed it by 1.5 cm), the next ones
    were 2 mm off; estimates before the stop, moving or not measured do not count."""
    from icub_pmp.demo.scenario import settled_still_estimate

    x = -0.38
    seq = [_visual_target(0.90, "still", x), _visual_target(0.95, "still", x),  # before
           _visual_target(1.00, "moving", x + 0.020), _visual_target(1.03, "still", x + 0.015),
           _visual_target(1.07, "held", x + 0.015, points=0),
           _visual_target(1.10, "still", x + 0.009), _visual_target(1.13, "still", x + 0.002),
           _visual_target(1.17, "still", x + 0.0015), _visual_target(1.20, "still", x + 0.001)]
    m = settled_still_estimate(seq, after=0.96)
    assert m is seq[7], (m.header.stamp, m.position.x)
    assert settled_still_estimate(seq[:7], after=0.96) is None
    # a moving estimate in between starts the count again
    seq2 = [_visual_target(1.0, "still", x), _visual_target(1.03, "moving", x),
            _visual_target(1.07, "still", x)]
    assert settled_still_estimate(seq2, after=0.96) is None


def test_a_still_pair_of_partial_measurements_is_not_the_goal():
    """A bench trial (seed 23, trial 11): right after the stop two still estimates of 226 and
    264 points agreed within 3 mm but were 33 mm off the cylinder (a part of it), where the
    moving cylinder had given 2,672 points; the goal is the next settled pair of whole
    measurements (3,396 and 3,928 points, 4-5 mm off)."""
    from icub_pmp.demo.scenario import settled_still_estimate

    x = -0.40
    seq = [_visual_target(0.30, "moving", x, 2672), _visual_target(1.05, "moving", x, 607),
           _visual_target(1.12, "moving", x + 0.035, 241),
           _visual_target(1.18, "still", x + 0.033, 226),
           _visual_target(1.22, "still", x + 0.034, 264),
           _visual_target(1.42, "moving", x + 0.011, 3025),
           _visual_target(1.46, "still", x + 0.005, 3396),
           _visual_target(1.49, "still", x + 0.004, 3928)]
    m = settled_still_estimate(seq, after=1.10)
    assert m is seq[7], (m.header.stamp, m.points)
    # with every measurement whole, the first still pair is the goal
    assert settled_still_estimate(seq[3:], after=1.10) is seq[4]


def test_a_missed_still_target_says_what_the_estimates_were():
    """No settled still target: the failure names what came after the stop (per state), the
    still ones' points against the partial bound, and where the last estimate was (a held
    target the region search lost), so a failed run can be read without a bag."""
    from icub_pmp.demo.scenario import estimates_summary

    x = -0.33
    seq = [_visual_target(0.90, "moving", x, 2000), _visual_target(1.05, "held", x, points=0),
           _visual_target(1.10, "still", x + 0.01, 500), _visual_target(1.15, "held", x, 0)]
    text = estimates_summary(seq, after=1.0)
    assert text.startswith("2 held, 1 still"), text
    assert "still points 500-500 (most of any estimate 2000, partial below 600)" in text
    assert "the last (held" in text and "[-0.33, 0.05, -0.03]" in text
    assert estimates_summary(seq, after=2.0) == "no estimate stamped after it"


def test_reaching_arm_is_the_one_on_the_objects_side() -> None:
    """An object left of the midline is reached with the left hand (a right hand reaching
    across the body passed over the resting left one and ended 2.1 cm off, seed 29 trial 19)."""
    from icub_pmp.demo.scenario import reaching_arm

    assert reaching_arm(np.array([-0.34, -0.13, -0.02])) == "left"
    assert reaching_arm(np.array([-0.34, 0.10, -0.02])) == "right"
    assert reaching_arm(np.array([-0.34, 0.0, -0.02])) == "right"
