"""FtDynamicsModel: the FT-cut RNEA model agrees with IcubModel and with Newton-Euler statics."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from icub_pmp.dynamics.ft_dynamics_model import FtDynamicsModel
from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_model import IcubModel

DISTAL = {
    "left": ["l_upper_arm", "l_elbow_1", "l_forearm", "l_wrist_1", "l_hand"],
    "right": ["r_upper_arm", "r_elbow_1", "r_forearm", "r_wrist_1", "r_hand"],
}


@pytest.fixture(scope="module")
def ft_model() -> FtDynamicsModel:
    return FtDynamicsModel()


@pytest.fixture(scope="module")
def icub() -> IcubModel:
    return IcubModel()


def test_joint_torques_equal_icub_model(ft_model, icub):
    """Adding the motionless FT joints changes no joint torque: RNEA equals IcubModel's."""
    rng = np.random.default_rng(0)
    assert ft_model.joint_names == icub.joint_names
    for _ in range(5):
        q = icub.random_q(rng)
        v = rng.normal(size=icub.nq)
        a = rng.normal(size=icub.nq)
        r = ft_model.rnea(q, v, a)
        np.testing.assert_allclose(r.tau, icub.inverse_dynamics(q, v, a), atol=1e-9)


def test_static_sensor_force_is_the_distal_weight(ft_model, icub):
    """At rest the sensor force (parent on child) holds up the distal arm: |f| = m g, pointing
    up in root_link, with m the mass of upper arm + forearm + hand links."""
    q = icub.posture("rest")
    r = ft_model.rnea(q)
    for hand in ("left", "right"):
        m = sum(ft_model.link_mass(k) for k in DISTAL[hand])
        assert 1.8 < m < 2.1  # the V2_7 URDF's distal arm (about 1.93 kg)
        f_sensor = r.sensor[hand][:3]
        rot = ft_model.frame_rotation(ft_model.spec.arm_ft_frames[hand])
        np.testing.assert_allclose(rot @ f_sensor, [0, 0, m * 9.81], atol=1e-9)


def test_hand_wrench_reaches_the_sensor_transported(ft_model, icub):
    """A wrench on the hand adds, at the sensor, its transport to the sensor frame (eq 2
    read backwards), and adds -J^T w to the joint torques (eq 3)."""
    rng = np.random.default_rng(1)
    q = icub.random_q(rng)
    w = rng.normal(size=6)
    r0 = ft_model.rnea(q)
    r1 = ft_model.rnea(q, hand_wrenches={"right": w})
    t_sh, t_rh = ft_model.hand_placements("right")
    # the shoulder balances the extra load: minus the hand wrench moved to the sensor frame
    expected = -t_sh.act(pin.Force(w)).vector
    np.testing.assert_allclose(r1.sensor["right"] - r0.sensor["right"], expected, atol=1e-9)
    np.testing.assert_allclose(r1.sensor["left"], r0.sensor["left"], atol=1e-12)
    jac = icub.frame_jacobian(q, "r_hand_dh_frame")
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
