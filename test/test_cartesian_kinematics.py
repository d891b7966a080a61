"""CasADi forward kinematics, chains and the iCub arm linear constraints (icub_pmp.cartesian)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from icub_pmp.cartesian import CHAIN_NAMES, ArmLinearConstraints, CasadiKinematics, KinematicChain
from icub_pmp.errors import InvalidInput, ModelError, UnknownName


@pytest.mark.parametrize("name", CHAIN_NAMES)
def test_fk_matches_pinocchio(model, name):
    """The CasADi hand pose equals pinocchio's to 1e-9 m / 1e-9 on 300 random configurations."""
    chain = KinematicChain.from_name(name)
    fk = CasadiKinematics(model, chain.frame, chain.fk_joints)
    idx = model.indices(chain.fk_joints)
    rng = np.random.default_rng(7)
    worst_p = worst_r = 0.0
    for _ in range(300):
        q = model.random_q(rng)
        T = model.frame_pose(q, chain.frame)
        p, R = fk.pose(q[idx])
        worst_p = max(worst_p, float(np.abs(p - T.translation).max()))
        worst_r = max(worst_r, float(np.abs(R - T.rotation).max()))
    assert worst_p < 1e-9
    assert worst_r < 1e-9


def test_fk_derivative_matches_pinocchio_jacobian(model):
    """d K_x / d q of the CasADi expressions equals pinocchio's frame Jacobian (linear part)."""
    import casadi as ca

    chain = KinematicChain.from_name("torso_left_arm")
    fk = CasadiKinematics(model, chain.frame, chain.fk_joints)
    jac = ca.Function("J", [fk.q], [ca.jacobian(fk.position, fk.q)])
    idx = model.indices(chain.fk_joints)
    q = model.random_q(np.random.default_rng(3))
    J_pin = model.frame_jacobian(q, chain.frame)[:3, idx]
    np.testing.assert_allclose(np.array(jac(q[idx])), J_pin, atol=1e-10)


def test_fk_rejects_a_joint_list_that_is_not_the_frame_path(model):
    """Building FK over joints that are not the root->frame path raises ModelError."""
    chain = KinematicChain.from_name("right_arm")
    with pytest.raises(ModelError, match="not the path"):
        CasadiKinematics(model, chain.frame, chain.joints)  # torso missing


def test_fk_pose_rejects_bad_q(model):
    """pose() rejects a NaN or wrongly sized configuration."""
    chain = KinematicChain.from_name("right_arm")
    fk = CasadiKinematics(model, chain.frame, chain.fk_joints)
    with pytest.raises(InvalidInput):
        fk.pose(np.full(10, np.nan))
    with pytest.raises(InvalidInput):
        fk.pose(np.zeros(7))


def test_chains():
    """7-DoF chains optimise the arm only and hold the torso; 10-DoF chains optimise both."""
    arm = KinematicChain.from_name("left_arm")
    full = KinematicChain.from_name("torso_left_arm")
    assert arm.n == 7 and full.n == 10
    assert arm.fixed_joints == ("torso_pitch", "torso_roll", "torso_yaw")
    assert full.fixed_joints == ()
    assert arm.frame == "l_hand_dh_frame"
    assert KinematicChain.from_name("torso_right_arm").frame == "r_hand_dh_frame"
    assert KinematicChain.named("right", True) == "torso_right_arm"
    with pytest.raises(UnknownName, match="torso_right_arm"):
        KinematicChain.from_name("tail")


def _deg(**kw: float) -> np.ndarray:
    order = ("q0", "q1", "q2", "q3", "q4")
    return np.radians([kw.get(k, 0.0) for k in order])


@pytest.mark.parametrize("hand", ["left", "right"])
def test_arm_constraints_numbers(model, hand):
    """The seven iKin constraints: the rest posture meets them; each listed configuration
    violates exactly the constraint it was built to violate."""
    alc = ArmLinearConstraints(hand)
    joints = alc.arm_joints
    c = alc.over(joints)
    assert c.C.shape == (7, 5)
    rest = model.posture("rest")[model.indices(joints)]
    assert alc.violation(joints, rest) == 0.0
    cases = {
        3: _deg(q0=-20, q1=20, q2=0, q3=50),  # shoulder roll under the torso-collision line
        4: _deg(q0=-20, q1=110, q2=0, q3=50),  # abduction > 100 deg
        5: _deg(q0=-20, q1=40, q3=106, q4=60),  # 2.5 q3 + q4 = 325 deg > 302.5
        6: _deg(q0=-20, q1=40, q3=106, q4=-60),  # q4 - 2.5 q3 = -325 deg < -302.5
        2: _deg(q0=-20, q1=150, q2=80, q3=50),  # q1 + q2 = 230 deg > 213.3 (and roll > 100)
    }
    for row, q in cases.items():
        v = c.C @ q
        bad = np.flatnonzero((v < c.lb - 1e-12) | (v > c.ub + 1e-12))
        assert row in bad, (row, bad)
        assert alc.violation(joints, q) > 0
    # the 26.4 deg line of constraint 4 goes through (q1, q2) = (26.4 - 0.0427 q2, q2)
    q = _deg(q0=-20, q1=26.4 - 0.0427 * 40 + 0.01, q2=40, q3=50)
    assert alc.violation(joints, q) == 0.0
    assert math.isclose(c.lb[0], math.radians(-347.0))


def test_arm_constraints_errors():
    """Unknown hand and a joint list without the shoulder joints are rejected."""
    with pytest.raises(UnknownName):
        ArmLinearConstraints("middle")
    with pytest.raises(InvalidInput, match="lack"):
        ArmLinearConstraints("right").over(["torso_pitch"])
