"""The generated MuJoCo model matches the URDF as pinocchio reads it (names, limits, kinematics),
its eyes/cameras match EyeKinematics, and the builder/URDF/mesh helpers behave."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from icub_pmp.errors import ConfigError, InvalidInput, UnknownName
from icub_pmp.kinematics import IcubModel, RobotSpec
from icub_pmp.kinematics.eye_kinematics import EyeKinematics, dh_transform
from icub_pmp.kinematics.tri_mesh import TriMesh
from icub_pmp.kinematics.urdf_robot import rpy_matrix
from icub_sim_bridge import SimConfig
from icub_sim_bridge.model_builder import EYE_CAMERAS


def _q_dict(model: IcubModel, q: np.ndarray) -> dict[str, float]:
    return {n: float(q[i]) for i, n in enumerate(model.joint_names)}


def test_model_joints_and_actuators(sim):
    """The model has the 23 actuated joints of RobotSpec (torso, arms, neck, eyes), one torque
    actuator each with the robot.yaml torque limit as force range, and no leg joints."""
    spec = RobotSpec.load()
    assert sim.joint_names == spec.actuated_joints
    m = sim.model
    assert m.nu == 23
    for i, name in enumerate(sim.joint_names):
        a = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
        assert m.actuator_forcerange[a].tolist() == [-spec.torque_limit(name),
                                                     spec.torque_limit(name)]
        assert sim.torque_limits[i] == spec.torque_limit(name)
    joints = {m.joint(i).name for i in range(m.njnt)}
    assert not any(j.startswith(("l_hip", "r_knee", "l_ankle")) for j in joints)


def test_collision_pairs_between_the_arms(sim):
    """MuJoCo's contype/conaffinity filter lets every collision geom of the left arm touch every
    one of the right arm, and no two geoms of the same arm touch each other; the arms still
    collide with the table and objects."""
    m = sim.model

    def collide(a: int, b: int) -> bool:
        return bool((m.geom_contype[a] & m.geom_conaffinity[b])
                    or (m.geom_contype[b] & m.geom_conaffinity[a]))

    arm = {s: [g for g in range(m.ngeom) if m.geom(g).name.startswith(f"{s}_")
               and m.geom(g).name.endswith("_collision")] for s in "lr"}
    assert len(arm["l"]) == len(arm["r"]) == 5
    assert all(collide(a, b) for a in arm["l"] for b in arm["r"])
    for side in "lr":
        assert not any(collide(a, b) for a in arm[side] for b in arm[side] if a != b)
    table = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "table_top")
    box = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "box_geom")
    assert all(collide(a, table) and collide(a, box) for a in arm["l"] + arm["r"])


def test_written_mjcf_loads(sim, tmp_path):
    """The model written as MJCF (ModelBuilder.write_xml, meshes inline) loads back with the
    same bodies, actuators, sensors and cameras."""
    from icub_sim_bridge.model_builder import ModelBuilder

    path = ModelBuilder(sim.config).write_xml(sim.built, tmp_path / "icub_sim.xml")
    m = mujoco.MjModel.from_xml_path(str(path))
    a = sim.model
    assert (m.nbody, m.nu, m.nsensor, m.ncam, m.njnt) == (a.nbody, a.nu, a.nsensor, a.ncam,
                                                          a.njnt)


def test_joint_limits_match_pinocchio(sim, model):
    """Joint limits [rad] of the 20 URDF joints equal pinocchio's (same URDF)."""
    idx = sim.indices(model.joint_names)
    np.testing.assert_allclose(sim.lower[idx], model.lower, atol=1e-12)
    np.testing.assert_allclose(sim.upper[idx], model.upper, atol=1e-12)


def test_hand_positions_match_pinocchio(sim, model):
    """Over 30 random configurations within the limits, both hand frames (and the arm FT and
    head frames) are where pinocchio puts them, to 1e-6 m and 1e-6 rad."""
    rng = np.random.default_rng(3)
    frames = ("l_hand_dh_frame", "r_hand_dh_frame", "l_arm_ft", "r_arm_ft", "head_imu_0")
    for _ in range(30):
        q = model.random_q(rng)
        sim.reset(q=_q_dict(model, q))
        for f in frames:
            T = model.frame_pose(q, f)
            pose = sim.frame_pose(f)
            np.testing.assert_allclose(pose.position, T.translation, atol=1e-6)
            R = np.zeros(9)
            mujoco.mju_quat2Mat(R, pose.quaternion)
            np.testing.assert_allclose(R.reshape(3, 3), T.rotation, atol=1e-6)


def test_masses_match_pinocchio(sim, model):
    """The robot's total mass in MuJoCo equals pinocchio's (URDF inertials, legs included)."""
    m = sim.model
    robot = [i for i in range(1, m.nbody) if m.body(i).name not in ("table", "box", "cylinder")]
    total = sum(m.body_mass[i] for i in robot)
    pin_total = sum(inertia.mass for inertia in model.model.inertias)
    assert total == pytest.approx(pin_total, rel=1e-3)  # + 3 g of eye bodies


def test_cameras_match_eye_kinematics(sim, model):
    """The two MuJoCo eye cameras sit at EyeKinematics.T_root_camera (optical frame turned pi
    about x), for random torso/neck/eye angles, to 1e-9."""
    rng = np.random.default_rng(5)
    eyes = sim.built.eye_kinematics
    for _ in range(10):
        q = model.random_q(rng)
        tilt, version, vergence = rng.uniform(-0.5, 0.2), rng.uniform(-0.4, 0.4), \
            rng.uniform(0.0, 0.5)
        qd = _q_dict(model, q) | {"eyes_tilt": tilt, "eyes_version": version,
                                      "eyes_vergence": vergence}
        sim.reset(q=qd)
        st = sim.joint_state()
        np.testing.assert_allclose(st.position[sim.indices(["eyes_tilt", "eyes_version",
                                                             "eyes_vergence"])],
                                   [tilt, version, vergence], atol=1e-12)
        T_head = model.frame_pose(q, "head").homogeneous
        for side in ("left", "right"):
            T = eyes.T_root_camera(T_head, side, tilt, version, vergence)
            c = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_CAMERA, EYE_CAMERAS[side])
            np.testing.assert_allclose(sim.data.cam_xpos[c], T[:3, 3], atol=1e-9)
            np.testing.assert_allclose(sim.data.cam_xmat[c].reshape(3, 3),
                                       T[:3, :3] @ np.diag([1.0, -1.0, -1.0]), atol=1e-9)


def test_eye_kinematics_geometry(model):
    """Eyes 0.068 m apart, left eye on the robot's left (-y), optical axes forward (-x) at
    zero; positive vergence converges; pans/version_vergence are inverse maps."""
    eyes = EyeKinematics.from_model(model)
    T_head = model.frame_pose(np.zeros(model.nq), "head").homogeneous
    Tl = eyes.T_root_camera(T_head, "left", 0.0, 0.0, 0.0)
    Tr = eyes.T_root_camera(T_head, "right", 0.0, 0.0, 0.0)
    assert np.linalg.norm(Tl[:3, 3] - Tr[:3, 3]) == pytest.approx(0.068, abs=1e-12)
    assert Tl[1, 3] < Tr[1, 3]
    np.testing.assert_allclose(Tl[:3, 2], [-1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(Tl[:3, 0], [0.0, 1.0, 0.0], atol=1e-12)  # image x = right
    Tl = eyes.T_root_camera(T_head, "left", 0.0, 0.0, 0.3)
    Tr = eyes.T_root_camera(T_head, "right", 0.0, 0.0, 0.3)
    assert Tl[1, 2] > 0 > Tr[1, 2]  # left eye turns right, right eye turns left
    assert eyes.version_vergence(*eyes.pans(0.2, 0.1)) == pytest.approx((0.2, 0.1))
    with pytest.raises(UnknownName):
        eyes.T_head_camera("middle", 0.0, 0.0, 0.0)
    with pytest.raises(InvalidInput):
        eyes.T_head_camera("left", float("nan"), 0.0, 0.0)


def test_dh_transform_and_rpy():
    """dh_transform is Rz Tz Tx Rx; rpy_matrix is Rz(y) Ry(p) Rx(r) (URDF)."""
    T = dh_transform(0.1, 0.2, np.pi / 2, np.pi / 2)
    np.testing.assert_allclose(T[:3, 3], [0.0, 0.1, 0.2], atol=1e-12)
    np.testing.assert_allclose(rpy_matrix((0.0, 0.0, np.pi / 2)) @ [1, 0, 0], [0, 1, 0],
                               atol=1e-12)


def test_mesh_simplification_keeps_extent():
    """Vertex clustering reduces a dense mesh and keeps its bounding box within one cell."""
    from icub_sim_bridge.model_builder import ModelBuilder

    b = ModelBuilder(SimConfig(cameras_enabled=False))
    path = b.urdf.resolve_mesh(
        "package://iCub/meshes/simmechanics/sim_sea_2-5_l_elbow_prt-binary.stl", b.meshes_root)
    mesh = TriMesh.from_stl(path, (0.001, 0.001, 0.001))
    small = mesh.simplified(0.01)
    assert small.n_faces < mesh.n_faces / 3
    np.testing.assert_allclose(small.vertices.min(0), mesh.vertices.min(0), atol=0.01)
    np.testing.assert_allclose(small.vertices.max(0), mesh.vertices.max(0), atol=0.01)


def test_config_validation():
    """SimConfig rejects a bad mode, a non-positive timestep and a 2-value position."""
    with pytest.raises(ConfigError, match="mode"):
        SimConfig(mode="fast")
    with pytest.raises(ConfigError, match="timestep"):
        SimConfig(timestep=0.0)
    with pytest.raises(ConfigError, match="box_position"):
        SimConfig(box_position=(0.1, 0.2))


def test_shipped_camera_intrinsics():
    """config/sim_bridge.yaml holds the Gazebo iCub's eye-camera intrinsics and a 1 ms step."""
    from icub_pmp.config import config_dir, load_params_file

    params = load_params_file(config_dir() / "sim_bridge.yaml", "sim_bridge")
    # the realism.* parameters belong to RealismConfig (declared beside SimConfig by the node)
    cfg = SimConfig.from_dict({k: v for k, v in params.items() if not k.startswith("realism.")})
    assert (cfg.camera_width, cfg.camera_height, cfg.camera_fx, cfg.camera_cx,
            cfg.camera_cy) == (320, 240, 343.12, 160.0, 120.0)
    assert cfg.timestep == 0.001
