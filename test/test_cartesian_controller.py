"""CartesianController: the go-to-pose core of the cartesian_solver node (eq 11 + the min-jerk
rollout, continuing the running trajectory)."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.cartesian import CartesianController, MinJerkConfig
from icub_pmp.errors import InvalidInput

CHAIN = "torso_right_arm"
TARGET_A = np.array([-0.30, 0.15, 0.05])  # root_link [m]
TARGET_B = np.array([-0.25, 0.20, 0.12])


@pytest.fixture
def controller(vm_ik_solver) -> CartesianController:
    return CartesianController(vm_ik_solver, MinJerkConfig(trajectory_time=1.0))


@pytest.fixture(scope="module")
def measured(model) -> dict[str, float]:
    return dict(model.spec.posture("rest"))


def test_a_goal_is_solved_and_rolled_out_from_the_measured_joints(controller, measured):
    motion = controller.go_to(CHAIN, TARGET_A, None, now=10.0, measured=measured)
    assert motion.solution.success and not motion.continued
    traj = motion.trajectory
    idx = controller.model.indices(traj.joint_names)
    np.testing.assert_allclose(traj.q[0], controller.model.posture("rest")[idx], atol=1e-9)
    np.testing.assert_allclose(traj.q[-1], motion.solution.q, atol=2e-3)
    assert np.linalg.norm(traj.hand_position[-1] - TARGET_A) < 5e-3
    assert controller.active is motion and motion.start_time == 10.0


def test_a_goal_during_the_motion_continues_the_running_trajectory(controller, measured):
    """Half-way through, a new goal starts from the running trajectory's state at that time
    (same joints, same velocity): no jump, no restart from rest."""
    first = controller.go_to(CHAIN, TARGET_A, None, now=10.0, measured=measured)
    elapsed = first.trajectory.duration / 2
    second = controller.go_to(CHAIN, TARGET_B, None, now=10.0 + elapsed, measured=measured)
    assert second.continued and second.solution.success
    k = first.trajectory.index_at(elapsed)
    np.testing.assert_allclose(second.trajectory.q[0], first.trajectory.q[k], atol=1e-12)
    np.testing.assert_allclose(second.trajectory.qd[0], first.trajectory.qd[k], atol=1e-9)
    assert np.linalg.norm(second.trajectory.qd[0]) > 1e-3  # it was moving


def test_after_the_motion_or_with_a_start_state_a_goal_starts_afresh(controller, measured):
    first = controller.go_to(CHAIN, TARGET_A, None, now=0.0, measured=measured)
    late = controller.go_to(CHAIN, TARGET_B, None, now=first.trajectory.duration + 1.0,
                            measured=measured)
    assert not late.continued
    explicit = controller.go_to(CHAIN, TARGET_A, None, now=late.start_time + 0.1,
                                measured=measured, start_state={"r_elbow": 1.0})
    assert not explicit.continued
    assert explicit.q_start[controller.model.indices(["r_elbow"])][0] == 1.0


def test_an_unreachable_goal_moves_nothing(controller, measured):
    first = controller.go_to(CHAIN, TARGET_A, None, now=0.0, measured=measured)
    far = controller.go_to(CHAIN, [-2.0, 0.0, 0.0], None, now=0.1, measured=measured)
    assert not far.solution.success and far.trajectory is None
    assert controller.active is first


def test_bad_goals_are_refused_by_name(controller):
    with pytest.raises(InvalidInput, match="trajectory_time"):
        controller.go_to(CHAIN, TARGET_A, None, now=0.0, trajectory_time=0.05,
                         measured={"r_elbow": 0.5})
    with pytest.raises(InvalidInput, match="no /joint_states"):
        controller.go_to(CHAIN, TARGET_A, None, now=0.0)
    assert controller.trajectory_time(0.0) == controller.config.trajectory_time
