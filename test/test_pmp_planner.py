"""The PMP planner on the iCub model: each test asserts a claim of Mohan et al. (2009)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from icub_pmp.baselines import PMP_DLS_CONFIG, DlsSolver
from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics import RobotSpec
from icub_pmp.pmp import (
    HeldObject,
    ObstacleField,
    PmpConfig,
    PmpPlanner,
    ReachGoal,
    TimeBaseGenerator,
)

MM = 1e-3


@pytest.fixture(scope="module")
def planner():
    return PmpPlanner()


@pytest.fixture(scope="module")
def rest(planner):
    return planner.start_configuration(None)


def frames(planner, hands=("left", "right")):
    return [planner.spec.hand_frame(h) for h in hands]


def hand_positions(planner, q, hands=("left", "right")):
    return planner.provider.positions(q, frames(planner, hands))


def random_reachable(planner, rest, rng, hands=("left", "right"), use_torso=True):
    """Targets that a configuration within the joint limits reaches (a solution exists)."""
    joints = list(planner.spec.torso_joints) if use_torso else []
    for h in hands:
        joints += planner.spec.arm_joints(h)
    idx = [planner.provider.joint_names.index(j) for j in joints]
    q = rest.copy()
    q[idx] = rng.uniform(planner.provider.lower[idx], planner.provider.upper[idx])
    return dict(zip(hands, hand_positions(planner, q, hands)))


def target_at_distance(planner, q0, hand, delta, dist):
    """Hand position reached by moving the arm joints ``delta`` (direction, by joint suffix)
    from q0 until the hand is ``dist`` [m] away: reachable by construction."""
    names = planner.provider.joint_names
    start = hand_positions(planner, q0, (hand,))[0]
    lo, hi = 0.0, 3.0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        q = q0.copy()
        for j, v in delta.items():
            q[names.index(f"{hand[0]}_{j}")] += mid * v
        x = hand_positions(planner, q, (hand,))[0]
        lo, hi = (mid, hi) if np.linalg.norm(x - start) < dist else (lo, mid)
    return x


def column(plan, joint):
    return plan.positions[:, plan.joint_names.index(joint)]


# ---------------------------------------------------------------------- terminal attractor
def test_reachable_bimanual_targets_are_hit_at_tau(planner, rest):
    """Sect. 2.4/App. A: with the TBG the hands reach reachable targets at t = tau (within
    1 mm), the trajectory starts at the start posture and its last sample is the equilibrium."""
    rng = np.random.default_rng(11)
    for _ in range(6):
        targets = random_reachable(planner, rest, rng)
        plan = planner.plan(ReachGoal(targets=targets, tau=2.0), rest)
        assert plan.success, plan.message
        assert plan.t[0] == 0.0 and plan.t[-1] == pytest.approx(2.0)
        idx = [planner.provider.joint_names.index(j) for j in plan.joint_names]
        assert np.allclose(plan.positions[0], rest[idx])
        final = hand_positions(planner, plan.q_final)  # independent forward kinematics
        for i, h in enumerate(("left", "right")):
            assert np.linalg.norm(final[i] - targets[h]) <= 1 * MM
            assert plan.residuals[h] <= 1 * MM
        assert np.allclose(plan.velocities[[0, -1]], 0.0)


def test_two_hands_at_3x_distances_arrive_together(planner, rest):
    """Sect. 2.5: one TBG synchronises the branches: a hand with a 3x longer way to go covers
    the same fraction of its path at every instant and both arrive at tau."""
    delta = {"shoulder_pitch": -0.5, "elbow": -0.3, "shoulder_yaw": 0.2}
    targets = {
        "left": target_at_distance(planner, rest, "left", delta, 0.04),
        "right": target_at_distance(planner, rest, "right", delta, 0.12),
    }
    plan = planner.plan(ReachGoal(targets=targets, use_torso=False), rest)
    assert plan.success, plan.message
    fractions = {}
    for h in ("left", "right"):
        path = plan.hand_paths[h]
        seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
        fractions[h] = np.concatenate([[0.0], np.cumsum(seg)]) / seg.sum()
        # only at tau within 1 mm: the hand is still travelling at 0.8 tau
        at_80 = np.linalg.norm(path[np.searchsorted(plan.t, 0.8 * plan.tau)] - targets[h])
        assert at_80 > 1 * MM
    assert np.max(np.abs(fractions["left"] - fractions["right"])) < 0.1
    for h in ("left", "right"):
        arrive = plan.t[np.argmax(fractions[h] >= 0.99)]
        assert arrive > 0.75 * plan.tau


def test_speed_profile_is_bell_shaped_with_peak_near_half_tau(planner, rest):
    """Sect. 2.4, Fig 9: the hand speed rises from zero to a single peak near tau/2 and falls
    back to zero at tau, whatever the distance."""
    x0 = hand_positions(planner, rest, ("right",))[0]
    for dist in (0.06, 0.18):
        target = x0 + dist * np.array([-0.6, 0.0, 0.8])
        plan = planner.plan(ReachGoal(targets={"right": target}, use_torso=True), rest)
        assert plan.success, plan.message
        speed = plan.hand_speed("right")
        peak = int(np.argmax(speed))
        assert abs(plan.t[peak] - plan.tau / 2) < 0.1 * plan.tau
        assert speed[0] < 0.02 * speed[peak] and speed[-1] < 0.02 * speed[peak]
        rising, falling = np.diff(speed[: peak + 1]), np.diff(speed[peak:])
        assert np.all(rising > -0.02 * speed[peak]) and np.all(falling < 0.02 * speed[peak])


# ---------------------------------------------------------------------- internal constraints
def test_joint_limits_are_never_crossed(planner, rest):
    """Eq 6 + the relaxation's boundary rule: no sample of any plan leaves the joint range,
    including plans toward targets out of reach that press the joints against their limits."""
    rng = np.random.default_rng(12)
    goals = [ReachGoal(targets=random_reachable(planner, rest, rng)) for _ in range(4)]
    goals.append(ReachGoal(targets={"right": [-0.9, 0.5, 0.4], "left": [-0.2, -0.9, -0.5]}))
    for goal in goals:
        plan = planner.plan(goal, rest)
        idx = [planner.provider.joint_names.index(j) for j in plan.joint_names]
        lo, hi = planner.provider.lower[idx], planner.provider.upper[idx]
        assert np.all(plan.positions >= lo) and np.all(plan.positions <= hi)


def test_narrowed_wrist_range_changes_the_final_posture(planner, rest):
    """Fig 2 (bottom): the same reach with a narrowed wrist range ends in a different posture
    that respects the narrowed range and still reaches the target."""
    names = planner.provider.joint_names
    qt = rest.copy()
    for j, v in (("r_shoulder_pitch", -0.8), ("r_shoulder_yaw", 0.4), ("r_wrist_pitch", -0.7),
                 ("r_wrist_yaw", 0.3)):
        qt[names.index(j)] = v
    target = hand_positions(planner, qt, ("right",))[0]
    free = planner.plan(ReachGoal(targets={"right": target}, use_torso=False), rest)
    assert free.success, free.message
    wrist = "r_wrist_pitch"
    w_free = column(free, wrist)[-1]
    centre = rest[names.index(wrist)]
    narrow = (centre - 0.02, centre + 0.02)  # a wrist range the free reach goes beyond
    plan = planner.plan(
        ReachGoal(targets={"right": target}, use_torso=False, joint_limits={wrist: narrow}), rest
    )
    assert plan.success, plan.message
    w = column(plan, wrist)
    assert np.all(w > narrow[0]) and np.all(w < narrow[1])
    assert abs(w_free - centre) > 0.02  # the free reach did use the wrist beyond that range
    others = [j for j in plan.joint_names if j != wrist]
    change = max(abs(column(plan, j)[-1] - column(free, j)[-1]) for j in others)
    assert change > 0.02  # the other joints compensate: a different final posture


def test_frozen_joint_does_not_move(planner, rest):
    """Sect. 2.1: freezing a joint through A_int (admittance 0) keeps it still; the other joints
    still bring the hand to the target."""
    rng = np.random.default_rng(13)
    targets = random_reachable(planner, rest, rng, hands=("right",), use_torso=False)
    targets = {"right": hand_positions(planner, rest, ("right",))[0] * 0.6 + 0.4 * targets["right"]}
    plan = planner.plan(
        ReachGoal(targets=targets, use_torso=True, frozen_joints=("r_elbow", "torso_yaw")), rest
    )
    for j in ("r_elbow", "torso_yaw"):
        assert np.all(column(plan, j) == rest[planner.provider.joint_names.index(j)])
    assert plan.success, plan.message
    assert np.ptp(column(plan, "r_shoulder_pitch")) > 0


# ---------------------------------------------------------------------- branching (Fig 7)
def test_trunk_is_recruited_as_targets_move_beyond_reach(planner, rest):
    """Sect. 3.1, Fig 7: with a compliant trunk the trunk motion grows as the targets move away
    and lets the hands reach targets the arms alone (stiff trunk: grounded shoulders) cannot;
    near the body the trunk barely moves."""
    x0 = hand_positions(planner, rest)
    torso = [planner.provider.joint_names.index(j) for j in planner.spec.torso_joints]
    motion, stiff_res, compliant_res = [], [], []
    for d in (0.03, 0.08, 0.13, 0.18):
        targets = {"left": x0[0] + [-d, 0.0, d], "right": x0[1] + [-d, 0.0, d]}
        compliant = planner.plan(ReachGoal(targets=targets, trunk_admittance_scale=1.0), rest)
        stiff = planner.plan(ReachGoal(targets=targets, trunk_admittance_scale=0.0), rest)
        assert np.allclose(stiff.q_final[torso], rest[torso])
        motion.append(float(np.linalg.norm(compliant.q_final[torso] - rest[torso])))
        stiff_res.append(stiff.max_residual)
        compliant_res.append(compliant.max_residual)
    assert np.all(np.diff(motion) > 0), motion
    assert motion[0] < 0.25 * motion[-1], motion
    assert stiff_res[0] <= 1 * MM and compliant_res[0] <= 1 * MM
    beyond = [i for i, r in enumerate(stiff_res) if r > 10 * MM]
    assert beyond, stiff_res  # the far targets are beyond the arms' reach...
    assert all(compliant_res[i] <= 1 * MM for i in beyond)  # ...but not the trunk's


# ---------------------------------------------------------------------- robustness (Sect. 4)
def test_singular_stretched_arm_start_gives_no_nan(planner, rest):
    """Sect. 1/4: the Jacobian-transpose relaxation does not crash at a kinematic singularity:
    from a fully stretched arm (elbow at 0, hand point on the forearm axis: rank-2 position
    Jacobian) the plan is finite and reaches a reachable target."""
    names = planner.provider.joint_names
    arm = [names.index(j) for j in planner.spec.right_arm_joints]
    limits = {"r_elbow": (-0.1, 1.85), "r_wrist_prosup": (-1.2, 2.2),
              "r_wrist_pitch": (-1.4, 1.7), "r_wrist_yaw": (-0.35, 1.7)}
    q = rest.copy()
    q[arm[3:]] = np.radians([0.0, 116.079, 89.999, 88.361])
    jac = planner.provider.kinematics(q, frames(planner, ("right",))).jacobians[0, :3][:, arm]
    assert np.linalg.svd(jac)[1][-1] < 1e-4  # singular start
    qt = q.copy()
    qt[arm[3:]] = [0.9, 0.5, 0.3, 0.2]
    target = hand_positions(planner, qt, ("right",))[0]
    plan = planner.plan(
        ReachGoal(targets={"right": target}, use_torso=False, joint_limits=limits), q
    )
    assert np.all(np.isfinite(plan.positions)) and np.all(np.isfinite(plan.velocities))
    assert plan.success, plan.message
    # and from the iCub's own fully stretched elbow (on its joint limit)
    q2 = rest.copy()
    q2[names.index("r_elbow")] = planner.provider.lower[names.index("r_elbow")]
    q2[names.index("r_shoulder_pitch")] = -1.2
    plan2 = planner.plan(ReachGoal(targets={"right": target}, use_torso=True), q2)
    assert np.all(np.isfinite(plan2.positions)) and plan2.success, plan2.message


def test_out_of_reach_target_ends_at_the_closest_reachable_point(planner, rest):
    """Sect. 2.1 (Fig 1, target B), Sect. 4: for a target outside the workspace the relaxation
    ends where the hand is as close as the body allows (checked against a brute-force search
    of 60,000 arm postures), answers success=False and reports the residual distance."""
    target = np.array([-0.55, 0.45, 0.25])
    plan = planner.plan(ReachGoal(targets={"right": target}, use_torso=False), rest)
    assert not plan.success
    assert "out of reach" in plan.message
    names = planner.provider.joint_names
    arm = [names.index(j) for j in planner.spec.right_arm_joints]
    rng = np.random.default_rng(14)
    fr = frames(planner, ("right",))
    q = rest.copy()
    best, best_x = np.inf, None
    for sample in rng.uniform(planner.provider.lower[arm], planner.provider.upper[arm],
                              size=(60000, 7)):
        q[arm] = sample
        x = planner.provider.positions(q, fr)[0]
        d = np.linalg.norm(x - target)
        if d < best:
            best, best_x = d, x
    residual = plan.residuals["right"]
    assert residual > 0.05  # really out of reach
    assert residual <= best + 1 * MM  # at least as close as the best sampled posture
    assert np.linalg.norm(plan.hand_paths["right"][-1] - best_x) < 0.02  # the same place


def test_torque_limits_respected_after_null_space_settling(rest):
    """Sect. 2.3, Fig 3: after reaching, with the target force applied and a weak wrist, the
    saturation block lets the arm settle in the null space into a posture whose joint
    torques (J^T F_T + gravity) are within every rating, the hand still on the target. A
    feasible posture exists: found here among DLS solutions from random starts."""
    spec = RobotSpec.load()
    planner0 = PmpPlanner(spec=spec)
    names = planner0.provider.joint_names
    arm = [names.index(j) for j in spec.right_arm_joints]
    fr = [spec.hand_frame("right")]
    target = planner0.provider.positions(rest, fr)[0] + [-0.04, 0.0, 0.04]
    force = np.array([0.0, 0.0, -20.0])  # the hand presses down with 20 N
    limits = dict(spec.torque_limits)
    limits["r_wrist_yaw"] = 0.5  # a weak wrist motor [N m]
    weak = dataclasses.replace(spec, torque_limits=limits)
    rating = np.array([limits[j] for j in names])
    plain = planner0.plan(ReachGoal(targets={"right": target}, use_torso=False), rest)
    tau_plain = planner0.provider.static_torques(plain.q_final, fr, force[None], True)
    assert np.max(np.abs(tau_plain[arm]) / rating[arm]) > 1.0  # plain PMP violates
    dls = DlsSolver(planner0.provider, PMP_DLS_CONFIG)
    rng = np.random.default_rng(15)
    feasible = 0
    for _ in range(60):
        q = rest.copy()
        q[arm] = rng.uniform(planner0.provider.lower[arm], planner0.provider.upper[arm])
        sol = dls.solve(q, spec.right_arm_joints, fr, target[None])
        tau = planner0.provider.static_torques(sol.q, fr, force[None], True)
        feasible += sol.success and np.all(np.abs(tau[arm]) <= 0.95 * rating[arm])
    assert feasible > 0
    plan = PmpPlanner(spec=weak).plan(
        ReachGoal(targets={"right": target}, use_torso=False, target_forces={"right": force}),
        rest,
    )
    tau = planner0.provider.static_torques(plan.q_final, fr, force[None], True)
    assert np.all(np.abs(tau[arm]) <= rating[arm]), tau[arm]
    assert plan.torque_ratio <= 1.0 and plan.success, plan.message
    assert plan.residuals["right"] <= 1 * MM


# ---------------------------------------------------------------------- extensions
def test_held_object_keeps_the_grasp_during_transport(planner, rest):
    """Sect. 3.2, Fig 8: the goal pulls the object, the object pulls both hands: the hands
    carry it to the goal keeping their distance within 5 mm along the whole trajectory."""
    x0 = hand_positions(planner, rest)
    x0 = x0 + np.array([[0.0, 0.08, 0.0], [0.0, -0.08, 0.0]])  # a 25 cm box held in front
    q = planner.plan(ReachGoal(targets={"left": x0[0], "right": x0[1]}), rest).q_final
    grasp = hand_positions(planner, q)
    goal = grasp.mean(axis=0) + np.array([-0.06, 0.05, 0.12])
    obj = HeldObject.between_hands({"left": grasp[0], "right": grasp[1]}, goal)
    plan = planner.plan(ReachGoal(held_object=obj), q)
    assert plan.success, plan.message
    gap = np.linalg.norm(plan.hand_paths["left"] - plan.hand_paths["right"], axis=1)
    assert np.max(np.abs(gap - np.linalg.norm(grasp[0] - grasp[1]))) < 5 * MM
    assert np.linalg.norm(plan.object_path[-1] - goal) < 1 * MM
    assert np.linalg.norm(plan.hand_paths["left"][-1] - (goal + grasp[0] - grasp.mean(0))) < MM


def test_obstacle_field_keeps_the_path_outside_the_obstacle(planner, rest):
    """Sect. 2.3: a repulsive field around an obstacle placed on the free path keeps the hand
    path out of it, and the hand still reaches the target (the paper's field on the end
    effector alone, ``obstacle_body_links`` empty: the arm's own volume, which this obstacle
    on the hand's way does not leave room for, is test_pmp_body_volume.py's)."""
    planner = PmpPlanner(dataclasses.replace(planner.config, obstacle_body_links=()),
                         provider=planner.provider)
    names = planner.provider.joint_names
    qt = rest.copy()
    for j, v in (("r_shoulder_pitch", -1.3), ("r_shoulder_roll", 0.3), ("r_elbow", 0.5),
                 ("r_shoulder_yaw", 0.3)):
        qt[names.index(j)] = v
    target = hand_positions(planner, qt, ("right",))[0]
    free = planner.plan(ReachGoal(targets={"right": target}, use_torso=False), rest)
    centre = free.hand_paths["right"][len(free.t) // 2] + [0.0, 0.01, 0.0]
    obstacle = ObstacleField(centre, radius=0.03, influence=0.03, gain=1e-3)
    assert obstacle.clearance(free.hand_paths["right"]).min() < 0  # the free path hits it
    plan = planner.plan(
        ReachGoal(targets={"right": target}, use_torso=False, obstacles=(obstacle,)), rest
    )
    assert obstacle.clearance(plan.hand_paths["right"]).min() > 0
    assert plan.success, plan.message


def test_orientation_target_is_reached_with_position(planner, rest):
    """Eq 1 with a rotational field on the hand frame: position and orientation both reached."""
    rng = np.random.default_rng(16)
    names = planner.provider.joint_names
    arm = [names.index(j) for j in planner.spec.right_arm_joints]
    q = rest.copy()
    q[arm] = rest[arm] + rng.uniform(-0.3, 0.3, 7)
    kin = planner.provider.kinematics(q, frames(planner, ("right",)))
    goal = ReachGoal(targets={"right": kin.positions[0]}, orientations={"right": kin.rotations[0]},
                     use_torso=False)
    plan = planner.plan(goal, rest)
    assert plan.success, plan.message
    assert plan.rotation_residuals["right"] <= 0.01 and plan.residuals["right"] <= 1 * MM


# ---------------------------------------------------------------------- soundness of the TBG
def test_relaxation_converges_to_the_literal_eq_4a_integration():
    """The divergent Gamma(t) is handled by integrating in s = -ln(1 - xi) (ds = Gamma dt). In
    the 'gamma' parametrisation the plan (default steps) equals a 0.2 ms explicit Euler
    integration of eq 4a, q_dot = Gamma(t) A (J^T F + T_int), to within 10 mm at 0.75 tau, and
    the difference shrinks (first order) as the relaxation step shrinks (the paper's network:
    no per-hand synchronisation feedback)."""
    errors = []
    default = PmpConfig()
    for h0, growth in ((default.initial_step, default.step_growth), (0.02, 1.1)):
        cfg = PmpConfig(time_parametrisation="gamma", initial_step=h0, step_growth=growth,
                        max_steps=2000, posture_memory_size=0, synchronise_hands=0.0)
        pl = PmpPlanner(cfg)
        q0 = pl.start_configuration(None)
        x0 = hand_positions(pl, q0)
        goal = ReachGoal(targets={"left": x0[0] + [-0.08, 0.05, 0.1],
                                  "right": x0[1] + [-0.05, -0.1, 0.05]})
        plan = pl.plan(goal, q0)
        assert plan.success, plan.message
        net = pl.build_network(goal, q0)
        trace = pl._relax.run(net)  # also balances net's fields exactly as plan() did
        a = net.admittance * trace.rate_scale
        tbg = TimeBaseGenerator(plan.tau)
        z, dt, t_end = net.initial_state(), 2e-4, 0.75 * plan.tau
        for t in np.arange(0.0, t_end - 1e-12, dt):
            st = net.evaluate(z)
            z = z + dt * float(tbg.gamma(t + dt / 2)) * a * (st.jacobian.T @ st.force + st.torque)
        euler = net.hand_positions(z)
        i = int(np.argmin(np.abs(plan.t - t_end)))
        planned = np.array([plan.hand_paths[h][i] for h in plan.hands])
        errors.append(float(np.linalg.norm(euler - planned, axis=1).max()))
    assert errors[0] < 10 * MM and errors[1] < 0.5 * errors[0], errors


def test_gamma_parametrisation_also_reaches_at_tau(rest):
    """Eq 7 taken literally (Appendix A: z = z0 (1 - xi)^gamma): the distance to the target
    never grows, and the target is reached at tau."""
    pl = PmpPlanner(PmpConfig(time_parametrisation="gamma"))
    x0 = hand_positions(pl, rest, ("right",))[0]
    target = x0 + [-0.05, 0.05, 0.08]
    plan = pl.plan(ReachGoal(targets={"right": target}), rest)
    dist = np.linalg.norm(plan.hand_paths["right"] - target, axis=1)
    assert plan.success and dist[-1] <= 1 * MM
    assert np.all(np.diff(dist) <= 1e-4)


# ---------------------------------------------------------------------- API
def test_bad_goals_raise_clear_errors(planner, rest):
    """NaN targets, unknown hands/joints, tau <= 0 and a start far outside the limits raise
    InvalidInput/UnknownName naming the problem; nothing is planned."""
    with pytest.raises(InvalidInput, match="NaN"):
        ReachGoal(targets={"right": [np.nan, 0.0, 0.0]})
    with pytest.raises(InvalidInput, match="tau"):
        ReachGoal(targets={"right": [0.0, 0.0, 0.0]}, tau=0.0)
    with pytest.raises(InvalidInput, match="no hand"):
        ReachGoal(targets={})
    with pytest.raises(InvalidInput, match="farther"):
        ReachGoal(targets={"left": [1e200, 0.0, 0.0]})
    with pytest.raises(InvalidInput, match="max_tau"):
        planner.plan(ReachGoal(targets={"right": [-0.3, 0.2, 0.0]}, tau=1e6), rest)
    with pytest.raises(UnknownName, match="head"):
        planner.plan(ReachGoal(targets={"head": [0.0, 0.0, 0.0]}), rest)
    with pytest.raises(UnknownName, match="r_knee"):
        planner.plan(ReachGoal(targets={"right": [-0.3, 0.2, 0.0]}, frozen_joints=("r_knee",)))
    q = rest.copy()
    q[planner.provider.joint_names.index("r_elbow")] = 3.0
    with pytest.raises(InvalidInput, match="r_elbow"):
        planner.plan(ReachGoal(targets={"right": [-0.3, 0.2, 0.0]}), q)


def test_synchronise_hands_option_brings_the_hands_in_step(rest):
    """Extension (synchronise_hands > 0): re-weighting each hand's field by its relative lag
    makes both hands cover the same fraction of their paths at each instant more closely than
    the TBG alone, with the same verdicts."""

    def lag(planner, targets):
        plan = planner.plan(ReachGoal(targets=targets), rest)
        assert plan.success, plan.message
        fractions = []
        for h in plan.hands:
            seg = np.linalg.norm(np.diff(plan.hand_paths[h], axis=0), axis=1)
            fractions.append(np.concatenate([[0.0], np.cumsum(seg)]) / seg.sum())
        return float(np.max(np.abs(fractions[0] - fractions[1])))

    plain = PmpPlanner(PmpConfig(posture_memory_size=0))
    synced = PmpPlanner(PmpConfig(posture_memory_size=0, synchronise_hands=2.0))
    rng = np.random.default_rng(18)
    lags_plain, lags_synced = [], []
    while len(lags_plain) < 6:
        targets = random_reachable(plain, rest, rng)
        if not plain.plan(ReachGoal(targets=targets), rest).success:
            continue
        lags_plain.append(lag(plain, targets))
        lags_synced.append(lag(synced, targets))
    assert np.mean(lags_synced) < 0.8 * np.mean(lags_plain), (lags_plain, lags_synced)
