"""The controller closed with the MuJoCo simulator and the wrench estimator in-process, in
lockstep at 1 kHz (SimLoop): hold against gravity, joint stiffness, trajectory tracking and
the velocity mode, measured on the simulated robot."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.control.impedance_controller_config import ImpedanceControllerConfig
from icub_sim_bridge.harness.sim_loop import SimLoop
from icub_sim_bridge.harness.sim_scenarios import track_min_jerk
from icub_sim_bridge.simulator import Simulator


def _loop(sim: Simulator, **kw) -> SimLoop:
    sim.reset("rest")
    return SimLoop(ImpedanceControllerConfig(**kw), sim=sim)


def test_holds_posture_against_gravity(sim):
    """Compliant impedance mode with gravity compensation and the torque loop closed on the
    estimated torques holds the rest posture within 0.5 deg on every joint for 2 s."""
    loop = _loop(sim, mode="impedance")
    q0 = sim.joint_state().position.copy()
    steps = loop.run(2.0)
    err = np.degrees(np.abs(np.array([s.q for s in steps]) - q0))
    assert err.max() < 0.5
    assert steps[-1].control.status == "ok"


def test_measured_stiffness_matches_configured_k(sim):
    """A 6 N force on the left hand deflects each loaded joint by tau_ext / K: the measured
    stiffness tau_ext / dq is within 10 % of the configured K (joints with |tau_ext| >
    0.1 N m), tau_ext = J^T F at the deflected posture."""
    loop = _loop(sim, mode="impedance")
    loop.run(0.1)
    q0 = sim.joint_state().position.copy()
    force = np.array([2.0, 3.0, 5.0])
    sim.apply_wrench("l_hand_dh_frame", force, np.zeros(3), 5.0)
    s = loop.run(2.5)[-1]
    c = loop.controller
    qm = c.model.q_from_dict(dict(zip(c.joint_names, s.q)))
    jac = c.model.frame_jacobian(qm, "l_hand_dh_frame")
    tau_model = jac.T @ np.concatenate([force, np.zeros(3)])
    k = np.array(c.config.gains("impedance", "stiffness"))
    checked = 0
    for name in c.model.joint_names:
        tau = tau_model[c.model.indices([name])[0]]
        if abs(tau) > 0.1:
            j = c.indices([name])[0]
            k_meas = tau / (s.q[j] - q0[j])
            assert k_meas == pytest.approx(k[j], rel=0.10), name
            checked += 1
    assert checked >= 6


def test_tracks_a_minimum_jerk_trajectory(sim):
    """A 2 s minimum-jerk joint trajectory (torso yaw, right arm, left elbow; 40 points with
    velocities, as a planner sends) is tracked in position mode with inverse-dynamics
    feed-forward: RMS error < 1 deg during the motion, final error < 0.5 deg 0.3 s after."""
    loop = _loop(sim, mode="position", feedforward="inverse_dynamics")
    loop.run(0.05)
    r = track_min_jerk(loop)
    assert r.rms_deg < 1.0
    assert r.final_deg < 0.5
    assert r.saturated_steps == 0


def test_velocity_mode_moves_at_the_commanded_rate(sim):
    """Velocity mode (eq 7): 0.3 rad/s on r_elbow for 0.5 s moves it 0.15 rad (within
    0.01 rad), then it holds."""
    loop = _loop(sim, mode="position", velocity_command_timeout=0.5)
    loop.run(0.05)
    c = loop.controller
    j = c.indices(["r_elbow"])[0]
    q0 = sim.joint_state().position[j]
    c.set_velocity_command(["r_elbow"], [0.3], loop.t)
    loop.run(0.8)
    assert sim.joint_state().position[j] - q0 == pytest.approx(0.15, abs=0.01)
