"""The DLS baseline (icub_pmp.baselines.DlsSolver): one solver for the PMP comparison (several
hands, position targets) and the Cartesian comparison (one chain, position or pose)."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.baselines import PMP_DLS_CONFIG, DlsConfig, DlsSolver
from icub_pmp.cartesian import KinematicChain
from icub_pmp.errors import ConfigError, InvalidInput
from icub_pmp.kinematics import IcubModel
from icub_pmp.pmp import PinocchioJacobianProvider

CHAIN = "torso_right_arm"


@pytest.fixture(scope="module")
def provider():
    return PinocchioJacobianProvider(IcubModel())


@pytest.fixture(scope="module")
def rest(provider):
    return provider.icub.posture("rest")


def _reachable_pose(provider, seed):
    """A hand pose of the chain reached by a configuration within the joint limits."""
    chain = KinematicChain.from_name(CHAIN)
    idx = [provider.joint_names.index(j) for j in chain.joints]
    rng = np.random.default_rng(seed)
    q = provider.icub.posture("rest")
    q[idx] = rng.uniform(provider.lower[idx], provider.upper[idx])
    kin = provider.kinematics(q, [chain.frame])
    return kin.positions[0], kin.rotations[0]


def test_chain_pose_target_is_reached_within_the_tolerances(provider):
    """DLS reaches a reachable pose within its tolerances and fails (flagged) when the target
    is out of reach."""
    dls = DlsSolver(provider)
    x, R = _reachable_pose(provider, seed=9)
    sol = dls.solve_chain(CHAIN, x, R)
    assert sol.success and sol.converged and sol.status == "Solve_Succeeded"
    assert sol.position_error <= dls.config.position_tolerance
    assert sol.orientation_error <= dls.config.orientation_tolerance
    assert sol.joint_names == KinematicChain.from_name(CHAIN).joints
    far = dls.solve_chain(CHAIN, [-2.0, 0.0, 0.0])
    assert not far.success and far.position_error > 1.0


def test_bimanual_position_targets_with_the_pmp_settings(provider, rest):
    """Both hands reach targets that a configuration within the limits reaches; only the
    listed joints move and every joint stays within its limits."""
    spec = provider.icub.spec
    joints = spec.torso_joints + spec.left_arm_joints + spec.right_arm_joints
    frames = [spec.hand_frame("left"), spec.hand_frame("right")]
    idx = [provider.joint_names.index(j) for j in joints]
    rng = np.random.default_rng(17)
    q = rest.copy()
    q[idx] = rng.uniform(provider.lower[idx], provider.upper[idx])
    targets = provider.positions(q, frames)
    sol = DlsSolver(provider, PMP_DLS_CONFIG).solve(rest, joints, frames, targets)
    assert sol.success and sol.position_errors.max() <= 1e-3
    others = np.setdiff1d(np.arange(provider.nq), idx)
    np.testing.assert_array_equal(sol.q[others], rest[others])
    assert np.all(sol.q >= provider.lower - 1e-12) and np.all(sol.q <= provider.upper + 1e-12)
    assert np.isnan(sol.orientation_error)


def test_stall_stop_ends_an_unreachable_solve_early(provider, rest):
    """With stall_iterations, an out-of-reach target stops long before max_iter, flagged."""
    spec = provider.icub.spec
    frames = [spec.hand_frame("right")]
    sol = DlsSolver(provider, PMP_DLS_CONFIG).solve(
        rest, spec.right_arm_joints, frames, [[-2.0, 0.0, 0.0]])
    assert sol.status == "Stalled" and not sol.success
    assert sol.iterations < PMP_DLS_CONFIG.max_iter


def test_bad_inputs_are_rejected_by_name(provider, rest):
    dls = DlsSolver(provider)
    frames = [provider.icub.spec.hand_frame("right")]
    with pytest.raises(InvalidInput, match="positions"):
        dls.solve(rest, ["r_elbow"], frames, [np.nan, 0.0, 0.0])
    with pytest.raises(InvalidInput, match="not joints"):
        dls.solve(rest, ["r_knee"], frames, [0.0, 0.0, 0.0])
    with pytest.raises(InvalidInput, match="rotation"):
        dls.solve(rest, ["r_elbow"], frames, [0.0, 0.0, 0.0], [np.ones((3, 3))])
    with pytest.raises(ConfigError, match="damping"):
        DlsConfig(damping=0.0)
    with pytest.raises(ConfigError, match="stall_iterations"):
        DlsConfig(stall_iterations=-1)
