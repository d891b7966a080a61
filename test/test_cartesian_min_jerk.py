"""The minimum-jerk filter (Pattacini et al. 2010 LTI form) and the multi-referential
trajectory generator (icub_pmp.cartesian.MinJerkGenerator)."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.cartesian import (
    KinematicChain,
    MinJerkConfig,
    MinJerkFilter,
    MinJerkGenerator,
)
from icub_pmp.errors import InvalidInput

CHAIN = "torso_right_arm"


@pytest.fixture(scope="module")
def chain() -> KinematicChain:
    return KinematicChain.from_name(CHAIN)


def _step_response(T: float, Ts: float, seconds: float) -> np.ndarray:
    f = MinJerkFilter(1, T, Ts)
    x, out = 0.0, []
    for _ in range(int(round(seconds / Ts))):
        x += Ts * f.step(np.array([1.0 - x]))[0]
        out.append(x)
    return np.array(out)


@pytest.mark.parametrize("T, Ts", [(0.5, 0.001), (2.0, 0.01)])
def test_filter_reaches_90_percent_at_T(T, Ts):
    """Closed on an ideal integrator, the filter covers 90 % of a step at t = T (+-1.5 %),
    more than 98 % at 1.5 T, and overshoots by less than 0.01 %."""
    x = _step_response(T, Ts, 4 * T)
    assert abs(x[int(round(T / Ts)) - 1] - 0.90) < 0.015
    assert x[int(round(1.5 * T / Ts)) - 1] > 0.98
    assert x.max() < 1.0001


def test_filter_profile_is_bell_shaped():
    """The velocity of a step response starts at 0, peaks once near T/3 .. T/2, ends at 0."""
    Ts, T = 0.01, 2.0
    x = _step_response(T, Ts, 3 * T)
    v = np.diff(np.concatenate([[0.0], x])) / Ts
    k = int(np.argmax(v))
    assert v[0] == 0.0
    assert 0.25 * T < k * Ts < 0.5 * T
    assert np.all(np.diff(v[:k]) >= -1e-12) and np.all(np.diff(v[k:]) <= 1e-12)
    assert v[-1] < 1e-3 * v[k]


def test_filter_rejects_bad_times():
    """T below 10 Ts (iKin's lower bound) and non-positive Ts are rejected."""
    with pytest.raises(InvalidInput):
        MinJerkFilter(3, 0.05, 0.01)
    with pytest.raises(InvalidInput):
        MinJerkFilter(3, 2.0, 0.0)


def _goal(solver, chain, seed=0):
    model = solver.model
    q0 = model.posture("rest")
    target = model.frame_position(q0, chain.frame) + np.array([0.08, -0.05, 0.10])
    sol = solver.solve(chain.name, target, None, q0)
    assert sol.success
    return q0, sol


def test_generator_reaches_the_solution(model, chain, vm_ik_solver):
    """The rollout starts at q0 at rest, ends at q_d (within the settle tolerance) at rest,
    and the hand ends at K(q_d); 90 % of the hand distance is covered near T."""
    q0, sol = _goal(vm_ik_solver, chain)
    gen = MinJerkGenerator(model, chain)
    gen.reset(q0)
    gen.set_target(sol.q)
    tr = gen.rollout()
    idx = model.indices(chain.joints)
    np.testing.assert_allclose(tr.q[0], q0[idx])
    assert np.abs(tr.q[-1] - sol.q).max() < gen.config.settle_tolerance
    assert np.abs(tr.qd[0]).max() == 0.0 and np.abs(tr.qd[-1]).max() == 0.0
    assert np.linalg.norm(tr.hand_position[-1] - sol.position) < 1e-4
    d0 = np.linalg.norm(tr.hand_position[0] - sol.position)
    dT = np.linalg.norm(tr.hand_position[tr.index_at(gen.T)] - sol.position)
    assert 0.05 < dT / d0 < 0.15
    assert tr.duration <= gen.config.max_duration_factor * gen.T
    assert np.all(tr.q >= model.lower[idx] - 1e-12) and np.all(tr.q <= model.upper[idx] + 1e-12)


def test_generator_is_smooth(model, chain, vm_ik_solver):
    """Velocities change by small amounts per sample (no jumps): the largest change of any
    joint velocity between samples is below 3 % of that joint's peak velocity (the LTI
    min-jerk profile needs about 2.4 % at a 10 ms period with T = 2 s)."""
    q0, sol = _goal(vm_ik_solver, chain)
    gen = MinJerkGenerator(model, chain)
    gen.reset(q0)
    gen.set_target(sol.q)
    tr = gen.rollout()
    peak = np.abs(tr.qd).max(axis=0)
    jump = np.abs(np.diff(tr.qd, axis=0)).max(axis=0)
    moving = peak > 1e-3
    assert np.all(jump[moving] < 0.03 * peak[moving])


def test_retarget_mid_motion_is_smooth(model, chain, vm_ik_solver):
    """A new target at t = 0.8 s continues from the running state: velocity continuous at the
    switch (change no larger than elsewhere), and the motion ends at the new target."""
    q0, sol = _goal(vm_ik_solver, chain)
    solver = vm_ik_solver
    gen = MinJerkGenerator(model, chain)
    gen.reset(q0)
    gen.set_target(sol.q)
    first = gen.rollout()
    t_switch = 0.8
    state = first.state_at(t_switch)
    q_now = q0.copy()
    q_now[model.indices(chain.joints)] = state.q
    new_target = sol.position + np.array([-0.05, 0.10, -0.05])
    sol2 = solver.solve(CHAIN, new_target, None, q_now)
    assert sol2.success
    gen.restore(state)
    gen.set_target(sol2.q)
    second = gen.rollout()
    k = first.index_at(t_switch)
    np.testing.assert_allclose(second.q[0], first.q[k])
    # velocity just before the switch vs just after it
    before = first.qd[k - 1]
    after = second.qd[0]
    typical = np.abs(np.diff(first.qd[: k + 1], axis=0)).max()
    assert np.abs(after - before).max() <= 1.5 * typical + 1e-9
    assert np.abs(second.q[-1] - sol2.q).max() < gen.config.settle_tolerance
    assert np.linalg.norm(second.hand_position[-1] - new_target) < 1e-3


def test_task_coupling_straightens_the_hand_path(model, chain, vm_ik_solver):
    """With a strong task-space coupling (gamma large) the hand path is straighter than with
    the joint-space generator alone (the multi-referential scheme of Fig 8)."""
    q0, sol = _goal(vm_ik_solver, chain)

    def deviation(cfg: MinJerkConfig) -> float:
        gen = MinJerkGenerator(model, chain, cfg)
        gen.reset(q0)
        gen.set_target(sol.q)
        p = gen.rollout().hand_position
        d = (p[-1] - p[0]) / np.linalg.norm(p[-1] - p[0])
        rel = p - p[0]
        return float(np.linalg.norm(rel - np.outer(rel @ d, d), axis=1).max())

    joint_only = deviation(MinJerkConfig(task_space=False))
    coupled = deviation(MinJerkConfig(gamma=50.0))
    assert coupled < 0.5 * joint_only


def test_generator_rejects_bad_targets(model, chain):
    """A target of the wrong size or with NaN is rejected."""
    gen = MinJerkGenerator(model, chain)
    with pytest.raises(InvalidInput):
        gen.set_target(np.zeros(3))
    with pytest.raises(InvalidInput):
        gen.set_target(np.full(10, np.nan))
