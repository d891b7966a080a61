"""Motion vision: independent-motion segmentation from LK failures (motionCUT), tracking and
stereo triangulation. No ROS imports. The benchmark's baselines and synthetic data are in
:mod:`icub_pmp.baselines`."""

from icub_pmp.vision.image_checks import to_gray
from icub_pmp.vision.looming_detector import LoomingDetector
from icub_pmp.vision.motion_blobs import MotionBlob, MotionBlobs
from icub_pmp.vision.motion_segmenter import MotionSegmenter
from icub_pmp.vision.motion_segmenter_config import MotionSegmenterConfig
from icub_pmp.vision.stereo_triangulator import StereoPoint, StereoTriangulator
from icub_pmp.vision.target_tracker import TargetTracker, TrackedTarget

__all__ = [
    "LoomingDetector",
    "MotionBlob",
    "MotionBlobs",
    "MotionSegmenter",
    "MotionSegmenterConfig",
    "StereoPoint",
    "StereoTriangulator",
    "TargetTracker",
    "TrackedTarget",
    "to_gray",
]
