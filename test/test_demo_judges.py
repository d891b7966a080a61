"""The demo's transport, obstacle and press phases are judged on measured figures: each judge
fails when its figure is out of its bound and passes within it."""

from __future__ import annotations

import numpy as np

from icub_pmp.demo.scenario import (
    OBSTACLE_ARRIVAL_TOLERANCE,
    PRESS_FORCE_TOLERANCE,
    TRANSPORT_DISTANCE_TOLERANCE,
    judge_obstacle_reach,
    judge_press,
    judge_transport,
)


def test_transport_fails_on_a_change_during_the_motion_not_only_at_its_end():
    """A hand-to-hand distance that wanders 6 mm in the middle of the transport and comes back
    fails, though its end equals its start; one within 3 mm passes; a box lifted 2 cm fails;
    no samples fail with a message instead of a crash."""
    d0 = 0.2297
    wander = d0 + np.r_[np.zeros(10), np.linspace(0.0, -0.006, 20), np.linspace(-0.006, 0, 20)]
    ok, msg, fig = judge_transport(wander, 0.08)
    assert not ok and "changed by 6.0 mm" in msg
    assert abs(fig["hand_distance_change_max_m"] - 0.006) < 1e-9
    assert abs(fig["hand_distance_change_end_m"]) < 1e-12
    ok, msg, fig = judge_transport(d0 + np.linspace(0.0, 0.003, 50), 0.08)
    assert ok and TRANSPORT_DISTANCE_TOLERANCE == 0.005, msg
    ok, msg, _ = judge_transport(d0 + np.zeros(50), 0.02)
    assert not ok and "lifted only 2.0 cm" in msg
    ok, msg, _ = judge_transport(np.array([d0]), 0.08)
    assert not ok and "too few" in msg


def test_obstacle_reach_fails_on_contact_a_moved_obstacle_or_a_missed_target():
    """Any link touching the obstacle fails the reach, however well the hand arrives; so does
    an obstacle moved 3 mm or a hand 1.5 cm from its target; 5 mm off, untouched, passes."""
    target = np.array([-0.44, 0.15, 0.07])
    ok, msg, fig = judge_obstacle_reach(target, target, ["r_forearm", "r_forearm"], 0.0)
    assert not ok and "touched the obstacle with ['r_forearm']" in msg
    assert fig["obstacle_contact_links"] == 1.0
    ok, msg, _ = judge_obstacle_reach(target, target, [], 0.003)
    assert not ok and "moved by 3.0 mm" in msg
    ok, msg, _ = judge_obstacle_reach(target + [0.015, 0.0, 0.0], target, [], 0.0)
    assert not ok and "1.5 cm from the target" in msg
    ok, msg, _ = judge_obstacle_reach(target + [0.0, 0.005, 0.0], target, [], 0.0001)
    assert ok and OBSTACLE_ARRIVAL_TOLERANCE == 0.01, msg


def test_press_is_judged_on_the_estimate_against_the_target_force():
    """The estimator reports the world's force on the hand (+z when the hand pushes down):
    8.36 N against a 10 N target is 16 % off and fails, 9.5 N passes, a force of the wrong sign
    fails; the simulator's contact force is reported, not judged."""
    target = np.array([0.0, 0.0, -10.0])
    ok, msg, fig = judge_press(np.array([-0.05, -0.43, 8.36]), target, np.array([0, 0, 10.0]))
    assert not ok and "off the target" in msg
    assert abs(fig["estimated_force_N"] - 8.36) < 1e-9
    assert abs(fig["ground_truth_force_N"] - 10.0) < 1e-9
    ok, msg, fig = judge_press(np.array([0.0, -0.4, 9.5]), target, np.array([0, 0, 2.0]))
    assert ok and PRESS_FORCE_TOLERANCE == 0.10, msg
    assert fig["ground_truth_force_error_rel"] > 0.5
    ok, msg, _ = judge_press(np.array([0.0, 0.0, -10.0]), target, None)
    assert not ok
    ok, msg, _ = judge_press(np.array([0.0, 0.0, 10.0]), np.zeros(3), None)
    assert not ok and "no valid target force" in msg
