"""The simulator's realism: each imperfection of the ``icub`` preset is present, sized as
configured and seeded; ``ideal`` is the simulator without imperfections."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.errors import ConfigError
from icub_sim_bridge import RealismConfig, SimConfig, Simulator
from icub_sim_bridge.actuator_dynamics import ActuatorDynamics
from icub_sim_bridge.joint_friction import JointFriction
from icub_sim_bridge.model_mismatch import robot_bodies
from icub_sim_bridge.realism_config import PRESETS

_CFG = SimConfig(cameras_enabled=False)


def _sim(**realism) -> Simulator:
    return Simulator(_CFG, realism=RealismConfig(**{"preset": "icub", **realism}))


@pytest.fixture(scope="module")
def icub_sim() -> Simulator:
    return _sim()


def _still_second(sim: Simulator) -> tuple[np.ndarray, np.ndarray, list]:
    """Step one second on the simulator's hold; measured and true FT (1000, 4, 6), states."""
    meas, true, states = [], [], []
    for _ in range(1000):
        sim.step()
        meas.append(sim.ft_all())
        true.append(sim.true_ft_all())
        states.append(sim.joint_state())
    return np.array(meas), np.array(true), states


def test_ft_offset_and_noise_are_as_configured(icub_sim):
    """Over a still second the FT mean is off the true wrench by the sensor's offset (+ the
    drift so far) and the spread about it is the configured white noise."""
    sim = icub_sim
    meas, true, _ = _still_second(sim)
    s = sim.realism.resolved()
    ft = sim.imperfections.ft
    err = meas - true
    expected = ft.bias(sim.time)
    sem = np.r_[np.full(3, s.ft_force_noise_std), np.full(3, s.ft_torque_noise_std)] / np.sqrt(
        len(err))
    assert np.all(np.abs(err.mean(axis=0) - expected) < 5 * sem + 1e-3 * np.abs(expected))
    # the offset is there and within its range
    assert np.abs(ft.offset[:, :3]).max() > 0.3 * s.ft_force_offset
    assert np.all(np.abs(ft.offset[:, :3]) <= s.ft_force_offset)
    assert np.all(np.abs(ft.offset[:, 3:]) <= s.ft_torque_offset)
    std = err.std(axis=0)
    assert np.allclose(std[:, :3], s.ft_force_noise_std, rtol=0.12)
    assert np.allclose(std[:, 3:], s.ft_torque_noise_std, rtol=0.12)


def test_ft_override_changes_only_that_figure():
    """An override of the offset range changes the offsets (same seed: scaled draws), not
    the noise."""
    a, b = _sim(), _sim(ft_force_offset=5.0)
    assert np.allclose(b.imperfections.ft.offset[:, :3],
                       a.imperfections.ft.offset[:, :3] * 5.0 / PRESETS["icub"].ft_force_offset)
    assert np.array_equal(a.imperfections.ft.noise_std, b.imperfections.ft.noise_std)


def test_masses_com_and_inertias_differ_from_the_urdf_by_the_configured_amount(icub_sim):
    """The simulated links' masses are within +-10 % of the URDF's (and some near the bound),
    COMs within +-1 cm per axis, inertias scaled with the mass; the URDF model is untouched."""
    sim = icub_sim
    urdf, real = sim.built.model, sim.model
    assert real is not urdf
    b = robot_bodies(urdf, "root_link")
    assert len(b) > 20
    scale = real.body_mass[b] / urdf.body_mass[b]
    assert np.all(np.abs(scale - 1.0) <= 0.10 + 1e-12)
    assert np.abs(scale - 1.0).max() > 0.07
    shift = real.body_ipos[b] - urdf.body_ipos[b]
    assert np.all(np.abs(shift) <= 0.01 + 1e-12) and np.abs(shift).max() > 0.007
    assert np.allclose(real.body_inertia[b], urdf.body_inertia[b] * scale[:, None])


def test_same_seed_same_robot_other_seed_other_robot(icub_sim):
    """The seed fixes masses, FT offsets and IMU biases; another seed draws others."""
    again, other = _sim(), _sim(seed=7)
    for attr in ("mass_scale", "com_shift"):
        assert np.array_equal(getattr(icub_sim.imperfections.mismatch, attr),
                              getattr(again.imperfections.mismatch, attr))
        assert not np.allclose(getattr(icub_sim.imperfections.mismatch, attr),
                               getattr(other.imperfections.mismatch, attr))
    assert np.array_equal(icub_sim.imperfections.ft.offset, again.imperfections.ft.offset)
    assert not np.allclose(icub_sim.imperfections.ft.offset, other.imperfections.ft.offset)
    assert np.array_equal(icub_sim.imperfections.imu.errors.acc_bias,
                          again.imperfections.imu.errors.acc_bias)
    # the same noise sequence too
    for s in (again, other):
        s.step(5)
    fresh = _sim()
    fresh.step(5)
    assert np.array_equal(fresh.ft_all(), again.ft_all())


def test_encoders_are_quantised_and_imu_biased(icub_sim):
    """Positions are whole counts of the encoder resolution; the IMU's mean over a still
    second is off by its bias."""
    sim = icub_sim
    res = sim.realism.resolved().encoder_resolution
    q = sim.joint_state().position
    assert np.allclose(q / res, np.round(q / res), atol=1e-9)
    assert np.abs(q - sim.true_joint_state().position).max() <= res / 2 + 1e-12
    acc = np.array([sim.imu().linear_acceleration for _ in range(500)])
    true = sim.data.sensordata[sim._imu_adr["accelerometer"]:][:3]
    bias = sim.imperfections.imu.errors.acc_bias
    assert np.allclose(acc.mean(axis=0) - true, bias, atol=4 * 0.02 / np.sqrt(500))


def test_ideal_is_the_simulator_without_imperfections():
    """``ideal`` (the default): no imperfection object, the URDF model itself, sensors equal
    to the truth, and the same trajectory as a simulator built without a realism argument."""
    a = Simulator(_CFG, realism=RealismConfig())
    b = Simulator(_CFG)
    assert a.imperfections is None and a.model is a.built.model
    for s in (a, b):
        s.command(["r_elbow", "r_shoulder_pitch"], [1.0, -2.0])
        s.step(300)
    assert np.array_equal(a.ft_all(), a.true_ft_all())
    assert np.array_equal(a.joint_state().position, b.joint_state().position)
    assert np.array_equal(a.ft_all(), b.ft_all())
    zeros = dict(ft_force_noise_std=0.0, ft_torque_noise_std=0.0, ft_force_offset=0.0,
                 ft_torque_offset=0.0, ft_force_drift=0.0, ft_torque_drift=0.0,
                 ft_bandwidth_hz=0.0, mass_error=0.0, com_error=0.0,
                 friction_coulomb=(0.0,) * 3, friction_stiction=(0.0,) * 3,
                 friction_viscous=(0.0,) * 3, actuator_delay_steps=0, encoder_resolution=0.0,
                 velocity_noise_std=0.0, imu_acc_noise_std=0.0, imu_acc_bias=0.0,
                 imu_gyro_noise_std=0.0, imu_gyro_bias=0.0, camera_noise_std=0.0,
                 camera_focal_error=0.0, camera_principal_error=0.0,
                 camera_rotation_error_deg=0.0)
    assert not RealismConfig(preset="icub", **zeros).resolved().active


def test_friction_holds_below_breakaway_and_is_installed(icub_sim):
    """Dry friction is the stiction level at rest and the Coulomb level when moving; the
    viscous term is added to the model's joint damping."""
    f = JointFriction(["torso_yaw", "r_elbow", "neck_yaw", "l_eye_pan"], np.arange(4),
                      (0.4, 0.15, 0.05), (0.6, 0.25, 0.08), (0.3, 0.1, 0.02), 0.01)
    assert np.allclose(f.dry(np.zeros(4)), [0.6, 0.25, 0.08, 0.08])
    assert np.allclose(f.dry(np.full(4, 1.0)), [0.4, 0.15, 0.05, 0.05])
    sim = icub_sim
    fr = sim.imperfections.friction
    assert np.allclose(sim.model.dof_damping[fr.dofs] - sim.built.model.dof_damping[fr.dofs],
                       fr.viscous)


def test_actuation_is_one_step_late():
    """A torque step reaches the joint one physics step after it is commanded."""
    a = ActuatorDynamics(2, 1, 0.0, 0.001)
    assert np.array_equal(a.apply(np.array([1.0, 2.0])), [0.0, 0.0])
    assert np.array_equal(a.apply(np.array([3.0, 4.0])), [1.0, 2.0])


@pytest.mark.parametrize("bad, match", [
    ({"preset": "real"}, "ideal"),
    ({"ft_force_noise_std": -2.0}, "ft_force_noise_std"),
    ({"friction_coulomb": (0.1, 0.2)}, "friction_coulomb"),
    ({"mass_error": 1.5}, "mass_error"),
])
def test_bad_realism_parameters_are_refused_by_name(bad, match):
    """A wrong preset lists the valid ones; a bad figure is named."""
    with pytest.raises(ConfigError, match=match):
        RealismConfig(**bad)


def test_realism_parameters_are_realism_dot_names():
    """The ROS names are realism.<field>; unknown ones are refused by name."""
    cfg = RealismConfig.from_dict({"realism.preset": "icub", "realism.seed": 3})
    assert cfg.preset == "icub" and cfg.seed == 3
    assert "realism.preset" in cfg.to_dict()
    with pytest.raises(ConfigError, match="realism.nois"):
        RealismConfig.from_dict({"realism.nois": 1.0})


def test_cameras_see_through_the_perturbed_calibration():
    """With a principal-point error only, the rendered image is the nominal one shifted by
    that error (phase correlation, within 0.5 px); with pixel noise the images get its std;
    the nominal intrinsics (what camera_info publishes) are unchanged."""
    import cv2

    from icub_sim_bridge.camera_renderer import CameraRenderer

    zero = dict(camera_focal_error=0.0, camera_rotation_error_deg=0.0, camera_noise_std=0.0)
    ideal = Simulator(SimConfig())
    shifted = _sim(camera_principal_error=6.0, **zero)
    imgs = []
    for s in (ideal, shifted):
        r = CameraRenderer(s.model, s.built.camera, threaded=False)
        imgs.append(r.render(s.data)["left"])
        r.close()
    d = shifted.imperfections.cameras["left"].principal_shift
    assert np.abs(d).max() > 1.0  # a shift worth measuring
    grey = [cv2.cvtColor(i, cv2.COLOR_RGB2GRAY).astype(np.float64) for i in imgs]
    (dx, dy), _ = cv2.phaseCorrelate(grey[0], grey[1])
    assert abs(dx - d[0]) < 0.5 and abs(dy - d[1]) < 0.5, ((dx, dy), d)
    assert shifted.built.camera == ideal.built.camera
    noisy = _sim(**{**zero, "camera_noise_std": 2.0})
    out = noisy.imperfections.noisy_image(imgs[0])
    diff = out.astype(float) - imgs[0]
    assert abs(diff[(imgs[0] > 10) & (imgs[0] < 245)].std() - 2.0) < 0.2
