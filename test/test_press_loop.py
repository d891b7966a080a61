"""The press's force loop (icub_pmp.control.press_loop): a bad secant does not spoil the
compliance, a diverged press is not built on, the step is capped, and the loop converges on a
contact that is softer than the model and noisy."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.control.press_loop import PressLoop, PressLoopConfig, robust_secant_update
from icub_pmp.errors import InvalidInput

F = np.array([0.0, 0.0, -10.0])
MODEL = np.diag([0.0008, 0.0008, 0.0011])


def test_a_secant_that_disagrees_with_the_model_is_rejected():
    """A press that moved the target 2 mm down and changed the force by 0.5 N (the fingertips
    slipped: 4 mm/N, 3.6 x the model) or raised it while the target went up (sign) keeps the
    compliance; one at 1.5 x the model is fitted exactly."""
    dx = np.array([0.0, 0.0, -0.002])
    C, ok = robust_secant_update(MODEL, MODEL, dx, np.array([0.0, 0.0, -0.5]))
    assert not ok and C is MODEL
    C, ok = robust_secant_update(MODEL, MODEL, -dx, np.array([0.0, 0.0, -1.2]))
    assert not ok and C is MODEL
    dF = dx / (1.5 * 0.0011)
    C, ok = robust_secant_update(MODEL, MODEL, dx, dF)
    assert ok and np.allclose(C @ dF, dx)
    C, ok = robust_secant_update(MODEL, MODEL, dx, np.array([0.0, 0.0, -0.1]))
    assert not ok  # too small a change to tell


def test_a_diverged_press_is_not_built_on_and_the_best_is_kept():
    """After a press within 6 % and one nearly lifted off (95 %: the target went down, the
    force fell), the secant between them is rejected, and the next target is a correction of
    the good press, not of the lifted one; ``best`` is the good press."""
    loop = PressLoop(F, MODEL)
    loop.record([0.0, 0.0, -0.010], [0.0, 0.2, -9.4])
    good = loop.presses[0]
    lifted = loop.record(loop.next_target(), [0.0, 0.1, -0.5])
    assert not lifted.secant_accepted and np.array_equal(loop.compliance, MODEL)
    assert loop.best is good and not loop.done
    nxt = loop.next_target()
    expected = good.target + loop.compliance @ (F - good.exerted)
    assert np.allclose(nxt, expected)
    assert np.linalg.norm(nxt - good.target) < 0.001


def test_one_correction_moves_the_target_at_most_max_step():
    loop = PressLoop(F, MODEL, PressLoopConfig(max_step=0.002))
    loop.record(np.zeros(3), np.zeros(3))  # no contact yet: 10 N x 1.1 mm/N = 11 mm wanted
    step = loop.next_target()
    assert np.isclose(np.linalg.norm(step), 0.002)
    assert step[2] < 0


def test_the_loop_converges_on_a_softer_noisy_contact():
    """A contact twice as compliant as the model down, with a sideways friction force that
    grows with the press and 0.2 N of noise: within 8 presses the force is within 4 %."""
    rng = np.random.default_rng(3)
    true_c = np.array([[0.0016, 0.0, 0.0], [0.0, 0.0016, 0.0004], [0.0, 0.0, 0.0022]])
    contact = np.array([-0.3, 0.15, -0.05])

    def plant(target: np.ndarray) -> np.ndarray:
        f = np.linalg.solve(true_c, target - contact)
        return (f if f[2] < 0 else np.zeros(3)) + rng.normal(0.0, 0.2, 3)

    loop = PressLoop(F, MODEL)
    target = contact + MODEL @ F
    for _ in range(8):
        loop.record(target, plant(target))
        if loop.done:
            break
        target = loop.next_target()
    assert loop.done, [round(p.error, 3) for p in loop.presses]


def test_bad_input_is_a_clear_error():
    with pytest.raises(InvalidInput, match="force"):
        PressLoop(np.zeros(3), MODEL)
    with pytest.raises(InvalidInput, match="compliance"):
        PressLoop(F, np.full((3, 3), np.nan))
    with pytest.raises(InvalidInput, match="max_step"):
        PressLoopConfig(max_step=-1.0)
    with pytest.raises(InvalidInput, match="no press"):
        PressLoop(F, MODEL).next_target()


def test_contact_compliance_predicts_how_far_the_fingertips_and_the_frame_yield():
    """A force at the fingertips (the hull's lowest point, 5-6 cm from the hand frame) bends
    the joint springs by ``K^-1 J_c^T F``: forward kinematics of the bent posture moves the
    fingertips by the kept-orientation compliance (``J_c K^-1 J_c^T``) and the hand frame by
    the free one (``J_h K^-1 J_c^T``); down, the fingertips yield more than the frame."""
    from icub_pmp.demo import scenario
    from icub_pmp.kinematics import IcubModel

    model = IcubModel()
    spec = model.spec
    joints = list(spec.torso_joints) + list(spec.arm_joints("right"))
    stiffness = scenario.joint_stiffness(joints)
    frame = spec.hand_frame("right")
    q = model.posture("rest")
    c = scenario.hand_contact_point(model, q)
    pose = model.frame_pose(q, frame)
    local = np.asarray(pose.rotation).T @ (c - np.asarray(pose.translation))
    assert 0.03 < np.linalg.norm(local) < 0.12
    kept = scenario.contact_compliance(model, q, frame, c, stiffness, keep_orientation=True)
    free = scenario.contact_compliance(model, q, frame, c, stiffness)
    assert np.allclose(kept, kept.T) and np.all(np.linalg.eigvalsh(kept) > 0)
    idx = model.indices(joints)
    k = np.array([stiffness[j] for j in joints])
    J = model.frame_jacobian(q, frame)[:, idx]
    skew = np.array([[0, -c[2] + pose.translation[2], c[1] - pose.translation[1]],
                     [c[2] - pose.translation[2], 0, -c[0] + pose.translation[0]],
                     [-c[1] + pose.translation[1], c[0] - pose.translation[0], 0]])
    Jc = J[:3] - skew @ J[3:]
    F = np.array([0.0, 0.0, 0.5])  # the table pushes the fingertips up by 0.5 N
    dq = np.zeros_like(q)
    dq[idx] = (Jc.T @ F) / k
    bent = model.frame_pose(q + dq, frame)
    tip_moved = np.asarray(bent.rotation) @ local + np.asarray(bent.translation) - c
    frame_moved = np.asarray(bent.translation) - np.asarray(pose.translation)
    assert np.linalg.norm(tip_moved - kept @ F) < 0.05 * np.linalg.norm(tip_moved)
    assert np.linalg.norm(frame_moved - free @ F) < 0.05 * np.linalg.norm(frame_moved)
    assert kept[2, 2] > free[2, 2] > 0
