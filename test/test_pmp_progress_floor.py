"""The progress timing's joint floor (``progress_joint_floor``, decision 0061): a carry to the
edge of the workspace, whose last relaxation nodes turn ``shoulder_yaw`` while the hand barely
moves, is no longer squeezed into the last instants of the reach; the path is the same."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from icub_pmp.control.trajectory_limits import JointRateLimits, JointTrajectory
from icub_pmp.errors import ConfigError, InvalidInput
from icub_pmp.pmp import PmpConfig, PmpPlanner, ReachGoal, TimeBaseGenerator
from icub_pmp.pmp.tbg_timing import TbgTiming

WRISTS = tuple(f"{s}_wrist_{j}" for s in "lr" for j in ("prosup", "pitch", "yaw"))
#: the tabletop task's first round (decision 0061's trace): onto two cubes, lift, and the
#: carry of each to its target area at y = +-0.26, at the edge of the frozen-wrist arms' reach
ROUND = ({"left": (-0.28, -0.14, -0.035), "right": (-0.28, 0.14, -0.035)},
         {"left": (-0.282, -0.144, 0.035), "right": (-0.282, 0.144, 0.035)},
         {"left": (-0.28, -0.26, -0.02), "right": (-0.28, 0.26, -0.02)})


def _carry(floor: float):
    """The round's carry planned (after its two reaches) with ``floor``: (plan, the factor by
    which the joint rate limits stretch it)."""
    planner = PmpPlanner(dataclasses.replace(PmpConfig(), success_tolerance=0.01,
                                             progress_joint_floor=floor))
    q = None
    for targets in ROUND:
        plan = planner.plan(ReachGoal(targets={h: np.array(p) for h, p in targets.items()},
                                      use_torso=False, tau=2.0, frozen_joints=WRISTS), q)
        assert plan.success, plan.message
        q = plan.q_final
    limits = JointRateLimits.from_spec(planner.spec)
    rep = limits.report(JointTrajectory(plan.joint_names, np.asarray(plan.t), plan.positions,
                                        np.asarray(plan.velocities)))
    return plan, rep.time_scale


def test_carry_to_the_workspace_edge_is_not_stretched_by_a_final_spin():
    """Without the floor the carry's shoulder_yaw turns several rad/s in the last 0.1 s and the
    rate limits stretch the 2 s reach more than 4-fold; with the floor at 0.5 the same path
    (same end posture, same residuals) needs less than half that stretch and no joint turns
    faster than twice its speed limit."""
    plain, stretch_plain = _carry(0.0)
    floored, stretch_floored = _carry(0.5)
    yaw = plain.joint_names.index("l_shoulder_yaw")
    late = plain.t >= plain.t[-1] - 0.1
    assert np.max(np.abs(plain.velocities[late, yaw])) > 3.0
    assert stretch_plain > 4.0
    assert stretch_floored < 0.5 * stretch_plain, (stretch_plain, stretch_floored)
    assert np.allclose(floored.q_final, plain.q_final)
    assert floored.residuals == pytest.approx(plain.residuals)
    limits = JointRateLimits.from_spec()
    for j, name in enumerate(floored.joint_names):
        vmax = limits.velocity[limits.joint_names.index(name)]
        assert np.max(np.abs(floored.velocities[:, j])) < 2.0 * vmax, name


def test_floor_keeps_a_proportional_path_on_the_minimum_jerk_clock():
    """Where the hand moves in proportion to the joints the floor changes nothing: progress is
    the hand's travelled fraction either way."""
    t = np.linspace(0.0, 1.0, 11)
    hands = np.stack([t, 0 * t, 0 * t], axis=1)[:, None, :]  # (N, 1, 3)
    joints = np.stack([2 * t, t], axis=1)
    rot = np.repeat(np.eye(3)[None, None], len(t), axis=0)
    tbg = TimeBaseGenerator(2.0)
    p0 = TbgTiming(tbg).progress(hands, rot, joints)
    p1 = TbgTiming(tbg, joint_floor=0.5).progress(hands, rot, joints)
    assert np.allclose(p0, p1) and np.allclose(p0, t)


def test_bad_floor_is_a_clear_error():
    """A negative or NaN floor names the parameter."""
    with pytest.raises(InvalidInput, match="joint_floor"):
        TbgTiming(TimeBaseGenerator(1.0), joint_floor=-1.0)
    with pytest.raises(ConfigError, match="progress_joint_floor"):
        PmpConfig(progress_joint_floor=float("nan"))
