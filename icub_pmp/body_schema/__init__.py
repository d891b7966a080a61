"""The learned body schema (Bhat and Mohan, "Internal Body Model", eqs 1-2) and the learned
eye-hand map (force paper eq 12): tanh networks trained by Levenberg-Marquardt on babbling
data, a PMP body model from their Jacobians, and motor babbling itself. No ROS imports."""

from icub_pmp.body_schema.babbling import (
    HEAD_JOINTS,
    LEARNER_FIELDS,
    BabblingDataset,
    BabblingSample,
    MotorBabbling,
    load_dataset,
    min_jerk_move,
)
from icub_pmp.body_schema.babbling_config import BabblingConfig
from icub_pmp.body_schema.body_network import DEFAULT_HIDDEN, BodyNetwork, BodyPrediction
from icub_pmp.body_schema.eye_hand_map import (
    DEFAULT_EYE_HAND_HIDDEN,
    EYE_HAND_INPUTS,
    EyeHandMap,
)
from icub_pmp.body_schema.eye_hand_samples import (
    StereoSamples,
    babbled_hands,
    gaze_samples,
    perturbed_cameras,
    stereo_samples,
    view_samples,
)
from icub_pmp.body_schema.eye_hand_target import (
    TARGET_SOURCES,
    EyeHandPoints,
    EyeHandTargetConfig,
)
from icub_pmp.body_schema.jacobian_source import (
    JACOBIAN_SOURCES,
    JacobianSourceConfig,
    make_provider,
)
from icub_pmp.body_schema.learned_jacobian_provider import LearnedJacobianProvider
from icub_pmp.body_schema.lm_trainer import (
    LmTrainer,
    LmTrainerConfig,
    TrainingReport,
    check_dataset,
)
from icub_pmp.body_schema.marker_detector import (
    MarkerDetection,
    MarkerDetector,
    MarkerDetectorConfig,
)
from icub_pmp.body_schema.model_file import load_model, save_model
from icub_pmp.body_schema.tanh_mlp import TanhMlp

__all__ = [
    "BabblingConfig",
    "BabblingDataset",
    "BabblingSample",
    "HEAD_JOINTS",
    "LEARNER_FIELDS",
    "MarkerDetection",
    "MarkerDetector",
    "MarkerDetectorConfig",
    "MotorBabbling",
    "load_dataset",
    "min_jerk_move",
    "BodyNetwork",
    "BodyPrediction",
    "DEFAULT_EYE_HAND_HIDDEN",
    "DEFAULT_HIDDEN",
    "EYE_HAND_INPUTS",
    "EyeHandMap",
    "EyeHandPoints",
    "EyeHandTargetConfig",
    "StereoSamples",
    "TARGET_SOURCES",
    "perturbed_cameras",
    "stereo_samples",
    "gaze_samples",
    "babbled_hands",
    "view_samples",
    "JACOBIAN_SOURCES",
    "JacobianSourceConfig",
    "LearnedJacobianProvider",
    "make_provider",
    "LmTrainer",
    "LmTrainerConfig",
    "TanhMlp",
    "TrainingReport",
    "check_dataset",
    "load_model",
    "save_model",
]
