"""Dynamics: the FT-cut RNEA model, the wrench estimator (wholeBodyDynamics role, eqs 1-3 and
8-10 of the force-control paper) and the incremental RFRR learner of Sect. 3.1."""

from icub_pmp.dynamics.butterworth_low_pass import ButterworthLowPass
from icub_pmp.dynamics.contact_detector import ContactDetector
from icub_pmp.dynamics.ft_dynamics_model import FT_JOINTS, FtDynamicsModel, SensorWrenches
from icub_pmp.dynamics.ft_offset_calibration import (
    CalibrationError,
    FtOffsetCalibration,
    FtOffsets,
)
from icub_pmp.dynamics.joint_state_filter import FilteredState, JointStateFilter
from icub_pmp.dynamics.random_features_ridge import RandomFeaturesRidge
from icub_pmp.dynamics.wrench_estimator import WrenchEstimate, WrenchEstimator
from icub_pmp.dynamics.wrench_estimator_config import WrenchEstimatorConfig

__all__ = [
    "ButterworthLowPass",
    "CalibrationError",
    "ContactDetector",
    "FT_JOINTS",
    "FtDynamicsModel",
    "FtOffsetCalibration",
    "FtOffsets",
    "SensorWrenches",
    "FilteredState",
    "JointStateFilter",
    "RandomFeaturesRidge",
    "WrenchEstimate",
    "WrenchEstimator",
    "WrenchEstimatorConfig",
]
