"""Motion vision: independent-motion segmentation from LK failures (motionCUT), tracking,
stereo triangulation, and the benchmark's baselines and data. No ROS imports."""

from icub_pmp.vision.flow_residual_detector import FlowResidualDetector
from icub_pmp.vision.image_checks import to_gray
from icub_pmp.vision.looming_detector import LoomingDetector
from icub_pmp.vision.mog2_detector import Mog2Detector
from icub_pmp.vision.motion_blobs import MotionBlob, MotionBlobs
from icub_pmp.vision.motion_segmenter import MotionSegmenter
from icub_pmp.vision.motion_segmenter_config import MotionSegmenterConfig
from icub_pmp.vision.segmentation_metrics import SegmentationCounts
from icub_pmp.vision.stereo_triangulator import StereoPoint, StereoTriangulator
from icub_pmp.vision.synthetic_sequence import SyntheticFrame, SyntheticSequence, textured_image
from icub_pmp.vision.target_tracker import TargetTracker, TrackedTarget

__all__ = [
    "FlowResidualDetector",
    "LoomingDetector",
    "Mog2Detector",
    "MotionBlob",
    "MotionBlobs",
    "MotionSegmenter",
    "MotionSegmenterConfig",
    "SegmentationCounts",
    "StereoPoint",
    "StereoTriangulator",
    "SyntheticFrame",
    "SyntheticSequence",
    "TargetTracker",
    "TrackedTarget",
    "textured_image",
    "to_gray",
]
