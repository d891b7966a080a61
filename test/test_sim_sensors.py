"""The simulated sensors: FT statics and external forces against pinocchio + URDF inertials,
the FT sign convention (child_to_parent), the head IMU, the ground-truth hand wrench."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.kinematics import IcubModel
from icub_pmp.kinematics.urdf_robot import UrdfRobot
from icub_sim_bridge import FT_SENSORS, Simulator

G = np.array([0.0, 0.0, -9.81])


@pytest.fixture(scope="module")
def urdf(model) -> UrdfRobot:
    return UrdfRobot(model.urdf)


def _q_pin(sim: Simulator, model: IcubModel) -> np.ndarray:
    return sim.joint_state().position[sim.indices(model.joint_names)]


def expected_static_ft(model: IcubModel, urdf: UrdfRobot, q: np.ndarray, ft: str,
                       f_ext: np.ndarray | None = None, p_ext: np.ndarray | None = None
                       ) -> np.ndarray:
    """(6,) wrench the links distal to FT joint ``<ft>_sensor`` exert on the proximal side,
    in the FT frame, about its origin: weights (URDF masses and COMs placed by pinocchio's
    link frames) plus an optional external force ``f_ext`` at ``p_ext`` (root_link)."""
    child = urdf.joint(f"{ft}_sensor").child
    T_ft = model.frame_pose(q, ft)
    p, R = T_ft.translation, T_ft.rotation
    f = np.zeros(3)
    tau = np.zeros(3)
    for link in urdf.subtree_links(child):
        inertial = urdf.links[link].inertial
        if inertial is None or inertial.mass == 0:
            continue
        T = model.frame_pose(q, link).homogeneous
        c = T[:3, :3] @ inertial.T_link_com[:3, 3] + T[:3, 3]
        w = inertial.mass * G
        f += w
        tau += np.cross(c - p, w)
    if f_ext is not None:
        f += f_ext
        tau += np.cross(p_ext - p, f_ext)
    return np.concatenate((R.T @ f, R.T @ tau))


def _close(measured: np.ndarray, expected: np.ndarray, rel: float) -> None:
    for part in (slice(0, 3), slice(3, 6)):
        err = np.linalg.norm(measured[part] - expected[part])
        assert err <= rel * np.linalg.norm(expected[part]), (measured, expected)


def _clear_table(sim: Simulator) -> None:
    """Objects to the far end of the table, out of the arms' way."""
    sim.set_object_pose("box", [-0.58, -0.3, -0.05])
    sim.set_object_pose("cylinder", [-0.58, 0.3, -0.03])


def _raised_posture(model: IcubModel) -> dict[str, float]:
    q = {"l_shoulder_pitch": -1.0, "l_shoulder_roll": 0.6, "l_elbow": 1.2,
         "r_shoulder_pitch": -0.4, "r_shoulder_roll": 1.0, "r_shoulder_yaw": 0.3,
         "r_elbow": 0.5, "r_wrist_pitch": -0.3, "torso_pitch": 0.2, "torso_yaw": -0.3}
    return q


@pytest.mark.parametrize("posture", ["rest", "raised", "zero"])
def test_ft_statics_match_distal_weight(sim, model, urdf, posture):
    """Held still (gravity on), each of the four FT sensors reads the weight and moment of
    everything distal to it (URDF inertials at pinocchio's link poses), within 1 %."""
    if posture == "raised":
        sim.reset(q=_raised_posture(model))
    else:
        sim.reset(posture)
    _clear_table(sim)
    sim.step(300)
    assert np.abs(sim.joint_state().velocity).max() < 1e-6
    q = _q_pin(sim, model)
    for k, ft in enumerate(FT_SENSORS):
        _close(sim.ft_all()[k], expected_static_ft(model, urdf, q, ft), 0.01)


def test_ft_sign_convention_child_to_parent(sim, model):
    """An arm at rest: the l_arm_ft force rotated to root_link points DOWN with the distal
    weight (the child link pushes on the parent: URDF child_to_parent), not up."""
    sim.reset("rest")
    sim.step(50)
    q = _q_pin(sim, model)
    R = model.frame_pose(q, "l_arm_ft").rotation
    f_root = R @ sim.ft("l_arm_ft").force
    assert f_root[2] < -5.0  # about 1.9 kg of arm
    assert abs(f_root[0]) < 1e-6 and abs(f_root[1]) < 1e-6


@pytest.mark.parametrize("hand,ft", [("right", "r_arm_ft"), ("left", "l_arm_ft")])
def test_external_force_shows_in_arm_ft_with_lever_arm(sim, model, urdf, hand, ft):
    """A known force applied at the hand frame (xfrc_applied) appears in that arm's FT sensor
    as the force plus its moment about the sensor (lever arm hand - sensor), within 1 %; the
    other arm's sensor does not see it."""
    other = "l_arm_ft" if ft == "r_arm_ft" else "r_arm_ft"
    frame = sim.built.hand_frames[hand]
    sim.reset("rest")
    _clear_table(sim)
    sim.step(50)
    f_ext = np.array([4.0, -3.0, 6.0])
    sim.apply_wrench(frame, f_ext, np.zeros(3), duration=5.0)
    sim.step(1500)  # settles on the joint hold
    assert np.abs(sim.joint_state().velocity).max() < 1e-4
    q = _q_pin(sim, model)
    p_hand = model.frame_position(q, frame)
    k = FT_SENSORS.index(ft)
    measured = sim.ft_all()[k]
    expected = expected_static_ft(model, urdf, q, ft, f_ext, p_hand)
    gravity_only = expected_static_ft(model, urdf, q, ft)
    _close(measured - gravity_only, expected - gravity_only, 0.01)
    _close(measured, expected, 0.01)
    # the other arm only carries its own weight (in its frame, which the torso tilted a bit)
    _close(sim.ft_all()[FT_SENSORS.index(other)],
           expected_static_ft(model, urdf, q, other), 0.01)


def test_ground_truth_contact_wrench(sim):
    """The ground-truth hand wrench equals a wrench applied at the hand frame (force and
    torque, root_link, about the hand frame) and is zero without contact."""
    sim.reset("rest")
    sim.step(10)
    w0 = sim.contact_wrench("right")
    assert np.abs(np.concatenate(w0)).max() < 1e-9
    f, t = np.array([1.0, 2.0, -3.0]), np.array([0.1, -0.2, 0.05])
    sim.apply_wrench("r_hand_dh_frame", f, t, 1.0)
    sim.step(20)
    w = sim.contact_wrench("right")
    np.testing.assert_allclose(w.force, f, atol=1e-9)
    np.testing.assert_allclose(w.torque, t, atol=1e-4)  # hand moves ~1 um in a step
    assert np.abs(np.concatenate(sim.contact_wrench("left"))).max() < 1e-9
    sim.step(1000)  # the 1 s wrench has expired
    assert np.abs(sim.contact_wrench("right").force).max() < 1e-9


def test_ground_truth_sees_table_contact(sim):
    """Pressing a hand down onto the table shows an upward contact force on that hand."""
    sim.reset("rest")
    _clear_table(sim)
    idx = sim.indices(["l_shoulder_pitch", "l_elbow"])
    sim.step(10)
    sim.command(["l_shoulder_pitch", "l_elbow"], [8.0, -4.0])  # hand down onto the table
    sim.step(800)
    assert sim.commanded[idx].all()
    assert sim.contact_wrench("left").force[2] > 5.0
    assert np.abs(sim.contact_wrench("right").force).max() < 1e-9


def test_imu_reads_gravity_and_head_orientation(sim, model):
    """Still, the head IMU's proper acceleration rotated to root_link is +9.81 m/s^2 up, its
    gyro reads zero and its orientation is pinocchio's head_imu_0 frame."""
    sim.reset("rest")
    sim.step(20)
    imu = sim.imu()
    T = model.frame_pose(_q_pin(sim, model), "head_imu_0")
    import mujoco

    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, imu.orientation)
    np.testing.assert_allclose(R.reshape(3, 3), T.rotation, atol=1e-9)
    np.testing.assert_allclose(T.rotation @ imu.linear_acceleration, [0, 0, 9.81], atol=1e-6)
    np.testing.assert_allclose(imu.angular_velocity, 0.0, atol=1e-6)
