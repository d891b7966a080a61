"""JointTrajectory interpolation and validation; SetpointGenerator preemption, hold and the
velocity mode (eq 7)."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.control.joint_trajectory import JointTrajectory
from icub_pmp.control.setpoint_generator import SetpointGenerator
from icub_pmp.errors import InvalidInput, UnknownName


def _min_jerk(q0, q1, T, t):
    s = np.clip(t / T, 0, 1)
    return q0 + (q1 - q0) * (10 * s**3 - 15 * s**4 + 6 * s**5)


def test_single_point_from_rest_is_minimum_jerk():
    """One point reached from rest is the minimum-jerk profile (position and velocity)."""
    tr = JointTrajectory(["a", "b"], [2.0], [[1.0, -0.5]]).anchored(
        np.zeros(2), np.zeros(2), np.zeros(2), start=1.0)
    for t in np.linspace(0.0, 3.5, 36):
        s = tr.sample(t)
        np.testing.assert_allclose(s.q, _min_jerk(np.zeros(2), np.array([1.0, -0.5]), 2.0,
                                                  t - 1.0), atol=1e-12)
    assert tr.end == 3.0


def test_quintic_passes_through_points_with_given_derivatives():
    """Each point's position, velocity and acceleration are met; the curve is C2 at knots."""
    rng = np.random.default_rng(0)
    times = np.array([0.0, 0.4, 1.0, 1.7])
    pos, vel, acc = (rng.normal(size=(4, 3)) for _ in range(3))
    tr = JointTrajectory(["a", "b", "c"], times, pos, vel, acc, start=5.0)
    for k in range(1, 3):
        t = 5.0 + times[k]
        for eps in (-1e-7, 1e-7):
            s = tr.sample(t + eps)
            np.testing.assert_allclose(s.q, pos[k], atol=1e-5)
            np.testing.assert_allclose(s.v, vel[k], atol=1e-5)
            np.testing.assert_allclose(s.a, acc[k], atol=1e-4)


def test_positions_only_are_smooth_and_shape_preserving():
    """Without velocities, a monotone sequence gives a monotone curve (no overshoot) and the
    velocity is continuous."""
    tr = JointTrajectory(["a"], [0.5, 1.0, 1.5, 2.0], [[0.1], [0.5], [0.6], [1.0]]).anchored(
        np.zeros(1), np.zeros(1), np.zeros(1), start=0.0)
    ts = np.linspace(0, 2.0, 2001)
    q = np.array([tr.sample(t).q[0] for t in ts])
    v = np.array([tr.sample(t).v[0] for t in ts])
    assert np.all(np.diff(q) >= -1e-12)
    assert np.max(np.abs(np.diff(v))) < 0.01


def test_efforts_interpolate_linearly():
    """Efforts (torque-mode feed-forward) are interpolated linearly and held at the end."""
    tr = JointTrajectory(["a"], [0.0, 1.0], [[0.0], [0.0]], efforts=[[0.0], [2.0]])
    assert tr.sample(0.25).effort[0] == pytest.approx(0.5)
    assert tr.sample(3.0).effort[0] == pytest.approx(2.0)


@pytest.mark.parametrize(
    "kwargs, error, match",
    [
        (dict(names=["a"], times=[1.0], positions=[[np.nan]]), InvalidInput, "NaN"),
        (dict(names=["zz"], times=[1.0], positions=[[0.0]]), UnknownName, "zz"),
        (dict(names=["a"], times=[1.0, 1.0], positions=[[0.0], [1.0]]), InvalidInput,
         "strictly increasing"),
        (dict(names=["a"], times=[2.0, 1.0], positions=[[0.0], [1.0]]), InvalidInput,
         "strictly increasing"),
        (dict(names=["a"], times=[-1.0], positions=[[0.0]]), InvalidInput, "negative"),
        (dict(names=["a", "a"], times=[1.0], positions=[[0.0, 0.0]]), InvalidInput,
         "more than once"),
        (dict(names=["a"], times=[1.0], positions=[[0.0, 1.0]]), InvalidInput, "shape"),
        (dict(names=["a"], times=[], positions=np.zeros((0, 1))), InvalidInput, "no points"),
        (dict(names=["a"], times=[1.0], positions=[[3.0]]), InvalidInput, "upper limit"),
        (dict(names=["a"], times=[1.0], positions=[[0.0]], velocities=[[np.inf]]),
         InvalidInput, "velocities"),
    ],
)
def test_bad_trajectories_rejected(kwargs, error, match):
    """NaN/inf, unknown or repeated joints, non-increasing or negative times, wrong shapes,
    empty trajectories and points beyond the joint limits are rejected with a clear error."""
    with pytest.raises(error, match=match):
        JointTrajectory(**kwargs, valid_names=["a", "b"], lower={"a": -1.0}, upper={"a": 1.0})


def _gen():
    g = SetpointGenerator(["a", "b", "c"], np.full(3, -2.0), np.full(3, 2.0))
    g.hold(np.zeros(3), t=0.0)
    return g


def test_preemption_takes_over_only_named_joints():
    """A newer trajectory on joint b replaces the older one on b, joining from b's current
    set-point without a jump; a and c continue the older trajectory."""
    g = _gen()
    g.set_trajectory(JointTrajectory(["a", "b", "c"], [2.0], [[1.0, 1.0, 1.0]]), 0.0)
    for k in range(1, 1001):
        sp = g.update(k * 1e-3)
    qb = sp.q[1]
    g.set_trajectory(JointTrajectory(["b"], [1.0], [[-1.0]]), 1.0)
    sp2 = g.update(1.001)
    assert abs(sp2.q[1] - qb) < 2e-3  # continuous
    for k in range(1002, 3001):
        sp = g.update(k * 1e-3)
    np.testing.assert_allclose(sp.q, [1.0, -1.0, 1.0], atol=1e-12)
    assert not sp.moving and g.active_trajectories == 0
    np.testing.assert_allclose(sp.v, 0.0)


def test_velocity_mode_integrates_eq7_and_lapses():
    """A velocity command integrates q_d(t) = q_d(t - dt) + q_dot_d dt and stops (hold) after
    its timeout."""
    g = _gen()
    g.set_velocity(["c"], [0.5], t_now=0.0, timeout=0.2)
    for k in range(1, 201):
        sp = g.update(k * 1e-3)
    assert sp.q[2] == pytest.approx(0.1, abs=1e-9) and sp.v[2] == 0.5 and sp.moving
    for k in range(201, 400):
        sp = g.update(k * 1e-3)
    assert sp.q[2] == pytest.approx(0.1, abs=1e-3) and sp.v[2] == 0.0 and not sp.moving


def test_setpoints_clipped_to_limits_and_hold_stops_everything():
    """A velocity command stops at the (margin-shrunk) limit; hold() cancels every source."""
    g = SetpointGenerator(["a"], np.array([-1.0]), np.array([1.0]), margin=0.1)
    g.hold(np.zeros(1), t=0.0)
    g.set_velocity(["a"], [5.0], t_now=0.0, timeout=1.0)
    for k in range(1, 500):
        sp = g.update(k * 1e-3)
    assert sp.q[0] == pytest.approx(0.9) and sp.v[0] == 0.0
    g.set_trajectory(JointTrajectory(["a"], [1.0], [[-0.5]]), 0.5)
    g.hold()
    assert not g.update(0.6).moving and g.active_trajectories == 0


def test_no_motion_before_a_joint_state():
    """A trajectory before the first joint state is refused (no set-point to start from)."""
    g = SetpointGenerator(["a"], np.array([-1.0]), np.array([1.0]))
    with pytest.raises(InvalidInput, match="joint state"):
        g.set_trajectory(JointTrajectory(["a"], [1.0], [[0.5]]), 0.0)
