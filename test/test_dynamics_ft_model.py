"""FtDynamicsModel: the FT-cut RNEA model agrees with IcubModel and with Newton-Euler statics."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from icub_pmp.dynamics.ft_dynamics_model import FtDynamicsModel
from icub_pmp.errors import InvalidInput, UnknownName

DISTAL = {
    "left": ["l_upper_arm", "l_elbow_1", "l_forearm", "l_wrist_1", "l_hand"],
    "right": ["r_upper_arm", "r_elbow_1", "r_forearm", "r_wrist_1", "r_hand"],
}


@pytest.fixture(scope="module")
def ft_model() -> FtDynamicsModel:
    return FtDynamicsModel()


def test_joint_torques_equal_icub_model(ft_model, model):
    """Adding the motionless FT joints changes no joint torque: RNEA equals IcubModel's."""
    rng = np.random.default_rng(0)
    assert ft_model.joint_names == model.joint_names
    for _ in range(5):
        q = model.random_q(rng)
        v = rng.normal(size=model.nq)
        a = rng.normal(size=model.nq)
        r = ft_model.rnea(q, v, a)
        np.testing.assert_allclose(r.tau, model.inverse_dynamics(q, v, a), atol=1e-9)


def test_static_sensor_force_is_the_distal_weight(ft_model, model):
    """At rest the sensor force (parent on child) holds up the distal arm: |f| = m g, pointing
    up in root_link, with m the mass of upper arm + forearm + hand links."""
    q = model.posture("rest")
    r = ft_model.rnea(q)
    for hand in ("left", "right"):
        m = sum(ft_model.link_mass(k) for k in DISTAL[hand])
        assert 1.8 < m < 2.1  # the V2_7 URDF's distal arm (about 1.93 kg)
        f_sensor = r.sensor[hand][:3]
        rot = ft_model.frame_rotation(ft_model.spec.arm_ft_frames[hand])
        np.testing.assert_allclose(rot @ f_sensor, [0, 0, m * 9.81], atol=1e-9)


def test_hand_wrench_reaches_the_sensor_transported(ft_model, model):
    """A wrench on the hand adds, at the sensor, its transport to the sensor frame (eq 2
    read backwards), and adds -J^T w to the joint torques (eq 3)."""
    rng = np.random.default_rng(1)
    q = model.random_q(rng)
    w = rng.normal(size=6)
    r0 = ft_model.rnea(q)
    r1 = ft_model.rnea(q, hand_wrenches={"right": w})
    t_sh, t_rh = ft_model.hand_placements("right")
    # the shoulder balances the extra load: minus the hand wrench moved to the sensor frame
    expected = -t_sh.act(pin.Force(w)).vector
    np.testing.assert_allclose(r1.sensor["right"] - r0.sensor["right"], expected, atol=1e-9)
    np.testing.assert_allclose(r1.sensor["left"], r0.sensor["left"], atol=1e-12)
    jac = model.frame_jacobian(q, "r_hand_dh_frame")
    w_root = np.concatenate([t_rh.rotation @ w[:3], t_rh.rotation @ w[3:]])
    np.testing.assert_allclose(r1.tau, r0.tau - jac.T @ w_root, atol=1e-9)


def test_mass_scale_changes_only_that_link():
    """link_mass_scale multiplies the named link's mass (a deliberate model mismatch)."""
    m = FtDynamicsModel(link_mass_scale={"l_forearm": 1.1})
    base = FtDynamicsModel()
    assert m.link_mass("l_forearm") == pytest.approx(1.1 * base.link_mass("l_forearm"))
    assert m.link_mass("r_forearm") == base.link_mass("r_forearm")
    q = np.zeros(m.nq)
    d = m.rnea(q).sensor["left"][:3] - base.rnea(q).sensor["left"][:3]
    assert np.linalg.norm(d) == pytest.approx(0.1 * base.link_mass("l_forearm") * 9.81)


def test_bad_inputs_are_rejected(ft_model):
    """Unknown links/hands and a nonsense gravity raise clear errors."""
    with pytest.raises(UnknownName, match="l_forarm"):
        FtDynamicsModel(link_mass_scale={"l_forarm": 1.1})
    with pytest.raises(InvalidInput, match="positive"):
        FtDynamicsModel(link_mass_scale={"l_forearm": -1.0})
    with pytest.raises(UnknownName, match="hand"):
        ft_model.rnea(np.zeros(ft_model.nq), hand_wrenches={"middle": np.zeros(6)})
    with pytest.raises(InvalidInput, match="gravity"):
        ft_model.set_gravity([0, 0, float("nan")])


def test_estimator_two_passes_equal_the_general_rnea(ft_model, model):
    """The estimator's two passes (free_sensor_wrenches, then torques_with_sensor_excess) give
    the same sensor wrenches, hand wrenches and joint torques as the general rnea() with the
    hand wrenches applied: the external wrench on the distal arm given at the sensor is moved
    to the hand (eq 2) and folded into RNEA (eq 3)."""
    rng = np.random.default_rng(7)
    for _ in range(5):
        q, v, a = model.random_q(rng), rng.normal(size=ft_model.nq), rng.normal(size=ft_model.nq)
        excess = {h: rng.normal(size=6) for h in ("left", "right")}
        free = ft_model.free_sensor_wrenches(q, v, a)
        tau, ext_hand, ext_root = ft_model.torques_with_sensor_excess(excess)
        r0 = ft_model.rnea(q, v, a)
        r1 = ft_model.rnea(q, v, a, hand_wrenches=ext_hand)
        for h in ("left", "right"):
            np.testing.assert_allclose(free[h], r0.sensor[h], atol=1e-12)
            # the hand wrench makes the sensor carry exactly the excess less
            np.testing.assert_allclose(r1.sensor[h], r0.sensor[h] - excess[h], atol=1e-9)
            _, t_rh = ft_model.hand_placements(h)
            np.testing.assert_allclose(
                ext_root[h], np.concatenate([t_rh.rotation @ ext_hand[h][:3],
                                             t_rh.rotation @ ext_hand[h][3:]]), atol=1e-12)
        np.testing.assert_allclose(tau, r1.tau, atol=1e-9)
