"""Robot description and kinematics of the iCub (pinocchio on the icub-models URDF)."""

from icub_pmp.kinematics.robot_model import IcubModel
from icub_pmp.kinematics.robot_spec import RobotSpec, urdf_path

__all__ = ["IcubModel", "RobotSpec", "urdf_path"]
