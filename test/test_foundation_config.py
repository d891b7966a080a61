"""Configuration loading: ConfigBase, ROS parameter files (every shipped one), the robot spec."""

from __future__ import annotations

import dataclasses
import math

import pytest

from icub_pmp.body_schema import (
    BabblingConfig,
    EyeHandTargetConfig,
    JacobianSourceConfig,
    MarkerDetectorConfig,
)
from icub_pmp.cartesian import IkConfig, MinJerkConfig
from icub_pmp.config import ConfigBase, config_dir, load_params_file
from icub_pmp.control import ImpedanceControllerConfig
from icub_pmp.control.arrival_monitor import ArrivalConfig
from icub_pmp.dynamics import WrenchEstimatorConfig
from icub_pmp.errors import ConfigError, UnknownName
from icub_pmp.gaze import GazeControllerConfig, GazeNodeConfig
from icub_pmp.kinematics import IcubModel, RobotSpec
from icub_pmp.peripersonal import CollisionCheckConfig, PeripersonalConfig
from icub_pmp.peripersonal.peripersonal_node_config import PeripersonalNodeConfig
from icub_pmp.pmp import PmpConfig
from icub_pmp.ros.cartesian_node_config import CartesianNodeConfig
from icub_pmp.ros.pmp_node_config import PmpNodeConfig
from icub_pmp.ros.reach_request import ReachRequestConfig
from icub_pmp.ros.robot_state_publisher_config import RobotStatePublisherConfig
from icub_pmp.vision import MotionSegmenterConfig, StereoTargetConfig
from icub_sim_bridge import RealismConfig, SimConfig

#: config/<node>.yaml -> the configuration classes the node declares as its parameters
NODE_CONFIGS: dict[str, tuple[type[ConfigBase], ...]] = {
    "body_schema": (BabblingConfig, MarkerDetectorConfig),
    "cartesian_solver": (IkConfig, MinJerkConfig, CartesianNodeConfig, ArrivalConfig),
    "gaze_controller": (GazeControllerConfig, GazeNodeConfig),
    "impedance_controller": (ImpedanceControllerConfig,),
    "motion_segmenter": (MotionSegmenterConfig, StereoTargetConfig, EyeHandTargetConfig),
    "peripersonal_space": (PeripersonalConfig, CollisionCheckConfig, PeripersonalNodeConfig,
                           JacobianSourceConfig),
    "pmp_planner": (PmpConfig, PmpNodeConfig, ArrivalConfig, ReachRequestConfig,
                    JacobianSourceConfig),
    "robot_state_publisher": (RobotStatePublisherConfig,),
    "sim_bridge": (SimConfig, RealismConfig),
    "wrench_estimator": (WrenchEstimatorConfig,),
}
NOT_NODE_FILES = {"robot.yaml"}  # the robot description, not a --params-file
ROS_NODE_PARAMETERS = ("use_sim_time",)  # declared by rclpy for every node


@dataclasses.dataclass(frozen=True)
class _Gains(ConfigBase):
    stiffness: float = 1.0
    joints: tuple[str, ...] = ()
    steps: int = 10

    def validate(self) -> None:
        if self.stiffness < 0:
            raise ConfigError(f"stiffness must be >= 0, got {self.stiffness}")


def test_from_dict_rejects_unknown_keys_by_name():
    """An unknown parameter is named in the error together with the valid ones."""
    with pytest.raises(ConfigError, match=r"unknown parameter\(s\) \['stifness'\]"):
        _Gains.from_dict({"stifness": 2.0})


def test_from_dict_coerces_and_validates():
    """Ints become floats, lists become tuples, validate() runs, wrong types are refused."""
    g = _Gains.from_dict({"stiffness": 2, "joints": ["a", "b"], "steps": 3})
    assert g.stiffness == 2.0 and isinstance(g.stiffness, float)
    assert g.joints == ("a", "b")
    with pytest.raises(ConfigError, match="stiffness must be >= 0"):
        _Gains.from_dict({"stiffness": -1.0})
    with pytest.raises(ConfigError, match="expected int"):
        _Gains.from_dict({"steps": 2.5})
    with pytest.raises(ConfigError, match="NaN"):
        _Gains(stiffness=math.nan)


def test_params_file_keys(tmp_path):
    """`/**/node:`, `node:` and `/**:` blocks are all read; nested keys flatten with dots."""
    f = tmp_path / "p.yaml"
    f.write_text(
        "/**:\n  ros__parameters:\n    use_sim_time: true\n"
        "/**/planner:\n  ros__parameters:\n    gains:\n      k: 3.0\n    tau: 2.0\n"
    )
    p = load_params_file(f, "planner")
    assert p == {"use_sim_time": True, "gains.k": 3.0, "tau": 2.0}
    g = tmp_path / "q.yaml"
    g.write_text("planner:\n  ros__parameters:\n    tau: 1.0\n")
    with pytest.raises(ConfigError, match="no ros__parameters for node 'other'"):
        load_params_file(g, "other")


def test_robot_spec_is_consistent_with_the_urdf():
    """Every joint of robot.yaml exists in the URDF model and has a positive torque limit."""
    spec = RobotSpec.load()
    model = IcubModel(spec)
    assert set(model.joint_names) == set(spec.upper_body_joints)
    assert model.nq == 20
    assert all(t > 0 for t in model.torque_limits)
    for frame in list(spec.hand_frames.values()) + list(spec.arm_ft_frames.values()):
        model.frame_id(frame)
    rest = model.posture("rest")
    assert all(model.lower <= rest) and all(rest <= model.upper)


def test_unknown_names_list_valid_choices():
    """Unknown joints, frames and postures raise UnknownName listing what exists."""
    model = IcubModel()
    with pytest.raises(UnknownName, match="r_elbow"):
        model.indices(["r_elbo"])
    with pytest.raises(UnknownName, match="r_hand_dh_frame"):
        model.frame_id("r_hand_dh")
    with pytest.raises(UnknownName, match="rest"):
        RobotSpec.load().posture("sleep")


def test_every_shipped_params_file_parses():
    """Every config/*.yaml is valid YAML; node files have a ros__parameters block."""
    import yaml

    for f in sorted(config_dir().glob("*.yaml")):
        data = yaml.safe_load(f.read_text())
        assert isinstance(data, dict), f
        if f.name != "robot.yaml":
            assert any(
                isinstance(v, dict) and "ros__parameters" in v for v in data.values()
            ), f"{f.name} has no ros__parameters block"


def test_every_shipped_params_file_has_its_configurations():
    """Each config/<node>.yaml belongs to a node listed in NODE_CONFIGS (add yours there)."""
    files = {f.stem for f in config_dir().glob("*.yaml") if f.name not in NOT_NODE_FILES}
    assert files == set(NODE_CONFIGS), (
        f"without an entry in NODE_CONFIGS: {sorted(files - set(NODE_CONFIGS))}; "
        f"listed without a file: {sorted(set(NODE_CONFIGS) - files)}")


@pytest.mark.parametrize("node", sorted(NODE_CONFIGS))
def test_shipped_params_file_loads_into_its_configurations(node):
    """config/<node>.yaml: every key is a field of one of the node's configuration classes
    (field names = ROS parameter names) or a parameter of every ROS node (``use_sim_time``),
    and each class builds from it (types and ranges validated)."""
    path = config_dir() / f"{node}.yaml"
    params = load_params_file(path, node)
    known: set[str] = set(ROS_NODE_PARAMETERS)
    for cls in NODE_CONFIGS[node]:
        cfg = cls.from_yaml(path, node)
        known |= set(cls.field_names())
        assert cfg == cls.from_dict({k: v for k, v in params.items() if k in cls.field_names()})
    assert set(params) <= known, f"{path.name}: unknown keys {sorted(set(params) - known)}"
