"""Property-based tests (hypothesis): what must hold for every input, not for a few examples.

- the PMP fields (eqs 1 and 6 of Mohan et al. 2009, the FIRAS obstacle, the orientation field):
  forces are minus the gradient of their potentials, attract or repel as stated;
- the damped-least-squares step: bounded, a descent direction, the least-squares step when
  undamped;
- the message conversions: every round trip (numpy -> message -> numpy, CDR bytes) is exact.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from icub_pmp.kinematics.dls_step import damped_least_squares_step
from icub_pmp.kinematics.rotations import matrix_to_quat_wxyz, quat_wxyz_to_matrix, rotation_angle
from icub_pmp.pmp import ForceField, JointLimitField, ObstacleField, OrientationField
from icub_pmp.ros.conversions import (
    array_to_image,
    array_to_wrench,
    arrays_to_pose,
    arrays_to_trajectory,
    duration_to_sec,
    image_to_array,
    joint_state_arrays,
    make_joint_state,
    pose_to_arrays,
    sec_to_duration,
    sec_to_time,
    time_to_sec,
    trajectory_to_arrays,
    wrench_to_array,
)
from icub_pmp.ros.raw_messages import (
    RawJointStateReader,
    RawJointStateWriter,
    raw_header_stamp_ns,
)

settings.register_profile("icub", max_examples=60, deadline=None, derandomize=True)
settings.load_profile("icub")

finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
vec3 = hnp.arrays(np.float64, 3, elements=st.floats(-2.0, 2.0))
unit_quat = hnp.arrays(np.float64, 4, elements=st.floats(-1.0, 1.0)).filter(
    lambda q: np.linalg.norm(q) > 0.1).map(lambda q: q / np.linalg.norm(q))


def _numeric_gradient(f, x: np.ndarray, h: float = 1e-6) -> np.ndarray:
    g = np.zeros_like(x)
    for i in range(x.size):
        d = np.zeros_like(x)
        d[i] = h
        g[i] = (f(x + d) - f(x - d)) / (2 * h)
    return g


# ---------------------------------------------------------------------------- PMP fields
@given(target=vec3, x=vec3, k=hnp.arrays(np.float64, 3, elements=st.floats(1.0, 5e3)))
def test_force_field_is_minus_the_gradient_of_its_potential_and_attracts(target, x, k):
    """Eq 1: F = K (x_T - x) = -dU/dx, zero at the target, never pointing away from it."""
    field = ForceField(target, k)
    f = field.force(x)
    np.testing.assert_allclose(f, -_numeric_gradient(field.potential, x), rtol=1e-5, atol=1e-4)
    assert f @ (target - x) >= -1e-9
    np.testing.assert_allclose(field.force(target), 0.0, atol=1e-12)


@given(target=vec3, x=vec3, curl=st.floats(-500.0, 500.0), axis=vec3.filter(
    lambda a: np.linalg.norm(a) > 1e-3))
def test_curl_rotates_the_flow_without_moving_the_equilibrium(target, x, curl, axis):
    """The rotational component is perpendicular to x_T - x: same pull, same equilibrium."""
    plain = ForceField(target, 1000.0)
    curled = ForceField(target, 1000.0, curl=curl, curl_axis=axis)
    e = target - x
    assert abs((curled.force(x) - plain.force(x)) @ e) <= 1e-6 * (1 + e @ e) * (1 + abs(curl))
    np.testing.assert_allclose(curled.force(target), 0.0, atol=1e-12)


@given(lam=hnp.arrays(np.float64, 4, elements=st.floats(0.01, 0.99)),
       alpha=st.floats(1e-4, 10.0))
def test_joint_limit_field_pushes_toward_mid_range(lam, alpha):
    """Eq 6: the torque is minus the gradient of a convex potential, points toward mid-range
    and vanishes there; the stiffness is its (positive) negative derivative."""
    lower, upper = np.array([-1.0, 0.0, -2.0, 0.5]), np.array([1.0, 2.5, -1.0, 3.0])
    field = JointLimitField(lower, upper, alpha)
    q = lower + lam * (upper - lower)
    t = field.torques(q)
    np.testing.assert_allclose(t, -_numeric_gradient(field.potential, q), rtol=1e-4, atol=1e-6)
    assert np.all(t * (0.5 - lam) >= 0)
    np.testing.assert_allclose(field.torques((lower + upper) / 2), 0.0, atol=1e-12)
    assert np.all(field.stiffness(q) > 0)
    t2, k2 = field.torques_and_stiffness(q)
    np.testing.assert_allclose(t2, t)
    np.testing.assert_allclose(k2, field.stiffness(q))


@given(x=vec3, radius=st.floats(0.02, 0.2), influence=st.floats(0.01, 0.2))
def test_obstacle_field_repels_only_within_its_influence(x, radius, influence):
    """FIRAS: the force points away from the centre, is zero beyond the influence distance and
    is minus the gradient of the potential outside the clamped core."""
    field = ObstacleField([0.1, -0.2, 0.3], radius, influence)
    f = field.force(x)
    rho = float(field.clearance(x))
    assert f @ (x - field.center) >= 0
    if rho >= influence:
        assert not np.any(f)
    elif rho > 2 * field.rho_min:
        grad = _numeric_gradient(field.potential, x, h=1e-7)
        np.testing.assert_allclose(f, -grad, rtol=1e-3, atol=1e-6 * max(1.0, np.abs(f).max()))


@given(q_target=unit_quat, q_hand=unit_quat, k=st.floats(0.1, 100.0))
def test_orientation_torque_turns_the_hand_toward_the_target(q_target, q_hand, k):
    """The torque is k times the rotation vector to the target: its norm is k * angle (<= pi)
    and rotating the hand a little along it brings it closer."""
    R_t, R = quat_wxyz_to_matrix(q_target), quat_wxyz_to_matrix(q_hand)
    field = OrientationField(R_t, k)
    m = field.torque(R)
    angle = rotation_angle(R_t, R)
    # (acos of the trace, in rotation_angle, is good to ~1e-8 rad near 0)
    assert math.isclose(np.linalg.norm(m), k * angle, rel_tol=1e-6, abs_tol=1e-7 * k)
    if 1e-3 < angle < math.pi - 1e-3:
        step = pin.exp3(1e-3 * m / np.linalg.norm(m)) @ R
        assert rotation_angle(R_t, step) < angle


# ---------------------------------------------------------------------------- DLS step
@given(
    jac=hnp.arrays(np.float64, (3, 7), elements=st.floats(-1.0, 1.0)),
    err=hnp.arrays(np.float64, 3, elements=st.floats(-0.5, 0.5)),
    damping=st.floats(1e-3, 1.0),
    max_step=st.floats(1e-3, 2.0),
)
def test_dls_step_is_bounded_and_a_descent_direction(jac, err, damping, max_step):
    """dq = J^T (J J^T + mu^2 I)^-1 e: never longer than max_step, and J dq never points away
    from the error (e . J dq >= 0: the task error does not grow to first order)."""
    dq = damped_least_squares_step(jac.copy(), err, damping, max_step)
    assert np.linalg.norm(dq) <= max_step * (1 + 1e-12)
    assert err @ (jac @ dq) >= -1e-12


@given(
    jac=hnp.arrays(np.float64, (3, 7), elements=st.floats(-1.0, 1.0)).filter(
        lambda j: np.linalg.svd(j, compute_uv=False).min() > 0.1),
    err=hnp.arrays(np.float64, 3, elements=st.floats(-0.1, 0.1)),
)
def test_undamped_dls_step_solves_the_task_exactly(jac, err):
    """With mu -> 0 and no step cap, a full-rank J (3 x 7) is followed exactly: J dq = e, and
    dq is the minimum-norm solution (orthogonal to J's null space)."""
    dq = damped_least_squares_step(jac.copy(), err, 1e-9, 1e9)
    np.testing.assert_allclose(jac @ dq, err, atol=1e-9)
    np.testing.assert_allclose(dq, np.linalg.pinv(jac) @ err, atol=1e-9)


# ---------------------------------------------------------------------------- conversions
@given(ns=st.integers(0, 2**31 * 10**9 - 1))
def test_time_and_duration_round_trip_to_the_nanosecond(ns):
    s = ns * 1e-9
    assert abs(time_to_sec(sec_to_time(s)) - s) <= 1e-9 * max(1.0, s) * 1e-6 + 1e-9
    t = sec_to_time(s)
    assert 0 <= t.nanosec < 1_000_000_000
    d = sec_to_duration(s)
    assert abs(duration_to_sec(d) - s) <= 1e-9 + 1e-15 * s


@given(q=unit_quat)
def test_quaternion_matrix_round_trip(q):
    """matrix_to_quat(quat_to_matrix(q)) = +-q (w >= 0); the matrix is a rotation."""
    R = quat_wxyz_to_matrix(q)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) > 0
    back = matrix_to_quat_wxyz(R)
    assert back[0] >= 0
    assert np.allclose(back, q, atol=1e-9) or np.allclose(back, -q, atol=1e-9), (back, q)


@given(p=vec3, q=unit_quat)
def test_pose_round_trip(p, q):
    pos, quat = pose_to_arrays(arrays_to_pose(p, q))
    np.testing.assert_array_equal(pos, p)
    np.testing.assert_allclose(quat, q, atol=1e-15)


@given(w=hnp.arrays(np.float64, 6, elements=finite))
def test_wrench_round_trip(w):
    np.testing.assert_array_equal(wrench_to_array(array_to_wrench(w)), w)


@given(data=st.data(), n=st.integers(1, 6), k=st.integers(1, 8))
def test_trajectory_round_trip(data, n, k):
    """arrays -> JointTrajectory -> arrays keeps names, positions, velocities exactly and times
    to the nanosecond."""
    names = [f"j{i}" for i in range(n)]
    steps = data.draw(hnp.arrays(np.float64, k, elements=st.floats(0.001, 1.0)))
    times = np.cumsum(steps)
    pos = data.draw(hnp.arrays(np.float64, (k, n), elements=finite))
    vel = data.draw(hnp.arrays(np.float64, (k, n), elements=finite))
    msg = arrays_to_trajectory(names, times, pos, vel)
    names2, times2, pos2, vel2 = trajectory_to_arrays(msg, names)
    assert names2 == names
    np.testing.assert_allclose(times2, times, atol=1e-9)
    np.testing.assert_array_equal(pos2, pos)
    np.testing.assert_array_equal(vel2, vel)


@given(img=hnp.arrays(np.uint8, st.tuples(st.integers(1, 12), st.integers(1, 12), st.just(3))))
def test_rgb_image_round_trip(img):
    msg = array_to_image(img, "rgb8")
    np.testing.assert_array_equal(image_to_array(msg, img.shape[1], img.shape[0]), img)


@given(img=hnp.arrays(np.uint8, st.tuples(st.integers(1, 12), st.integers(1, 12))))
def test_mono_image_round_trip(img):
    np.testing.assert_array_equal(image_to_array(array_to_image(img, "mono8")), img)


@given(data=st.data(), n=st.integers(1, 30), ns=st.integers(0, 2**40))
def test_joint_state_raw_bytes_round_trip(data, n, ns):
    """JointState written as CDR bytes (RawJointStateWriter) reads back exactly, through the
    raw reader and through rclpy's deserialiser; the header stamp reads from the bytes."""
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import JointState

    names = [f"joint_{i}" for i in range(n)]
    q, v, tau = (data.draw(hnp.arrays(np.float64, n, elements=finite)) for _ in range(3))
    raw = RawJointStateWriter(names).write(ns, q, v, tau)
    assert raw_header_stamp_ns(raw) == ns
    msg = RawJointStateReader().read(raw)
    assert list(msg.name) == names and msg.stamp_ns == ns
    for a, b in ((msg.position, q), (msg.velocity, v), (msg.effort, tau)):
        np.testing.assert_array_equal(a, b)
    ros = deserialize_message(raw, JointState)
    np.testing.assert_array_equal(np.asarray(ros.position), q)
    q2, v2, _ = joint_state_arrays(ros, names[::-1])
    np.testing.assert_array_equal(q2, q[::-1])
    np.testing.assert_array_equal(v2, v[::-1])
    built = make_joint_state(names, position=q, stamp=sec_to_time(1.5))
    np.testing.assert_array_equal(joint_state_arrays(built, names)[0], q)
