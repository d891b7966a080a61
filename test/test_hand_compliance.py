"""hand_compliance: C = J K^-1 J^T predicts how far a joint-sprung hand's set-point lies
beyond the contact for a given force."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.control.hand_compliance import hand_compliance
from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics import IcubModel


@pytest.fixture(scope="module")
def model() -> IcubModel:
    return IcubModel()


def _arm(model: IcubModel) -> dict[str, float]:
    spec = model.spec
    k = [400.0, 400.0, 300.0, 300.0, 300.0, 200.0, 200.0, 60.0, 40.0, 40.0]
    return dict(zip(list(spec.torso_joints) + list(spec.arm_joints("right")), k))


def test_compliance_predicts_the_set_point_of_a_force(model):
    """The joint springs hold a hand force F when K (q_d - q) = J^T F: the set-point posture
    q_d = q + K^-1 J^T F puts the hand C F away from the contact (to first order: within 1 %
    for a 2 N force); C is symmetric positive definite."""
    stiffness = _arm(model)
    q = model.posture("rest")
    C = hand_compliance(model, q, "r_hand_dh_frame", stiffness)
    assert np.allclose(C, C.T) and np.all(np.linalg.eigvalsh(C) > 0.0)
    F = np.array([0.5, -0.3, -2.0])
    idx = model.indices(list(stiffness))
    J = model.frame_jacobian(q, "r_hand_dh_frame")[:3, idx]
    q_d = q.copy()
    q_d[idx] += (J.T @ F) / np.array(list(stiffness.values()))
    moved = model.frame_position(q_d, "r_hand_dh_frame") - model.frame_position(
        q, "r_hand_dh_frame")
    assert np.linalg.norm(moved - C @ F) < 0.01 * np.linalg.norm(C @ F)


def test_stiffer_joints_make_a_stiffer_hand(model):
    """Doubling every joint stiffness halves the compliance."""
    stiffness = _arm(model)
    q = model.posture("rest")
    C1 = hand_compliance(model, q, "r_hand_dh_frame", stiffness)
    C2 = hand_compliance(model, q, "r_hand_dh_frame", {j: 2 * k for j, k in stiffness.items()})
    assert np.allclose(C2, 0.5 * C1)


def test_bad_stiffness_or_names_are_refused(model):
    """A zero, negative or NaN stiffness, no joint at all, or an unknown joint is refused with
    a clear error."""
    q = model.posture("rest")
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(InvalidInput, match="r_elbow"):
            hand_compliance(model, q, "r_hand_dh_frame", {"r_elbow": bad})
    with pytest.raises(InvalidInput, match="names no joint"):
        hand_compliance(model, q, "r_hand_dh_frame", {})
    with pytest.raises(UnknownName):
        hand_compliance(model, q, "r_hand_dh_frame", {"r_knee": 10.0})
