"""PMP building blocks: each test checks an equation of Mohan et al. 2009 or a derivative."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from icub_pmp.errors import ConfigError, InvalidInput
from icub_pmp.kinematics import RobotSpec
from icub_pmp.pmp import (
    BranchNetwork,
    ForceField,
    JointLimitField,
    ObstacleField,
    OrientationField,
    PinocchioJacobianProvider,
    PmpConfig,
    TimeBaseGenerator,
)


@pytest.fixture(scope="module")
def provider():
    return PinocchioJacobianProvider()


@pytest.fixture(scope="module")
def spec():
    return RobotSpec.load()


# ---------------------------------------------------------------------- TBG (eq 7)
def test_tbg_is_minimum_jerk_with_bell_speed():
    """xi goes 0 -> 1 over tau with zero speed at both ends and its speed peak at tau/2 (eq 7)."""
    tbg = TimeBaseGenerator(2.0)
    t = np.linspace(0, 2, 2001)
    assert tbg.xi(0.0) == 0.0 and tbg.xi(2.0) == 1.0
    assert np.all(np.diff(tbg.xi(t)) >= 0)
    v = tbg.xi_dot(t)
    assert v[0] == 0 and v[-1] == 0
    assert t[np.argmax(v)] == pytest.approx(1.0, abs=1e-3)
    assert v.max() == pytest.approx(1.875 / 2.0)
    assert np.allclose(np.gradient(tbg.xi(t), t), v, atol=1e-5)


def test_gamma_integrates_to_relaxation_time_and_diverges_at_tau():
    """s(t) = -ln(1 - xi) is the integral of Gamma = xi_dot/(1 - xi) (eq 7); Gamma has a simple
    pole at tau (Gamma (tau - t) -> 3) and s maps [0, tau) onto [0, inf)."""
    tbg = TimeBaseGenerator(1.5)
    for t in (0.3, 0.75, 1.2, 1.45):
        integral, _ = quad(lambda x: float(tbg.gamma(x)), 0.0, t, limit=200)
        assert integral == pytest.approx(float(tbg.relaxation_time(t)), rel=1e-7)
    assert np.isinf(tbg.gamma(1.5)) and np.isinf(tbg.relaxation_time(1.5))
    assert float(tbg.gamma(1.5 - 1e-7)) * 1e-7 == pytest.approx(3.0, rel=1e-4)
    # no cancellation near tau: s stays finite and increasing at 1e-12 s before tau
    near = 1.5 - np.array([1e-3, 1e-6, 1e-9, 1e-12])
    s = tbg.relaxation_time(near)
    assert np.all(np.isfinite(s)) and np.all(np.diff(s) > 0)
    # inverse map
    ts = np.array([0.01, 0.4, 1.0, 1.49])
    assert np.allclose(tbg.time_of_relaxation(tbg.relaxation_time(ts)), ts, atol=1e-9)


def test_tbg_rejects_bad_tau():
    """A non-positive or NaN tau is an InvalidInput naming tau."""
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(InvalidInput, match="tau"):
            TimeBaseGenerator(bad)


# ---------------------------------------------------------------------- fields (eqs 1, 6)
def test_force_field_eq1_isotropic_anisotropic_and_curl():
    """F = K_ext (x_T - x) (eq 1); the rotational component vanishes at the target and is
    orthogonal to the radial pull; -dF/dx equals the reported Jacobian."""
    xt = np.array([0.1, -0.2, 0.3])
    x = np.array([0.0, 0.0, 0.0])
    assert np.allclose(ForceField(xt, 500.0).force(x), 500.0 * xt)
    aniso = ForceField(xt, [100.0, 200.0, 300.0])
    assert np.allclose(aniso.force(x), [10.0, -40.0, 90.0])
    curl = ForceField(xt, 100.0, curl=50.0, curl_axis=(0, 0, 1))
    assert np.allclose(curl.force(xt), 0.0)
    extra = curl.force(x) - 100.0 * xt
    assert abs(extra @ xt) < 1e-12 and np.linalg.norm(extra) > 0
    eps = 1e-6
    num = np.column_stack([(curl.force(x + eps * e) - curl.force(x - eps * e)) / (2 * eps)
                           for e in np.eye(3)])
    assert np.allclose(-num, curl.jacobian, atol=1e-6)


def test_force_field_rejects_bad_stiffness():
    """Negative, asymmetric or NaN stiffness and a NaN target raise InvalidInput."""
    with pytest.raises(InvalidInput, match="stiffness"):
        ForceField([0, 0, 0], -1.0)
    with pytest.raises(InvalidInput, match="symmetric"):
        ForceField([0, 0, 0], [[1, 2, 0], [0, 1, 0], [0, 0, 1]])
    with pytest.raises(InvalidInput, match="target"):
        ForceField([0, np.nan, 0], 1.0)


def test_joint_limit_field_eq6():
    """T = alpha ln((1 - lambda)/lambda) (eq 6): zero at mid-range, pushing inward near each
    limit, diverging at the limits; stiffness = -dT/dq and T = -dU/dq."""
    f = JointLimitField([-1.0, 0.0], [1.0, 2.0], alpha=0.5)
    assert np.allclose(f.torques(np.array([0.0, 1.0])), 0.0)
    q = np.array([-0.5, 1.5])  # lambda = 0.25, 0.75
    assert np.allclose(f.torques(q), [0.5 * np.log(3.0), -0.5 * np.log(3.0)])
    near = f.torques(np.array([-1.0 + 1e-8, 2.0 - 1e-8]))
    assert near[0] > 8.0 and near[1] < -8.0
    assert np.all(np.isfinite(f.torques(np.array([-5.0, 5.0]))))  # clamped beyond limits
    eps = 1e-7
    for i in range(2):
        dq = np.zeros(2)
        dq[i] = eps
        dt = (f.torques(q + dq) - f.torques(q - dq)) / (2 * eps)
        assert -dt[i] == pytest.approx(f.stiffness(q)[i], rel=1e-6)
        du = (f.potential(q + dq) - f.potential(q - dq)) / (2 * eps)
        assert -du == pytest.approx(f.torques(q)[i], rel=1e-5)
    t, k = f.torques_and_stiffness(q)
    assert np.allclose(t, f.torques(q)) and np.allclose(k, f.stiffness(q))


def test_joint_limit_field_rejects_empty_range():
    """upper <= lower raises InvalidInput naming the joint index."""
    with pytest.raises(InvalidInput, match="index"):
        JointLimitField([0.0, 1.0], [1.0, 1.0], 0.1)


def test_obstacle_field_is_the_gradient_of_its_potential_and_local():
    """The repulsive field is -grad U, points away from the centre, and is zero beyond the
    influence distance (so it cannot move an equilibrium outside that shell)."""
    ob = ObstacleField([0.0, 0.0, 0.0], radius=0.05, influence=0.05, gain=1e-3)
    x = np.array([0.06, 0.02, -0.01])
    f = ob.force(x)
    assert f @ x > 0
    eps = 1e-7
    grad = np.array([(ob.potential(x + eps * e) - ob.potential(x - eps * e)) / (2 * eps)
                     for e in np.eye(3)])
    assert np.allclose(-grad, f, rtol=1e-5)
    assert np.allclose(ob.force([0.2, 0.0, 0.0]), 0.0)
    assert ob.clearance([0.1, 0.0, 0.0]) == pytest.approx(0.05)


def test_orientation_field_pulls_along_the_rotation_vector():
    """M = k log(R_T R^T): zero at the target, about the rotation axis otherwise."""
    rz = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90 deg about z
    field = OrientationField(rz, stiffness=2.0)
    assert np.allclose(field.torque(rz), 0.0)
    assert np.allclose(field.torque(np.eye(3)), [0.0, 0.0, 2.0 * np.pi / 2])
    with pytest.raises(InvalidInput, match="rotation"):
        OrientationField(np.diag([1.0, 1.0, -1.0]))


# ---------------------------------------------------------------------- body model
def test_provider_jacobians_match_finite_differences(provider, spec):
    """The hand Jacobians (LOCAL_WORLD_ALIGNED linear rows) are the derivative of the hand
    positions: x_dot = J q_dot (eq 4)."""
    rng = np.random.default_rng(3)
    frames = [spec.hand_frame("left"), spec.hand_frame("right")]
    q = rng.uniform(provider.lower, provider.upper)
    kin = provider.kinematics(q, frames)
    assert np.allclose(kin.positions, provider.positions(q, frames))
    eps = 1e-7
    for j in range(provider.nq):
        dq = np.zeros(provider.nq)
        dq[j] = eps
        d = (provider.positions(q + dq, frames) - provider.positions(q - dq, frames)) / (2 * eps)
        assert np.allclose(kin.jacobians[:, :3, j], d, atol=1e-6)


def test_provider_static_torques_are_jacobian_transpose_plus_gravity(provider, spec):
    """tau = J^T F_T (+ g(q)) (Sect. 2.3: torques depend on the posture through J^T)."""
    rng = np.random.default_rng(4)
    frames = [spec.hand_frame("right")]
    q = rng.uniform(provider.lower, provider.upper)
    f = np.array([[3.0, -2.0, 5.0]])
    kin = provider.kinematics(q, frames)
    expected = kin.jacobians[0, :3].T @ f[0]
    assert np.allclose(provider.static_torques(q, frames, f, gravity=False), expected, atol=1e-9)
    g = provider.icub.gravity_torques(q)
    assert np.allclose(provider.static_torques(q, frames, f, gravity=True), expected + g,
                       atol=1e-9)
    assert "r_elbow" in provider.ancestors(frames[0])
    assert "l_elbow" not in provider.ancestors(frames[0])


# ---------------------------------------------------------------------- branching (Fig 5)
def test_branch_network_nodes_equal_the_stacked_relaxation(provider, spec):
    """Sum node + per-segment admittances + assignment node (Fig 5) give the same joint and
    hand velocities as the stacked PMP q_dot = A G^T F (the nodes are dual, Sect. 3.1)."""
    rng = np.random.default_rng(5)
    trunk = spec.torso_joints
    arms = {h: spec.arm_joints(h) for h in ("left", "right")}
    net = BranchNetwork(trunk, arms, [0.1, 0.2, 0.3],
                        {h: rng.uniform(0.5, 1.5, 7) for h in arms})
    q = rng.uniform(provider.lower, provider.upper)
    frames = [spec.hand_frame(h) for h in arms]
    kin = provider.kinematics(q, frames)
    idx = [provider.joint_names.index(j) for j in net.joint_names]
    g = kin.jacobians[:, :3, idx].reshape(6, -1)
    forces = rng.normal(size=(2, 3))
    stacked = net.admittance * (g.T @ forces.reshape(-1))
    chain_torques, chain_jac = {}, {}
    for i, h in enumerate(arms):
        cols = net.chain_indices(h)
        chain_jac[h] = g[3 * i:3 * i + 3, cols]
        chain_torques[h] = chain_jac[h].T @ forces[i]  # eq 2 on branch h's own chain
    q_dot = net.relax(chain_torques)
    assert np.allclose(q_dot, stacked)
    # assignment node: each hand moves by its chain Jacobian times [trunk; own] velocities
    assigned = net.assignment_node(
        q_dot[net.trunk_slice], {h: q_dot[net.branch_slices[h]] for h in arms}
    )
    for i, h in enumerate(arms):
        assert np.allclose(chain_jac[h] @ assigned[h], (g @ stacked)[3 * i:3 * i + 3])
    # a stiff trunk grounds the shoulders: no trunk motion
    stiff = net.with_admittance(trunk_admittance=[0.0, 0.0, 0.0])
    assert np.allclose(stiff.relax(chain_torques)[stiff.trunk_slice], 0.0)


def test_branch_network_validation():
    """A duplicate joint, a missing admittance or a negative admittance raise InvalidInput."""
    with pytest.raises(InvalidInput, match="twice"):
        BranchNetwork(["a"], {"left": ["a", "b"]}, [1.0], {"left": [1.0, 1.0]})
    with pytest.raises(InvalidInput, match="right"):
        BranchNetwork([], {"right": ["b"]}, [], {})
    with pytest.raises(InvalidInput, match=">= 0"):
        BranchNetwork([], {"left": ["b"]}, [], {"left": [-1.0]})


# ---------------------------------------------------------------------- configuration
def test_pmp_config_rejects_bad_values():
    """Out-of-range values raise ConfigError naming the field; unknown keys are rejected."""
    with pytest.raises(ConfigError, match="tau"):
        PmpConfig(tau=0.0)
    with pytest.raises(ConfigError, match="time_parametrisation"):
        PmpConfig(time_parametrisation="linear")
    with pytest.raises(ConfigError, match="arm_admittance"):
        PmpConfig(arm_admittance=(1.0, 1.0))
    with pytest.raises(ConfigError, match="bogus"):
        PmpConfig.from_dict({"bogus": 1.0})
