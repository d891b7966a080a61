"""The wrench estimator on the simulated iCub (MuJoCo, in-process lockstep with the
controller): FT prediction during contact-free motion (the paper's Table 1 experiment),
external hand wrenches vs the simulator's ground truth, contact flags."""

from __future__ import annotations

import numpy as np

from icub_pmp.control.impedance_controller_config import ImpedanceControllerConfig
from icub_sim_bridge.harness.sim_loop import SimLoop
from icub_sim_bridge.harness.sim_scenarios import (
    press_left_hand_on_table,
    raised_posture,
    start_periodic_motion,
)

HANDS = ("left", "right")


def _force_ok(est: np.ndarray, truth: np.ndarray) -> bool:
    """Within 5 % of the true force or 0.1 N, whichever is larger."""
    return bool(np.linalg.norm(est - truth) <= max(0.05 * np.linalg.norm(truth), 0.1))


def test_ft_prediction_during_contact_free_motion(sim):
    """Table 1 analogue: both arms move periodically (10 joints, 0.37-0.71 Hz, 10-20 deg) with
    no contact; the FT wrench predicted by RNEA with null hand wrenches matches the measured
    one: |mean error| < 0.02 N / 0.005 N m and std < 0.15 N / 0.05 N m per axis (measured
    here: std <= 0.06 N and 0.025 N m), and no contact is flagged."""
    sim.reset(q=raised_posture(sim.spec))
    loop = SimLoop(ImpedanceControllerConfig(mode="position", feedforward="inverse_dynamics"),
                   sim=sim)
    loop.run(0.02)
    t0 = start_periodic_motion(loop, 3.0)
    steps = loop.run(3.0)
    window = [s for s in steps if 1.2 <= s.t - t0 <= 3.0]
    for h in HANDS:
        err = np.array([s.estimate.ft_measured[h] - s.estimate.ft_predicted[h] for s in window])
        assert np.all(np.abs(err.mean(0)) < [0.02] * 3 + [0.005] * 3), h
        assert np.all(err.std(0) < [0.15] * 3 + [0.05] * 3), h
        moving = np.array([s.estimate.ft_measured[h] for s in window]).std(0)
        assert moving[:3].max() > 0.5  # the arms really moved the sensor readings
    assert not any(s.estimate.contact[h] for s in steps for h in HANDS)


def test_applied_force_estimated_within_5_percent(sim):
    """A 4 N scripted force (root_link (1, -2, 3) direction) on the right hand: the estimated
    external wrench (eq 2, root_link, about the hand origin) matches the ground truth within
    5 % (or 0.1 N) over the last 0.5 s; the contact flag is on for the right hand only, and
    off again 0.2 s after the force ends."""
    sim.reset("rest")
    loop = SimLoop(ImpedanceControllerConfig(mode="impedance"), sim=sim)
    loop.run(0.1)
    f = 4.0 * np.array([1.0, -2.0, 3.0]) / np.linalg.norm([1.0, -2.0, 3.0])
    sim.apply_wrench("r_hand_dh_frame", f, np.zeros(3), 1.5)
    steps = loop.run(1.5)
    for s in steps[-500:]:
        assert _force_ok(s.estimate.ext_root["right"][:3], s.ground_truth["right"][:3])
        np.testing.assert_allclose(s.ground_truth["right"][:3], f, atol=1e-6)
        assert s.estimate.contact["right"] and not s.estimate.contact["left"]
    after = loop.run(0.2)
    assert not after[-1].estimate.contact["right"]
    assert np.linalg.norm(after[-1].estimate.ext_root["right"][:3]) < 0.1


def test_hand_pressing_on_the_table(sim):
    """The left hand is driven down onto the table (compliant impedance mode, set-point
    below the surface): once it presses steadily, the estimated contact force matches the
    simulator's contact ground truth within 5 % (or 0.1 N) and the contact flag is on."""
    sim.reset("rest")
    loop = SimLoop(ImpedanceControllerConfig(mode="impedance"), sim=sim)
    loop.run(0.05)
    press_left_hand_on_table(loop)
    steps = loop.run(2.0)
    pressed = [s for s in steps[-300:]]
    gt = np.array([s.ground_truth["left"][:3] for s in pressed])
    assert gt[:, 2].min() > 1.0  # the table pushes the hand up by more than 1 N
    for s in pressed:
        assert _force_ok(s.estimate.ext_root["left"][:3], s.ground_truth["left"][:3])
        assert s.estimate.contact["left"]


def test_gravity_from_the_simulated_imu(sim):
    """gravity_source='imu': the head IMU of the simulator (proper acceleration, 3 Hz
    low-pass) gives root_link gravity within 0.01 m/s^2 of (0, 0, -9.81) at rest, and the
    hand-wrench estimate still matches the ground truth within 5 % (or 0.1 N)."""
    from icub_pmp.dynamics.wrench_estimator_config import WrenchEstimatorConfig

    sim.reset("rest")
    loop = SimLoop(ImpedanceControllerConfig(mode="impedance"),
                   WrenchEstimatorConfig(gravity_source="imu"), sim=sim)
    loop.run(0.5)
    np.testing.assert_allclose(loop.estimator.model.gravity, [0.0, 0.0, -9.81], atol=0.01)
    sim.apply_wrench("l_hand_dh_frame", np.array([0.0, -2.0, 3.0]), np.zeros(3), 1.5)
    s = loop.run(1.2)[-1]
    assert _force_ok(s.estimate.ext_root["left"][:3], s.ground_truth["left"][:3])
