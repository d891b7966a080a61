"""The eq 11 Cartesian solver (IkSolver, CasADi + IPOPT, its warm-start seed)."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from icub_pmp.cartesian import (
    ArmLinearConstraints,
    IkConfig,
    IkSolver,
    KinematicChain,
    MinJerkConfig,
)
from icub_pmp.config import config_dir
from icub_pmp.errors import ConfigError, InvalidInput, UnknownName
from icub_pmp.ros.cartesian_node_config import CartesianNodeConfig

CHAIN = "torso_right_arm"


def _cfg(**kw) -> IkConfig:
    """Test configuration: CasADi VM (no compile, fast start) and a wall-time bound loose
    enough for a heavily loaded machine (these tests check answers, not speed)."""
    kw.setdefault("codegen", False)
    kw.setdefault("max_solve_time", 5.0)
    return IkConfig(**kw)


@pytest.fixture(scope="module")
def solver(model) -> IkSolver:
    # the CasADi VM (no C compilation) keeps the suite fast; test_codegen_* covers gcc
    return IkSolver(model, _cfg())


def _targets(model, n, seed, hand="right", torso=True):
    """Hand poses of configurations drawn uniformly in the joint limits that meet the arm
    constraints (torso at 0 when ``torso`` is False)."""
    chain = KinematicChain.from_name(KinematicChain.named(hand, True))
    alc = ArmLinearConstraints(hand)
    idx = model.indices(chain.joints)
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        q = model.random_q(rng)
        if not torso:
            q[model.indices(chain.joints[:3])] = 0.0
        if alc.violation(chain.joints, q[idx]) == 0.0:
            out.append(model.frame_pose(q, chain.frame))
    return out


def test_reachable_poses_solved_within_epsilon_and_limits(model, solver):
    """Random reachable poses (10-DoF): position within sqrt(epsilon + tol), orientation within
    1 deg, joints inside their limits and the shoulder constraints met."""
    cfg = solver.config
    prob = solver.problem(CHAIN)
    for T in _targets(model, 8, seed=1):
        for rot in (None, T.rotation):
            sol = solver.solve(CHAIN, T.translation, rot)
            assert sol.success, sol.message
            assert sol.position_error <= math.sqrt(cfg.epsilon + cfg.constraint_tolerance) + 1e-12
            assert sol.position_error ** 2 <= cfg.epsilon + cfg.constraint_tolerance
            assert np.all(sol.q >= prob.lbx) and np.all(sol.q <= prob.ubx)
            assert sol.constraint_violation <= 1e-6
            if rot is not None:
                assert math.degrees(sol.orientation_error) < 1.0
            else:
                assert math.isnan(sol.orientation_error)
            # the reported pose is the FK of the reported joints (pinocchio)
            q = solver.full_q(sol)
            np.testing.assert_allclose(model.frame_position(q, prob.chain.frame), sol.position,
                                       atol=1e-9)


def test_orientation_error_decreases_with_its_weight(model, solver):
    """With a strong rest-posture pull, the orientation error shrinks as its weight grows."""
    pulled = IkSolver(model, _cfg(rest_weight=0.5,
                                      rest_joint_weights_arm=(1.0,) * 7))
    T = _targets(model, 1, seed=11)[0]
    errs = [pulled.solve(CHAIN, T.translation, T.rotation, orientation_weight=w).orientation_error
            for w in (0.01, 0.1, 1.0, 10.0)]
    assert all(a > b for a, b in zip(errs, errs[1:])), errs
    assert errs[0] > 5 * errs[-1]


def test_rest_posture_keeps_the_waist_upright(model):
    """When the arm alone can reach (targets made with the torso at 0), the rest-posture term
    with iKin's weights (torso 1, arm 0) keeps the torso upright; without it the torso moves."""
    with_rest = IkSolver(model, _cfg(rest_joint_weights_arm=(0.0,) * 7))
    no_rest = IkSolver(model, _cfg(rest_weight=0.0))
    worst_rest, worst_free = 0.0, 0.0
    for T in _targets(model, 4, seed=5, torso=False):
        a = with_rest.solve(CHAIN, T.translation, T.rotation)
        b = no_rest.solve(CHAIN, T.translation, T.rotation)
        assert a.success and b.success
        worst_rest = max(worst_rest, float(np.abs(a.q[:3]).max()))
        worst_free = max(worst_free, float(np.abs(b.q[:3]).max()))
    assert math.degrees(worst_rest) < 1.0
    assert math.degrees(worst_free) > 5.0


def test_torso_used_when_the_arm_cannot_reach(solver):
    """A point beyond the 7-DoF arm's reach: right_arm fails (and says so), torso_right_arm
    reaches it by bending the waist."""
    target = np.array([-0.35, 0.0, 0.25])
    arm = solver.solve("right_arm", target)
    assert not arm.success
    assert arm.position_error > 5e-3
    assert "not reached" in arm.message
    full = solver.solve(CHAIN, target)
    assert full.success, full.message
    assert math.degrees(np.abs(full.q[:3]).max()) > 3.0


def test_seven_dof_chain_holds_the_torso(model, solver):
    """A 7-DoF solve keeps the torso at q_start's values and uses them in the kinematics."""
    q_start = model.posture("rest")
    q_start[model.indices(["torso_pitch", "torso_yaw"])] = [0.3, -0.2]
    T = model.frame_pose(q_start, "r_hand_dh_frame")
    target = T.translation + np.array([0.02, -0.03, 0.02])
    sol = solver.solve("right_arm", target, None, q_start)
    assert sol.success, sol.message
    assert sol.joint_names[0] == "r_shoulder_pitch"
    q = solver.full_q(sol, q_start)
    np.testing.assert_allclose(q[model.indices(["torso_pitch", "torso_yaw"])], [0.3, -0.2])
    assert np.linalg.norm(model.frame_position(q, "r_hand_dh_frame") - target) < 5.1e-4


def test_shoulder_constraints_hold(model, solver):
    """Solutions meet the 7 shoulder/forearm constraints, although the same targets solved
    without them give violating solutions (so the constraints are active)."""
    free = IkSolver(model, _cfg(shoulder_constraints=False))
    chain = KinematicChain.from_name(CHAIN)
    alc = ArmLinearConstraints("right")
    rng = np.random.default_rng(2)
    violated = 0
    for _ in range(6):
        T = model.frame_pose(model.random_q(rng), chain.frame)
        a = solver.solve(CHAIN, T.translation, T.rotation)
        assert alc.violation(chain.joints, a.q) <= 1e-6
        b = free.solve(CHAIN, T.translation, T.rotation)
        violated += alc.violation(chain.joints, b.q) > 1e-3
    assert violated >= 1


def test_left_chains(model, solver):
    """The left chains solve left-hand targets (frame l_hand_dh_frame)."""
    T = _targets(model, 1, seed=3, hand="left")[0]
    for chain in ("torso_left_arm", "left_arm"):
        sol = solver.solve(chain, T.translation, None, model.posture("rest"))
        if chain == "torso_left_arm":
            assert sol.success, sol.message
        assert sol.joint_names[-1] == "l_wrist_yaw"


def test_warm_start_needs_fewer_iterations(model):
    """Starting IPOPT from the previous solution converges in fewer iterations than from rest
    (without the seed: with it both take ~0 IPOPT iterations, see the seed tests below)."""
    solver = IkSolver(model, _cfg(seed_warm_start=False))
    T = _targets(model, 1, seed=8)[0]
    cold = solver.solve(CHAIN, T.translation, T.rotation)
    warm = solver.solve(CHAIN, T.translation, T.rotation, solver.full_q(cold))
    assert warm.success
    assert warm.iterations < cold.iterations


def test_bad_requests_raise(solver):
    """NaN targets, wrong shapes, non-rotations, bad weights and unknown chains raise
    InvalidInput / UnknownName naming the problem."""
    with pytest.raises(InvalidInput, match="position"):
        solver.solve(CHAIN, [np.nan, 0.0, 0.0])
    with pytest.raises(InvalidInput, match="position"):
        solver.solve(CHAIN, [0.1, 0.2])
    with pytest.raises(InvalidInput, match="rotation"):
        solver.solve(CHAIN, [-0.3, 0.1, 0.0], np.ones((3, 3)))
    with pytest.raises(InvalidInput, match="rotation"):
        solver.solve(CHAIN, [-0.3, 0.1, 0.0], np.full((3, 3), np.nan))
    with pytest.raises(InvalidInput, match="orientation_weight"):
        solver.solve(CHAIN, [-0.3, 0.1, 0.0], orientation_weight=-1.0)
    with pytest.raises(InvalidInput, match="epsilon"):
        solver.solve(CHAIN, [-0.3, 0.1, 0.0], epsilon=0.0)
    with pytest.raises(InvalidInput, match="q"):
        solver.solve(CHAIN, [-0.3, 0.1, 0.0], None, np.zeros(3))
    with pytest.raises(UnknownName, match="torso_left_arm"):
        solver.solve("tail", [-0.3, 0.1, 0.0])


def test_unreachable_target_reports_the_residual(solver):
    """A target 2 m away: success False, the residual (> 1 m) and IPOPT's status reported."""
    sol = solver.solve(CHAIN, [-2.0, 0.0, 0.0])
    assert not sol.success
    assert sol.position_error > 1.0
    assert sol.status != "Solve_Succeeded"
    assert "not reached" in sol.message


def test_solve_time_is_bounded(model):
    """With a tiny wall-time budget IPOPT stops early; the solver reports it, no exception.
    (Without the seed: warm-started from it, IPOPT may certify the seed's point before the
    first wall-time check; the seed itself is a fixed number of iterations.)"""
    quick = IkSolver(model, _cfg(max_solve_time=1e-4, seed_warm_start=False))
    T = _targets(model, 1, seed=4)[0]
    sol = quick.solve(CHAIN, T.translation, T.rotation)
    assert sol.status == "Maximum_WallTime_Exceeded"
    assert not sol.converged
    assert np.all(np.isfinite(sol.q))


def test_epsilon_is_a_squared_distance(model, solver):
    """epsilon bounds the squared error: 1e-4 m^2 lets the position error reach 10 mm."""
    T = _targets(model, 1, seed=12)[0]
    loose = solver.solve(CHAIN, T.translation, T.rotation, epsilon=1e-4,
                         orientation_weight=1.0)
    assert loose.position_error <= 0.01 + 1e-6
    tight = solver.solve(CHAIN, T.translation, T.rotation)
    assert tight.position_error <= 5.1e-4


def test_codegen_matches_the_casadi_vm(model, solver):
    """The gcc-compiled NLP gives the same solution as CasADi's virtual machine."""
    compiled = IkSolver(model, _cfg(codegen=True))
    assert compiled.problem(CHAIN).compiled
    T = _targets(model, 1, seed=6)[0]
    a = compiled.solve(CHAIN, T.translation, T.rotation)
    b = solver.solve(CHAIN, T.translation, T.rotation)
    np.testing.assert_allclose(a.q, b.q, atol=1e-6)


def test_reconfigure_keeps_problems_unless_needed(model):
    """Changing epsilon or weights keeps the built NLP; changing IPOPT settings rebuilds it."""
    s = IkSolver(model, _cfg())
    p = s.problem("right_arm")
    s.reconfigure(_cfg(epsilon=1e-6, orientation_weight=2.0))
    assert s.problem("right_arm") is p
    s.reconfigure(_cfg(epsilon=1e-6, max_iter=50))
    assert s.problem("right_arm") is not p


def test_shipped_solver_settings_are_the_defaults():
    """config/cartesian_solver.yaml ships IkConfig's defaults (the iKinCartesianSolver values)."""
    assert IkConfig.from_yaml(config_dir() / "cartesian_solver.yaml", "cartesian_solver") \
        == IkConfig()


@pytest.mark.parametrize(
    "cls, bad",
    [
        (IkConfig, {"epsilon": -1.0}),
        (IkConfig, {"rest_joint_weights_arm": [1.0, 2.0]}),
        (IkConfig, {"max_iter": 0}),
        (MinJerkConfig, {"trajectory_time": 0.05}),
        (MinJerkConfig, {"period": 0.0}),
        (CartesianNodeConfig, {"default_chain": "tail"}),
        (IkConfig, {"epsilonn": 1e-6}),
    ],
)
def test_bad_configs_rejected(cls, bad):
    """Out-of-range or unknown parameters raise ConfigError."""
    with pytest.raises(ConfigError):
        cls.from_dict(bad)


def test_additional_nonlinear_constraint(model):
    """An extra nonlinear constraint (hand x axis pointing down: R[2, 0] <= -0.9, a 'palm
    orientation' limit) holds at the solution of a position-only request, whereas the solution
    without it violates it; a malformed constraint is rejected."""


    from icub_pmp.cartesian import NlpConstraint

    def x_axis_down(q_fk, kin):
        _, R = kin.function(q_fk)
        return R[2, 0]

    target = np.array([-0.25, 0.20, 0.05])
    plain = IkSolver(model, _cfg()).solve(CHAIN, target)
    assert plain.success and plain.rotation[2, 0] > -0.9
    c = NlpConstraint("x_axis_down", x_axis_down, [-np.inf], [-0.9])
    solver = IkSolver(model, _cfg(), constraints={CHAIN: [c]})
    sol = solver.solve(CHAIN, target)
    assert sol.success, sol.message
    assert sol.rotation[2, 0] <= -0.9 + 1e-6
    assert sol.constraint_violation <= 1e-6
    bad = NlpConstraint("two_rows", lambda q, k: ca.vertcat(q[0], q[1]), [0.0], [1.0])
    with pytest.raises(InvalidInput, match="two_rows"):
        IkSolver(model, _cfg(), constraints={CHAIN: [bad]}).problem(CHAIN)
    with pytest.raises(UnknownName):
        IkSolver(model, _cfg(), constraints={"tail": [c]})


def test_lifted_form_solves_eq11_itself(model, solver):
    """The NLP keeps the position error as variables s (x_d - K_x(q) - s = 0, ||s||^2 <=
    epsilon). IPOPT's answers are KKT points of eq 11 as written (||x_d - K_x(q)||^2 <=
    epsilon): s equals the hand's error, and with IPOPT's multipliers the gradient of eq 11's
    own Lagrangian vanishes (to IPOPT's tolerance), the bound multiplier being >= 0."""


    from icub_pmp.cartesian.nlp_scaling import POSITION_SCALE

    prob = solver.problem(CHAIN)
    n, m = prob.chain.n, prob.n_linear
    x_d = prob.p[prob.layout.x_d]
    g_direct = ca.vertcat(POSITION_SCALE * ca.sumsqr(x_d - prob.fk_position),
                          ca.DM(prob.linear.C) @ prob.q)
    derivatives = ca.Function("eq11_direct", [prob.q, prob.p],
                              [ca.gradient(prob.f, prob.q), ca.jacobian(g_direct, prob.q)])
    eps = solver.config.epsilon
    lbx, ubx = prob.x_bounds
    lbg, ubg = prob.g_bounds(eps)
    q_rest = model.posture("rest")[model.indices(prob.chain.joints)]
    for T in _targets(model, 3, seed=21):
        for rot in (None, T.rotation):
            p = prob.parameters(T.translation, rot, solver.config.orientation_weight,
                                solver.rest_weights(prob.chain), q_rest, np.zeros(0))
            res = prob.solver(x0=prob.start(q_rest, p), p=p, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
            assert prob.solver.stats()["success"]
            x = np.array(res["x"]).reshape(-1)
            q, s = x[:n], x[n:]
            lam_g = np.array(res["lam_g"]).reshape(-1)
            lam_x = np.array(res["lam_x"]).reshape(-1)[:n]
            pos, _ = prob.kinematics.pose(q)
            np.testing.assert_allclose(s, T.translation - pos, atol=1e-6)
            assert lam_g[3] >= 0.0  # multiplier of the bound on the squared error
            grad_f, jac_g = (np.array(v) for v in derivatives(q, p))
            lam_direct = lam_g[3 : 4 + m]  # the same multipliers serve eq 11's direct form
            stationarity = grad_f.reshape(-1) + jac_g.T @ lam_direct + lam_x
            assert np.abs(stationarity).max() <= 10 * solver.config.tol, stationarity


# ---------------------------------------------------------------------------- the seed
# The warm-start seed (icub_pmp.cartesian.ik_seed.IkSeed): the answer is always IPOPT's; the
# seed (a fixed-iteration Newton method on eq 11) only gives the warm-started IPOPT its starting
# point and multipliers, with IPOPT from the start joints as the fallback. `solver` runs with
# the seed (the default), `plain` without.


@pytest.fixture(scope="module")
def plain(model) -> IkSolver:
    return IkSolver(model, _cfg(seed_warm_start=False))


def _objective(solver, rot):
    """Eq 11's objective at joints q for the solver's weights, as a function of (q, target)."""
    prob = solver.problem(CHAIN)
    f = ca.Function("f", [prob.q, prob.p], [prob.f])
    q_rest = solver.model.posture("rest")[solver.model.indices(prob.chain.joints)]

    def value(q, T):
        p = prob.parameters(T.translation, None if rot is None else T.rotation,
                            solver.config.orientation_weight, solver.rest_weights(prob.chain),
                            q_rest, np.zeros(0))
        return float(f(q, p))

    return value


def test_seeded_answers_meet_eq11_and_match_ipopt_from_rest(model, solver, plain):
    """On random reachable targets (position and pose) the seeded solver's answers are
    warm-started IPOPT answers (most of them), meet eq 11's constraints (squared position error
    within epsilon + IPOPT's tolerance, joint limits, shoulder constraints), reach 1 deg with
    orientation, have an objective no worse than IPOPT's from rest (1e-6 + 1 %) and need fewer
    IPOPT iterations in total."""
    seeded = solver
    cfg = seeded.config
    prob = seeded.problem(CHAIN)
    n_seeded, its_seeded, its_plain = 0, 0, 0
    for T in _targets(model, 6, seed=31):
        for rot in (None, T.rotation):
            a = seeded.solve(CHAIN, T.translation, rot)
            b = plain.solve(CHAIN, T.translation, rot)
            assert a.success and b.success, (a.message, b.message)
            assert a.position_error ** 2 <= cfg.epsilon + cfg.constraint_tolerance
            assert np.all(a.q >= prob.lbx) and np.all(a.q <= prob.ubx)
            assert a.constraint_violation <= 1e-6
            if rot is not None:
                assert math.degrees(a.orientation_error) < 1.0
            f = _objective(seeded, rot)
            fa, fb = f(a.q, T), f(b.q, T)
            assert fa <= fb * 1.01 + 1e-6, (fa, fb)
            n_seeded += a.seeded
            its_seeded += a.iterations
            its_plain += b.iterations
            assert not b.seeded
    assert n_seeded >= 6  # of 12
    assert its_seeded < its_plain


def test_seed_point_is_a_local_minimum_of_eq11(model, solver):
    seeded = solver
    """On a position target the seed alone ends within 1 mm of the target, inside the joint
    limits, with s on the epsilon ball and a positive multiplier on it, and passes its
    second-order check; IPOPT warm-started there needs at most 3 iterations."""
    prob = seeded.problem(CHAIN)
    T = _targets(model, 1, seed=32)[0]
    q_rest = model.posture("rest")[model.indices(prob.chain.joints)]
    p = prob.parameters(T.translation, None, 1.0, seeded.rest_weights(prob.chain), q_rest,
                        np.zeros(0))
    eps = seeded.config.epsilon
    x0, lam_x, lam_g, perr, minimum = seeded.seed(CHAIN)(q_rest, p, eps)
    n = prob.chain.n
    assert perr <= 1e-3 and minimum
    assert np.all(x0[:n] >= prob.lbx) and np.all(x0[:n] <= prob.ubx)
    assert np.linalg.norm(x0[n:]) == pytest.approx(math.sqrt(eps), rel=1e-9)
    assert lam_g[3] > 0.0
    sol = seeded.solve(CHAIN, T.translation)
    assert sol.seeded and sol.success
    assert sol.iterations <= 3


def test_a_seed_that_misses_falls_back_to_ipopt_from_the_start(solver, plain):
    seeded = solver
    """An unreachable target: the seed cannot reach it, IPOPT runs from the start joints as
    without the seed: the same answer (the residual reported, success False)."""
    a = seeded.solve(CHAIN, [-2.0, 0.0, 0.0])
    b = plain.solve(CHAIN, [-2.0, 0.0, 0.0])
    assert not a.seeded and not a.success
    np.testing.assert_allclose(a.q, b.q, atol=1e-9)
    assert a.position_error == pytest.approx(b.position_error, abs=1e-9)
    assert "not reached" in a.message


def test_seed_starts_from_the_given_joints(model, solver, plain):
    seeded = solver
    """The node's warm start: from the previous answer (joints at or ~1e-8 rad inside their
    limits) the seed stays there: the seeded solve returns (nearly) the same joints, seeded,
    with at most 2 IPOPT iterations (also from the answer of IPOPT without the seed)."""
    T = _targets(model, 1, seed=33)[0]
    first = seeded.solve(CHAIN, T.translation, T.rotation)
    again = seeded.solve(CHAIN, T.translation, T.rotation, seeded.full_q(first))
    assert again.success and again.seeded and again.iterations <= 2
    np.testing.assert_allclose(again.q, first.q, atol=1e-3)
    T = _targets(model, 1, seed=8)[0]  # its IPOPT answer has joints 3e-8 rad from a limit
    ref = plain.solve(CHAIN, T.translation, T.rotation)
    again = seeded.solve(CHAIN, T.translation, T.rotation, plain.full_q(ref))
    assert again.success and again.seeded and again.iterations <= 2
    np.testing.assert_allclose(again.q, ref.q, atol=1e-3)


def test_compiled_seed_matches_the_casadi_vm(model, solver):
    seeded = solver
    """The gcc-compiled seed gives the same point and multipliers as CasADi's VM."""
    compiled = IkSolver(model, _cfg(codegen=True)).seed(CHAIN)
    assert compiled.compiled
    prob = seeded.problem(CHAIN)
    T = _targets(model, 1, seed=34)[0]
    q_rest = model.posture("rest")[model.indices(prob.chain.joints)]
    p = prob.parameters(T.translation, T.rotation, 1.0, seeded.rest_weights(prob.chain), q_rest,
                        np.zeros(0))
    a = compiled(q_rest, p, 2.5e-7)
    b = seeded.seed(CHAIN)(q_rest, p, 2.5e-7)
    for u, v in zip(a[:3], b[:3]):
        np.testing.assert_allclose(u, v, atol=1e-8)
    assert a[3] == pytest.approx(b[3], abs=1e-9) and a[4] == b[4]
