"""Trajectory execution on the controller core: joint rate limits (config/robot.yaml), goals
(FollowJointTrajectory semantics: success, preemption, tolerances, safe hold, cancel) and the
safe holds of the watchdogs (no simulator: the joints are fed back as the set-point says, or
held away from it)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from icub_pmp.control.impedance_controller import ImpedanceController
from icub_pmp.control.impedance_controller_config import ImpedanceControllerConfig
from icub_pmp.control.joint_trajectory import JointTrajectory
from icub_pmp.control.trajectory_goal import GoalCode
from icub_pmp.control.trajectory_limits import JointRateLimits, scale_trajectory_time
from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.robot_spec import RobotSpec


@pytest.fixture(scope="module")
def base() -> ImpedanceController:
    return ImpedanceController()


def _ctl(base: ImpedanceController, **kw) -> ImpedanceController:
    return ImpedanceController(ImpedanceControllerConfig(**kw), base.spec, base.model)


def _rest(c: ImpedanceController) -> np.ndarray:
    p = c.spec.posture("rest")
    return np.array([p[j] for j in c.joint_names])


def _traj(c: ImpedanceController, joint: str, target: float, duration: float
          ) -> JointTrajectory:
    return c.make_trajectory([joint], [duration], np.array([[target]]))


def _run(c: ImpedanceController, t0: float, t1: float, follow: bool = True,
         offset: dict[int, float] | None = None, dt: float = 0.001) -> float:
    """Step from t0 to t1; the joints track the set-point exactly (``follow``) plus
    ``offset`` {joint index: rad}."""
    q = c.setpoints.q.copy()
    t = t0
    while t < t1 - 1e-12:
        t += dt
        if follow:
            q = c.setpoints.q.copy()
        for k, d in (offset or {}).items():
            q[k] = c.setpoints.q[k] + d
        c.step(t, q, np.zeros(c.n))
    return t


def test_robot_spec_rate_limits_are_the_cited_values():
    """config/robot.yaml: 100 deg/s (icub-models jntVelMax) and 2000 deg/s^2 on the torso, arms
    and neck; 1000 deg/s (the real iCub's head boards) and 20000 deg/s^2 on the eyes."""
    spec = RobotSpec.load()
    for j in spec.actuated_joints:
        eye = j in spec.eye_joints
        assert spec.velocity_limit(j) == pytest.approx(math.radians(1000.0 if eye else 100.0))
        assert spec.acceleration_limit(j) == pytest.approx(
            math.radians(20000.0 if eye else 2000.0))


def test_peak_rates_of_a_min_jerk_point_to_point():
    """A single point reached from rest is the minimum-jerk profile: peak speed 1.875 A/T,
    peak acceleration 5.7735 A/T^2."""
    tr = JointTrajectory(["a"], [0.0, 2.0], np.array([[0.0], [1.0]]))
    v, a = tr.peak_rates(samples_per_segment=2001)
    assert v[0] == pytest.approx(1.875 / 2.0, rel=1e-4)
    assert a[0] == pytest.approx(5.7735 / 4.0, rel=1e-3)


def test_time_scale_brings_a_fast_trajectory_within_the_limits():
    """The report's time scale, applied to the time axis, leaves every joint within its
    limits, and the worst joint sits on its limit."""
    lim = JointRateLimits(["a", "b"], [1.0, 1.0], [2.0, 2.0])
    tr = JointTrajectory(["a", "b"], [0.0, 0.3], np.array([[0.0, 0.0], [1.0, 0.2]]))
    rep = lim.report(tr)
    assert rep.time_scale > 1
    assert rep.worst[0] == "a"
    t, _, _ = scale_trajectory_time(tr.times, None, None, rep.time_scale)
    slow = JointTrajectory(["a", "b"], t, tr.positions)
    rep2 = lim.report(slow)
    assert rep2.within(1e-3)
    assert max(rep2.velocity_ratio.max(), math.sqrt(rep2.acceleration_ratio.max())) == \
        pytest.approx(1.0, rel=1e-2)
    with pytest.raises(InvalidInput, match="factor >= 1"):
        scale_trajectory_time(tr.times, None, None, 0.5)


def test_controller_refuses_a_trajectory_beyond_the_velocity_limit(base):
    """A 10 ms move of the elbow by 0.3 rad (far beyond 100 deg/s) is refused with a
    message naming the joint and the limit; the same move over 2 s is accepted."""
    c = _ctl(base)
    q = _rest(c)
    c.step(0.0, q, np.zeros(c.n))
    k = c.joint_names.index("r_elbow")
    with pytest.raises(InvalidInput, match=r"r_elbow.*(velocity|acceleration) limit"):
        c.set_trajectory(_traj(c, "r_elbow", q[k] + 0.3, 0.01), 0.0)
    assert c.setpoints.active_trajectories == 0
    c.set_trajectory(_traj(c, "r_elbow", q[k] + 0.3, 2.0), 0.0)
    assert c.setpoints.active_trajectories == 1


def test_goal_succeeds_when_the_joints_arrive(base):
    """A goal whose joint follows its set-point ends SUCCESSFUL just after its last point."""
    c = _ctl(base)
    q = _rest(c)
    c.step(0.0, q, np.zeros(c.n))
    k = c.joint_names.index("r_elbow")
    g = c.execute(_traj(c, "r_elbow", q[k] + 0.2, 1.0), 0.0)
    _run(c, 0.0, 0.5)
    assert not g.done and g.feedback is not None
    assert g.feedback.time_to_go == pytest.approx(0.5, abs=2e-3)
    _run(c, 0.5, 1.01)
    assert g.done and g.outcome.code == GoalCode.SUCCESSFUL
    assert abs(g.outcome.final_error[0]) < 1e-6
    assert c.goals == ()


def test_goal_tolerance_violated_when_the_joint_stays_away(base):
    """A joint held 0.1 rad from its set-point (an obstacle) ends GOAL_TOLERANCE_VIOLATED
    goal_time_tolerance after the end, naming the joint."""
    c = _ctl(base)
    q = _rest(c)
    c.step(0.0, q, np.zeros(c.n))
    k = c.joint_names.index("r_elbow")
    g = c.execute(_traj(c, "r_elbow", q[k] + 0.2, 0.5), 0.0, goal_tolerance=[0.05],
                  goal_time_tolerance=0.2)
    _run(c, 0.0, 0.65, offset={k: -0.1})
    assert not g.done
    _run(c, 0.65, 0.75, offset={k: -0.1})
    assert g.outcome.code == GoalCode.GOAL_TOLERANCE_VIOLATED
    assert "r_elbow" in g.outcome.message


def test_path_tolerance_violation_aborts_while_moving(base):
    c = _ctl(base)
    q = _rest(c)
    c.step(0.0, q, np.zeros(c.n))
    k = c.joint_names.index("r_elbow")
    g = c.execute(_traj(c, "r_elbow", q[k] + 0.2, 1.0), 0.0, path_tolerance=[0.05])
    _run(c, 0.0, 0.2, offset={k: 0.08})
    assert g.outcome.code == GoalCode.PATH_TOLERANCE_VIOLATED


def test_a_newer_trajectory_on_a_joint_preempts_the_goal(base):
    """A second goal on one of the first goal's joints preempts it; a goal on other joints
    does not."""
    c = _ctl(base)
    q = _rest(c)
    c.step(0.0, q, np.zeros(c.n))
    ke, kw = c.joint_names.index("r_elbow"), c.joint_names.index("l_elbow")
    g1 = c.execute(c.make_trajectory(["r_elbow", "r_wrist_prosup"], [1.0],
                                     np.array([[q[ke] + 0.2, 0.1]])), 0.0)
    g2 = c.execute(_traj(c, "l_elbow", q[kw] + 0.2, 1.0), 0.0)
    _run(c, 0.0, 0.3)
    assert not g1.done and not g2.done
    g3 = c.execute(_traj(c, "r_wrist_prosup", 0.0, 1.0), 0.3)
    _run(c, 0.3, 0.31)
    assert g1.outcome.code == GoalCode.PREEMPTED
    assert not g2.done and not g3.done


def test_cancel_holds_the_measured_posture(base):
    c = _ctl(base)
    q = _rest(c)
    c.step(0.0, q, np.zeros(c.n))
    k = c.joint_names.index("r_elbow")
    g = c.execute(_traj(c, "r_elbow", q[k] + 0.3, 1.0), 0.0)
    _run(c, 0.0, 0.5)
    mid = c.measured_position[k]
    c.cancel(g)
    assert g.outcome.code == GoalCode.CANCELED
    _run(c, 0.5, 1.2)
    assert c.setpoints.q[k] == pytest.approx(mid, abs=1e-9)


def test_watchdog_aborts_goals_with_the_reason(base):
    """No joint state for state_timeout: the goal ends SAFE_HOLD at once, saying why; new
    trajectories are refused until joint states are back."""
    c = _ctl(base, state_timeout=0.1)
    q = _rest(c)
    c.step(0.0, q, np.zeros(c.n))
    k = c.joint_names.index("r_elbow")
    g = c.execute(_traj(c, "r_elbow", q[k] + 0.2, 1.0), 0.0)
    _run(c, 0.0, 0.2)
    assert c.check_watchdog(0.35)
    assert g.outcome.code == GoalCode.SAFE_HOLD
    assert "no joint state" in g.outcome.message
    with pytest.raises(InvalidInput, match="safe hold"):
        c.execute(_traj(c, "r_elbow", q[k], 1.0), 0.35)
    c.step(0.36, c.setpoints.q.copy(), np.zeros(c.n))
    assert not c.safe_hold
    c.execute(_traj(c, "r_elbow", q[k], 1.0), 0.36)


def test_wall_time_safe_hold_from_the_node(base):
    """enter_safe_hold (the node's wall-time check: simulator paused or gone) aborts the goal
    with its reason."""
    c = _ctl(base)
    q = _rest(c)
    c.step(0.0, q, np.zeros(c.n))
    g = c.execute(_traj(c, "r_elbow", q[c.joint_names.index("r_elbow")] + 0.2, 1.0), 0.0)
    c.enter_safe_hold("no joint state for 2.0 s of wall time: simulator paused or gone")
    assert g.outcome.code == GoalCode.SAFE_HOLD and "simulator" in g.outcome.message
    assert c.safe_hold_reason.startswith("no joint state")


def test_estimator_lost_latches_a_safe_hold_until_estimates_return(base):
    """With the torque loop on, no estimate for estimate_lost_timeout: safe hold (status
    safe_hold, goal aborted); a fresh estimate releases it."""
    c = _ctl(base, torque_loop=True, estimate_lost_timeout=0.2)
    q = _rest(c)
    names = list(c.joint_names)
    c.set_estimate(0.0, names, np.zeros(c.n))
    c.step(0.0, q, np.zeros(c.n))
    k = names.index("r_elbow")
    g = c.execute(_traj(c, "r_elbow", q[k] + 0.2, 1.0), 0.0)
    _run(c, 0.0, 0.25)
    assert g.outcome.code == GoalCode.SAFE_HOLD and "estimator lost" in g.outcome.message
    out = c.step(0.251, c.setpoints.q.copy(), np.zeros(c.n))
    assert out.status == "safe_hold"
    c.set_estimate(0.252, names, np.zeros(c.n))
    out = c.step(0.252, c.setpoints.q.copy(), np.zeros(c.n))
    assert out.status == "ok" and not c.safe_hold


def test_a_restarted_estimator_that_lags_still_releases_the_hold(base):
    """Estimates that come back 60-80 ms behind the joint states (a restarted estimator on a
    loaded machine: older than estimate_timeout, 50 ms) release the estimator-lost hold, while
    the torque loop waits for fresh ones; an estimate older than the hold does not."""
    c = _ctl(base, torque_loop=True, estimate_lost_timeout=0.2)
    q = _rest(c)
    names = list(c.joint_names)
    c.set_estimate(0.0, names, np.zeros(c.n))
    c.step(0.0, q, np.zeros(c.n))
    _run(c, 0.0, 0.25)
    assert c.safe_hold and "estimator lost" in c.safe_hold_reason
    c.set_estimate(0.0, names, np.zeros(c.n))  # the old stamp again: not a new estimate
    assert c.step(0.26, c.setpoints.q.copy(), np.zeros(c.n)).status == "safe_hold"
    for k in range(20):  # the new estimator, 70 ms behind
        t = 0.27 + 0.001 * k
        c.set_estimate(t - 0.07, names, np.zeros(c.n))
        out = c.step(t, c.setpoints.q.copy(), np.zeros(c.n))
    assert not c.safe_hold and out.status == "estimate_stale"


def test_bad_tolerances_are_refused(base):
    c = _ctl(base)
    q = _rest(c)
    c.step(0.0, q, np.zeros(c.n))
    tr = _traj(c, "r_elbow", q[c.joint_names.index("r_elbow")], 1.0)
    with pytest.raises(InvalidInput, match="goal_tolerance"):
        c.execute(tr, 0.0, goal_tolerance=[0.1, 0.1])
    with pytest.raises(InvalidInput, match="path_tolerance"):
        c.execute(tr, 0.0, path_tolerance=[float("nan")])
    with pytest.raises(InvalidInput, match="goal_time_tolerance"):
        c.execute(tr, 0.0, goal_time_tolerance=-1.0)
    assert c.goals == ()


def test_arrival_waits_for_the_hand_to_settle_then_judges_the_measured_error():
    """Judged only after the end and once the hand is still for settle_time; reached iff the
    measured distance is within the tolerance."""
    from icub_pmp.control.arrival_monitor import ArrivalConfig, ArrivalMonitor

    cfg = ArrivalConfig(arrival_tolerance=0.01, settle_speed=0.005, settle_time=0.2,
                        settle_timeout=2.0)
    m = ArrivalMonitor({"right": [0.0, 0.0, 0.0]}, cfg, end=1.0)
    t = 0.0
    while t < 1.0:  # moving in
        t += 0.01
        m.update(t, {"right": [0.1 * (1.0 - t), 0.0, 0.0]})
        assert not m.settled()
    for _ in range(15):  # still 3 mm away, at rest, 0.15 s: not yet settled
        t += 0.01
        m.update(t, {"right": [0.003, 0.0, 0.0]})
    assert not m.settled()
    for _ in range(10):
        t += 0.01
        m.update(t, {"right": [0.003, 0.0, 0.0]})
    assert m.settled()
    a = m.judge()
    assert a.reached and a.settled and a.errors["right"] == pytest.approx(0.003)


def test_arrival_times_out_on_a_hand_that_keeps_moving_and_fails_far_away():
    from icub_pmp.control.arrival_monitor import ArrivalConfig, ArrivalMonitor

    m = ArrivalMonitor({"left": [0.0, 0.0, 0.0]}, ArrivalConfig(settle_timeout=0.5), end=0.0)
    t = 0.0
    for k in range(60):
        t += 0.01
        m.update(t, {"left": [0.05 + 0.01 * math.sin(k), 0.0, 0.0]})
    assert m.settled()
    a = m.judge()
    assert not a.reached and not a.settled


def test_arrival_rejects_bad_targets():
    from icub_pmp.control.arrival_monitor import ArrivalMonitor

    with pytest.raises(InvalidInput, match="no target"):
        ArrivalMonitor({})
    with pytest.raises(InvalidInput, match="not finite"):
        ArrivalMonitor({"right": [float("nan"), 0.0, 0.0]})
