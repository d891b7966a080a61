"""ImpedanceController core: eq 6 and the modes, the torque PID (eqs 4-5), saturation, the
joint-limit guard, the watchdogs and input rejection (no simulator: exact known answers)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from icub_pmp.control.impedance_controller import ImpedanceController
from icub_pmp.control.impedance_controller_config import ImpedanceControllerConfig
from icub_pmp.control.torque_pid import TorquePid
from icub_pmp.errors import ConfigError, InvalidInput, UnknownName


@pytest.fixture(scope="module")
def base() -> ImpedanceController:
    return ImpedanceController()


def _ctl(base: ImpedanceController, **kw) -> ImpedanceController:
    return ImpedanceController(ImpedanceControllerConfig(**kw), base.spec, base.model)


def _rest(c: ImpedanceController) -> np.ndarray:
    p = c.spec.posture("rest")
    return np.array([p[j] for j in c.joint_names])


def _gravity(c: ImpedanceController, q: np.ndarray) -> np.ndarray:
    qm = c.model.q_from_dict(dict(zip(c.joint_names, q)))
    g = c.model.gravity_torques(qm)
    out = np.zeros(c.n)
    for j, name in enumerate(c.joint_names):
        if name in c.model.joint_names:
            out[j] = g[c.model.indices([name])[0]]
    return out


def test_first_step_holds_the_measured_posture_with_gravity_compensation(base):
    """At the first joint state the set-point latches it: the command is g(q) alone."""
    c = _ctl(base)
    q = _rest(c)
    out = c.step(0.0, q, np.zeros(c.n))
    np.testing.assert_allclose(out.setpoint.q, q)
    np.testing.assert_allclose(out.tau, _gravity(c, q), atol=1e-12)
    assert out.status == "no_estimate"


@pytest.mark.parametrize("mode", ["position", "impedance"])
def test_eq6_restoring_torque(base, mode):
    """tau_d = -K (q - q_d) - D (q_dot - q_dot_d) + g(q), per joint, with the mode's gains."""
    c = _ctl(base, mode=mode)
    q0 = _rest(c)
    c.step(0.0, q0, np.zeros(c.n))
    dq = np.zeros(c.n)
    dq[c.indices(["r_elbow", "torso_yaw"])] = [0.01, -0.02]
    v = np.zeros(c.n)
    v[c.indices(["l_shoulder_roll"])] = 0.3
    out = c.step(0.001, q0 + dq, v)
    k = np.array(c.config.gains(mode, "stiffness"))
    d = np.array(c.config.gains(mode, "damping"))
    np.testing.assert_allclose(out.tau_d, -k * dq - d * v + _gravity(c, q0 + dq), atol=1e-12)


def test_torque_mode_has_no_position_feedback(base):
    """Pure torque mode: tau = g(q) + the trajectory's effort, whatever the position error."""
    c = _ctl(base, mode="torque")
    q0 = _rest(c)
    q0[c.indices(["eyes_vergence"])] = 0.2  # the rest vergence (0) is in the guard band
    c.step(0.0, q0, np.zeros(c.n))
    c.set_trajectory(c.make_trajectory(["r_elbow"], [0.0, 1.0], [[0.8], [0.8]],
                                       efforts=[[0.5], [0.5]]), 0.0)
    q = q0.copy()
    q[c.indices(["l_elbow"])] += 0.1
    out = c.step(0.5, q, np.ones(c.n) * 0.1)
    expected = _gravity(c, q)
    expected[c.indices(["r_elbow"])] += 0.5
    np.testing.assert_allclose(out.tau, expected, atol=1e-12)


def test_saturation_at_robot_spec_limits(base):
    """Commands are clipped at config/robot.yaml's torque limits and flagged saturated."""
    c = _ctl(base, mode="position")
    q0 = _rest(c)
    c.step(0.0, q0, np.zeros(c.n))
    q = q0.copy()
    j = c.indices(["r_wrist_pitch"])[0]
    q[j] -= 0.5  # 40 N m/rad * 0.5 rad = 20 N m > 5 N m limit
    out = c.step(0.001, q, np.zeros(c.n))
    assert out.tau[j] == pytest.approx(c.spec.torque_limit("r_wrist_pitch"))
    assert out.saturated[j] and out.saturated.sum() == 1


def test_torque_pid_integral_removes_a_torque_deficit():
    """With a plant whose joint torque is the command minus 1 N m of friction (one step
    late), the integral of eq 5 makes the estimated torque converge to tau_d."""
    pid = TorquePid(2, kp=0.2, ki=20.0, integral_limit=5.0)
    tau_d = np.array([2.0, -1.0])
    mask = np.array([True, True])
    tau_hat = np.zeros(2)
    for _ in range(2000):
        cmd = pid(tau_d, tau_hat, 0.001, mask)
        tau_hat = cmd - np.array([1.0, 1.0])
    np.testing.assert_allclose(tau_hat, tau_d, atol=1e-6)
    # without a valid estimate the command is tau_d itself
    np.testing.assert_allclose(pid(tau_d, tau_hat, 0.001, ~mask), tau_d)


def test_estimate_watchdog_turns_the_torque_loop_off(base):
    """An estimate older than estimate_timeout (in joint-state time) is ignored: status
    'estimate_stale' and tau = tau_d; a fresh one closes the loop ('ok')."""
    c = _ctl(base, torque_ki=50.0, estimate_timeout=0.01)
    q = _rest(c)
    names = c.model.joint_names
    c.step(0.0, q, np.zeros(c.n))
    c.set_estimate(0.0, names, np.zeros(len(names)))  # far from g(q): large error
    out = c.step(0.005, q, np.zeros(c.n))
    assert out.status == "ok"
    out = c.step(0.010, q, np.zeros(c.n))
    assert out.status == "ok" and not np.allclose(out.tau, out.tau_d)
    out = c.step(0.030, q, np.zeros(c.n))
    assert out.status == "estimate_stale"
    np.testing.assert_allclose(out.tau, out.tau_d)


def test_time_going_back_forgets_the_estimate_of_the_old_timeline(base):
    """A restarted simulator (joint states at t = 0.001 s after t = 5 s): the estimate of
    t = 5 s is forgotten (it is not 'fresh' with a negative age) and the torque loop waits
    for a new one; an estimate of the new timeline closes it again."""
    c = _ctl(base, estimate_timeout=0.01)
    q = _rest(c)
    names = c.model.joint_names
    c.step(5.0, q, np.zeros(c.n))
    c.set_estimate(5.0, names, np.zeros(len(names)))
    assert c.step(5.001, q, np.zeros(c.n)).status == "ok"
    out = c.step(0.001, q, np.zeros(c.n))
    assert out.status == "no_estimate" and c.estimate_age(0.001) == -1.0
    c.set_estimate(0.001, names, np.zeros(len(names)))
    assert c.step(0.002, q, np.zeros(c.n)).status == "ok"


def test_joint_state_watchdog_trips_to_a_safe_hold(base):
    """No joint state for state_timeout: check_watchdog trips once, aborts the trajectory,
    refuses new ones; the next joint state resumes with a hold at that posture."""
    c = _ctl(base, state_timeout=0.1)
    q = _rest(c)
    c.step(0.0, q, np.zeros(c.n))
    c.set_trajectory(c.make_trajectory(["r_elbow"], [1.0], [[1.2]]), 0.0)
    c.step(0.001, q, np.zeros(c.n))
    assert not c.check_watchdog(0.05)
    assert c.check_watchdog(0.2) and c.safe_hold
    assert not c.check_watchdog(0.3)  # trips once
    with pytest.raises(InvalidInput, match="safe hold"):
        c.set_trajectory(c.make_trajectory(["r_elbow"], [1.0], [[1.2]]), 0.3)
    q2 = q.copy()
    q2[c.indices(["r_elbow"])] += 0.05
    out = c.step(0.4, q2, np.zeros(c.n))
    assert not c.safe_hold and c.setpoints.active_trajectories == 0
    np.testing.assert_allclose(out.setpoint.q, q2)


def test_joint_limit_guard_pushes_back(base):
    """In torque mode a joint inside the guard band gets a restoring spring; in impedance
    mode a set-point at the limit is not fought."""
    c = _ctl(base, mode="torque", joint_limit_margin=0.05, joint_limit_stiffness=50.0)
    q = _rest(c)
    j = c.indices(["r_elbow"])[0]
    q[j] = c.upper[j] - 0.01
    out = c.step(0.0, q, np.zeros(c.n))
    assert out.limit_guard[j]
    assert out.tau[j] - _gravity(c, q)[j] == pytest.approx(50.0 * (-0.04))
    d = _ctl(base, mode="impedance", joint_limit_margin=0.05)
    out = d.step(0.0, q, np.zeros(c.n))  # the set-point latches q itself
    assert not out.limit_guard[j]


def test_bad_inputs_rejected_and_nothing_changes(base):
    """NaN joint states, unknown joints in estimates, trajectories and velocity commands are
    rejected with a clear error; the controller keeps running unchanged."""
    c = _ctl(base)
    q = _rest(c)
    first = c.step(0.0, q, np.zeros(c.n))
    bad = q.copy()
    bad[2] = np.nan
    with pytest.raises(InvalidInput, match="NaN"):
        c.step(0.001, bad, np.zeros(c.n))
    with pytest.raises(InvalidInput, match="shape"):
        c.step(0.001, q[:5], np.zeros(5))
    with pytest.raises(UnknownName, match="r_knee"):
        c.set_estimate(0.0, ["r_knee"], [1.0])
    with pytest.raises(UnknownName, match="r_knee"):
        c.make_trajectory(["r_knee"], [1.0], [[0.0]])
    with pytest.raises(InvalidInput, match="strictly increasing"):
        c.make_trajectory(["r_elbow"], [1.0, 0.5], [[0.5], [0.6]])
    with pytest.raises(InvalidInput, match="NaN"):
        c.make_trajectory(["r_elbow"], [1.0], [[np.nan]])
    with pytest.raises(InvalidInput, match="upper limit"):
        c.make_trajectory(["r_elbow"], [1.0], [[3.0]])
    with pytest.raises(UnknownName):
        c.set_velocity_command(["nope"], [0.1], 0.0)
    out = c.step(0.001, q, np.zeros(c.n))
    np.testing.assert_allclose(out.tau, first.tau, atol=1e-12)


def test_runtime_config_change_keeps_the_setpoint(base):
    """Switching mode at run time keeps the set-point and resets the torque integral."""
    c = _ctl(base, mode="impedance")
    q = _rest(c)
    c.step(0.0, q, np.zeros(c.n))
    c.set_config(dataclasses.replace(c.config, mode="position"))
    dq = np.zeros(c.n)
    dq[c.indices(["r_shoulder_pitch"])] = 0.01
    out = c.step(0.001, q + dq, np.zeros(c.n))
    j = c.indices(["r_shoulder_pitch"])[0]
    k = c.config.position_stiffness_arm[0]
    assert out.tau_d[j] - _gravity(c, q + dq)[j] == pytest.approx(-k * 0.01)


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"mode": "admittance"}, "mode"),
        ({"feedforward": "magic"}, "feedforward"),
        ({"position_stiffness_arm": (1.0, 2.0)}, "position_stiffness_arm"),
        ({"impedance_damping_torso": (1.0, -1.0, 1.0)}, "impedance_damping_torso"),
        ({"torque_ki": -1.0}, "torque_ki"),
        ({"torque_limit_scale": 1.5}, "torque_limit_scale"),
        ({"state_timeout": 0.0}, "state_timeout"),
    ],
)
def test_config_validation(kw, match):
    """Each invalid configuration value is rejected by name."""
    with pytest.raises(ConfigError, match=match):
        ImpedanceControllerConfig(**kw)
