"""The gaze controller core (icub_pmp.gaze): closed-form eye fixation, the neck solver, the
limits, the target checks, the minimum-jerk neck/eye trajectories and tracking updates.

Fixation is always checked with EyeKinematics directly (the simulator's camera mounting): the
angle between each camera's optical axis (+z of its REP-103 frame) and the direction to the
point, not with the controller's own error function.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from icub_pmp.config import config_dir
from icub_pmp.errors import ConfigError, InvalidInput
from icub_pmp.gaze import (
    GAZE_JOINTS,
    EyeFixation,
    GazeController,
    GazeControllerConfig,
    GazeNodeConfig,
    MinJerkLoop,
)
from icub_pmp.kinematics import IcubModel, RobotSpec
from icub_pmp.kinematics.eye_kinematics import EYE_LIMITS, EyeKinematics

SEED = 20  # these tests' points (bench/gaze.py draws its own with another seed)


@pytest.fixture(scope="module")
def model() -> IcubModel:
    return IcubModel()


@pytest.fixture(scope="module")
def gaze(model) -> GazeController:
    return GazeController(model=model)


@pytest.fixture(scope="module")
def rest() -> dict[str, float]:
    return dict(RobotSpec.load().posture("rest"))


def _angle(z: np.ndarray, v: np.ndarray) -> float:
    """Angle [rad] between two vectors (atan2: exact near 0)."""
    return math.atan2(float(np.linalg.norm(np.cross(z, v))), float(z @ v))


def _axis_errors(model: IcubModel, joints: dict[str, float], p: np.ndarray) -> np.ndarray:
    """Angles [rad] between both optical axes and the direction to ``p`` (EyeKinematics)."""
    eyes = EyeKinematics.from_model(model)
    T_head = model.frame_pose(model.q_from_dict(joints), "head").homogeneous
    out = []
    for side in ("left", "right"):
        T = eyes.T_root_camera(T_head, side, joints["eyes_tilt"], joints["eyes_version"],
                               joints["eyes_vergence"])
        out.append(_angle(T[:3, 2], p - T[:3, 3]))
    return np.array(out)


def _front_points(n: int, seed: int = SEED) -> np.ndarray:
    """Points in front of the robot, over and above the table (root_link: x backward)."""
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-0.65, -0.2, n), rng.uniform(-0.35, 0.35, n),
                            rng.uniform(-0.1, 0.45, n)])


def _with(joints: dict[str, float], positions: np.ndarray) -> dict[str, float]:
    out = dict(joints)
    out.update(zip(GAZE_JOINTS, (float(v) for v in positions)))
    return out


def _limits(model: IcubModel) -> tuple[np.ndarray, np.ndarray]:
    idx = model.indices(GAZE_JOINTS[:3])
    lo = np.concatenate([model.lower[idx], [EYE_LIMITS[j][0] for j in GAZE_JOINTS[3:]]])
    hi = np.concatenate([model.upper[idx], [EYE_LIMITS[j][1] for j in GAZE_JOINTS[3:]]])
    return lo, hi


# ---------------------------------------------------------------------------- eyes
def test_closed_form_eyes_fixate_any_point_in_front(model):
    """For random head poses and points in front of the eyes, the closed-form tilt, version
    and vergence put both optical axes through the point (1e-9 rad), and the fixation point
    of those angles is the point."""
    eyes = EyeKinematics.from_model(model)
    fix = EyeFixation(eyes)
    rng = np.random.default_rng(SEED)
    idx = model.indices(GAZE_JOINTS[:3])
    for _ in range(50):
        q = np.zeros(model.nq)
        q[idx] = rng.uniform(model.lower[idx], model.upper[idx])
        T_head = model.frame_pose(q, "head").homogeneous
        hc = fix.head_center(T_head)
        direction = hc[:3, :3] @ np.array([*rng.uniform(-0.6, 0.6, 2), 1.0])
        p = hc[:3, 3] + rng.uniform(0.15, 2.0) * direction / np.linalg.norm(direction)
        a = fix.angles(T_head, p)
        for side in ("left", "right"):
            T = eyes.T_root_camera(T_head, side, *a)
            assert _angle(T[:3, 2], p - T[:3, 3]) < 1e-9
        np.testing.assert_allclose(fix.fixation_point(T_head, a), p, atol=1e-9)


def test_vergence_follows_distance(model):
    """Straight ahead, the vergence is 2 atan(b / 2 / d) of the distance d from the eyes'
    midpoint (baseline b = 0.068 m) and version and tilt vanish."""
    fix = EyeFixation(EyeKinematics.from_model(model))
    T_head = model.frame_pose(np.zeros(model.nq), "head").homogeneous
    hc = fix.head_center(T_head)
    for d in (0.2, 0.5, 1.5):
        a = fix.angles(T_head, hc[:3, 3] + d * hc[:3, 2])
        assert a[0] == pytest.approx(0.0, abs=1e-12)
        assert a[1] == pytest.approx(0.0, abs=1e-12)
        assert a[2] == pytest.approx(2 * math.atan(0.034 / d), abs=1e-12)


def test_parallel_axes_have_no_fixation_point(model):
    """Zero vergence: the optical axes are parallel, there is no fixation point."""
    fix = EyeFixation(EyeKinematics.from_model(model))
    T_head = model.frame_pose(np.zeros(model.nq), "head").homogeneous
    assert fix.fixation_point(T_head, np.zeros(3)) is None


# ---------------------------------------------------------------------------- solve
def test_solution_fixates_points_in_front_within_limits(gaze, model, rest):
    """Points over and above the table: the solved head posture puts both optical axes within
    the fixation tolerance (1 mrad) of the point, inside every joint limit, with the neck
    roll near 0 (< 3 deg)."""
    lo, hi = _limits(model)
    for p in _front_points(40):
        sol = gaze.solve(p, rest)
        assert sol.exact, (p, sol.clipped, sol.fixation_errors)
        err = _axis_errors(model, _with(rest, sol.positions), p)
        assert err.max() < gaze.config.fixation_tolerance, (p, err)
        assert np.all(sol.positions >= lo) and np.all(sol.positions <= hi)
        assert abs(sol.neck[1]) < math.radians(3.0), (p, np.degrees(sol.neck))


def test_neck_points_the_head_and_eyes_end_centred(gaze, rest):
    """A point the neck can point at: the head centre points at it (1e-3 rad) and the eyes
    end near their centre (version and tilt < 0.5 deg), as iKinGazeCtrl's neck solver does."""
    p = np.array([-0.6, 0.1, 0.25])
    sol = gaze.solve(p, rest)
    assert sol.neck_pointing_error < 1e-3
    assert abs(sol.eyes[0]) < math.radians(0.5) and abs(sol.eyes[1]) < math.radians(0.5)


def test_unreachable_point_is_clipped_and_says_so(gaze, model, rest):
    """A point high above the head (beyond neck pitch + eye tilt): the answer stays inside the
    limits, is marked inexact, names the clipped joints, and its predicted fixation error is
    the real one (EyeKinematics)."""
    p = np.array([-0.3, 0.1, 1.5])
    sol = gaze.solve(p, rest)
    lo, hi = _limits(model)
    assert np.all(sol.positions >= lo) and np.all(sol.positions <= hi)
    assert not sol.exact
    assert "eyes_tilt" in sol.clipped
    err = _axis_errors(model, _with(rest, sol.positions), p)
    np.testing.assert_allclose(sol.fixation_errors, err, atol=1e-9)
    assert sol.fixation_error > math.radians(5.0)
    # the pans stay within their own limits too
    pl, pr = EyeKinematics.pans(sol.eyes[1], sol.eyes[2])
    assert EYE_LIMITS["pan"][0] <= min(pl, pr) and max(pl, pr) <= EYE_LIMITS["pan"][1]


@pytest.mark.parametrize("point, words", [
    ([0.3, 0.0, 0.3], "behind the head"),
    ([0.0, 0.5, 0.33], "behind the head"),
    ([-0.12, 0.0, 0.33], "too close"),
    ([math.nan, 0.0, 0.0], "finite"),
    ([-0.3, 0.0], "3 finite"),
])
def test_bad_targets_raise_clear_errors(gaze, rest, point, words):
    """A point behind the head, too close to the eyes, NaN or of the wrong length raises
    InvalidInput naming the problem and the point."""
    with pytest.raises(InvalidInput, match=words):
        gaze.solve(np.array(point), rest)
    with pytest.raises(InvalidInput, match=words):
        gaze.plan(np.array(point), rest)


def test_non_finite_joints_are_refused(gaze, rest):
    """A NaN joint position raises InvalidInput naming the joint."""
    bad = dict(rest, neck_yaw=math.nan)
    with pytest.raises(InvalidInput, match="neck_yaw"):
        gaze.solve(np.array([-0.4, 0.0, 0.1]), bad)


# ---------------------------------------------------------------------------- trajectories
@pytest.mark.parametrize("T, Ts", [(0.25, 0.01), (0.75, 0.01), (0.25, 0.001)])
def test_min_jerk_loop_samples_the_continuous_response(T, Ts):
    """The closed min-jerk loop, sampled exactly: 90 % of a step at T (+-1.5 %), more than
    98 % at 1.5 T, no overshoot (< 0.01 %) even at 25 samples per T, and the same samples
    whatever the period."""
    loop = MinJerkLoop(1, T, Ts)
    e, y = np.array([1.0]), []
    for _ in range(int(round(4 * T / Ts))):
        e = loop.step(e)
        y.append(1.0 - e[0])
    y = np.array(y)
    assert abs(y[int(round(T / Ts)) - 1] - 0.90) < 0.015
    assert y[int(round(1.5 * T / Ts)) - 1] > 0.98
    assert y.max() < 1.0001
    fine = MinJerkLoop(1, T, Ts / 10)
    e = np.array([1.0])
    for _ in range(int(round(10 * T / Ts))):
        e = fine.step(e)
    assert 1.0 - e[0] == pytest.approx(y[int(round(T / Ts)) - 1], abs=1e-9)


def test_plan_is_a_min_jerk_move_from_rest_to_rest(gaze, model, rest):
    """The plan starts at the current head posture and ends at the solution, both at rest;
    positions stay inside the limits; the neck covers about 90 % of its move at
    neck_traj_time (the min-jerk controllers of iKinGazeCtrl: 90 % at T); the eyes reach
    their fixation much sooner than the neck reaches its target; the trajectory lasts about
    2 neck_traj_time (the min-jerk transient, down to 0.1 mrad) and its velocities are
    continuous."""
    c = gaze.config
    p = np.array([-0.5, 0.25, 0.15])  # the eyes never reach a limit on the way
    plan = gaze.plan(p, rest)
    q0 = gaze.head_joints(rest)
    np.testing.assert_allclose(plan.q[0], q0, atol=1e-12)
    np.testing.assert_allclose(plan.qd[0], 0.0, atol=0.01)
    np.testing.assert_allclose(plan.q[-1], plan.solution.positions, atol=1e-12)
    np.testing.assert_allclose(plan.qd[-1], 0.0, atol=1e-12)
    lo, hi = _limits(model)
    assert np.all(plan.q >= lo - 1e-12) and np.all(plan.q <= hi + 1e-12)
    neck0, neck1 = q0[:3], plan.solution.neck
    k = plan.index_at(c.neck_traj_time)
    frac = np.linalg.norm(plan.q[k, :3] - neck0) / np.linalg.norm(neck1 - neck0)
    assert 0.85 < frac < 0.95
    assert 1.5 * c.neck_traj_time < plan.duration < 2.6 * c.neck_traj_time
    # the velocities integrate to the positions (trapezoid rule, within 0.05 rad/s)
    mean_v = 0.5 * (plan.qd[:-1] + plan.qd[1:])
    np.testing.assert_allclose(np.diff(plan.q, axis=0) / c.period, mean_v, atol=0.05)
    acc = np.diff(plan.qd, axis=0) / c.period
    assert np.abs(acc[:, :3]).max() < 30.0  # rad/s^2: a smooth neck profile, no jumps
    # the eyes fixate well before the neck settles (saccade, then counter-rotation)
    errs = np.array([_axis_errors(model, _with(rest, q), p).max() for q in plan.q])
    settled = int(np.argmax(errs < math.radians(0.1)))
    assert plan.t[settled] < 2.0 * c.eyes_traj_time
    assert errs[settled:].max() < math.radians(0.1)
    neck_done = int(np.argmax(np.abs(plan.q[:, :3] - neck1).max(axis=1) < math.radians(0.5)))
    assert plan.t[neck_done] > plan.t[settled] + 0.3


def test_neck_time_can_be_set_per_plan_but_not_below_the_eyes(gaze, rest):
    """A longer neck time stretches the plan; a neck time not above eyes_traj_time raises."""
    p = np.array([-0.4, -0.2, 0.1])
    slow = gaze.plan(p, rest, neck_traj_time=1.5)
    assert slow.duration > gaze.plan(p, rest).duration + 0.5
    with pytest.raises(InvalidInput, match="eyes_traj_time"):
        gaze.plan(p, rest, neck_traj_time=gaze.config.eyes_traj_time)


def test_tracking_update_continues_smoothly(gaze, model, rest):
    """A new target during a plan: the new plan starts at the running plan's state (position
    and velocity) at that time; a target moved by less than the activation angle keeps the
    neck target, a large move re-solves it; both end fixating their targets."""
    p0 = np.array([-0.45, 0.0, 0.05])
    plan = gaze.plan(p0, rest)
    elapsed = 0.2
    k = plan.index_at(elapsed)
    near = p0 + np.array([0.0, 0.01, 0.0])  # about 1.2 deg from the head centre
    upd = gaze.update(plan, elapsed, near, rest)
    np.testing.assert_allclose(upd.q[0], plan.q[k], atol=1e-12)
    np.testing.assert_allclose(upd.qd[0], plan.qd[k], atol=1e-2)
    assert not upd.solution.neck_solved
    np.testing.assert_allclose(upd.solution.neck, plan.solution.neck)
    far = np.array([-0.35, 0.3, 0.2])
    upd2 = gaze.update(plan, elapsed, far, rest)
    assert upd2.solution.neck_solved
    for u, p in ((upd, near), (upd2, far)):
        assert _axis_errors(model, _with(rest, u.q[-1]), p).max() < 2e-3


def test_fixation_point_of_the_solution_is_the_target(gaze, rest):
    """GazeController.fixation_point at the solved posture returns the target."""
    p = np.array([-0.3, -0.15, 0.05])
    sol = gaze.solve(p, rest)
    np.testing.assert_allclose(gaze.fixation_point(_with(rest, sol.positions)), p, atol=1e-6)


# ---------------------------------------------------------------------------- config
def test_configs_validate_and_the_shipped_yaml_loads():
    """config/gaze_controller.yaml loads into both dataclasses with iKinGazeCtrl's times; a
    neck time not above the eyes' and unknown keys are refused by name."""
    path = config_dir() / "gaze_controller.yaml"
    c = GazeControllerConfig.from_yaml(path, "gaze_controller")
    n = GazeNodeConfig.from_yaml(path, "gaze_controller")
    assert (c.neck_traj_time, c.eyes_traj_time) == (0.75, 0.25)
    assert n.tracking_topic == "/motion/target"
    with pytest.raises(ConfigError, match="neck_traj_time"):
        GazeControllerConfig(neck_traj_time=0.2)
    with pytest.raises(ConfigError, match="neck_trajtime"):
        GazeControllerConfig.from_dict({"neck_trajtime": 1.0})
    with pytest.raises(ConfigError, match="tracking_topic"):
        GazeNodeConfig(tracking_topic="")


def test_a_large_head_turn_stays_within_the_joint_limits(gaze, rest):
    """A point far to the side needs a fast neck at the default 0.75 s: the plan keeps every
    head joint within its velocity and acceleration limits (config/robot.yaml) by
    lengthening the neck's trajectory, and still fixates the point."""
    from icub_pmp.control.joint_trajectory import JointTrajectory

    p = np.array([-0.2, 0.6, 0.6])
    fast = gaze._rollout(p, rest, None, None, gaze.config.neck_traj_time)
    over = gaze.rate_limits.report(JointTrajectory(fast.joint_names, fast.t, fast.q, fast.qd))
    assert not over.within(0.05)  # the iKinGazeCtrl default time is too fast for this turn
    plan = gaze.plan(p, rest)
    rep = gaze.rate_limits.report(JointTrajectory(plan.joint_names, plan.t, plan.q, plan.qd))
    assert rep.within(0.05), rep.describe()
    assert plan.duration > 0.75
