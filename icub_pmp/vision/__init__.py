"""Motion vision: independent-motion segmentation from LK failures (motionCUT), the stereo
target (blobs paired across the eyes, the object measured by stereo matching over its pixels,
tracked in root_link), tracking and triangulation. No ROS imports. The benchmark's baselines
and synthetic data are in :mod:`icub_pmp.baselines`."""

from icub_pmp.vision.blob_pairing import BlobPair, BlobPairing
from icub_pmp.vision.exceptions import ObjectNotFound
from icub_pmp.vision.image_checks import to_gray
from icub_pmp.vision.looming_detector import LoomingDetector
from icub_pmp.vision.motion_blobs import MotionBlob, MotionBlobs
from icub_pmp.vision.motion_segmenter import MotionSegmenter
from icub_pmp.vision.motion_segmenter_config import MotionSegmenterConfig
from icub_pmp.vision.object_locator import ObjectEstimate, ObjectGate, ObjectLocator
from icub_pmp.vision.object_tracker import TRACK_STATES, ObjectTracker, TrackedObject
from icub_pmp.vision.stereo_rectification import StereoRectification
from icub_pmp.vision.stereo_target import StereoTarget, StereoTargetResult
from icub_pmp.vision.stereo_target_config import StereoTargetConfig
from icub_pmp.vision.stereo_triangulator import StereoPoint, StereoTriangulator
from icub_pmp.vision.target_tracker import TargetTracker, TrackedTarget

__all__ = [
    "BlobPair",
    "BlobPairing",
    "LoomingDetector",
    "MotionBlob",
    "MotionBlobs",
    "MotionSegmenter",
    "MotionSegmenterConfig",
    "ObjectEstimate",
    "ObjectGate",
    "ObjectLocator",
    "ObjectNotFound",
    "ObjectTracker",
    "StereoPoint",
    "StereoRectification",
    "StereoTarget",
    "StereoTargetConfig",
    "StereoTargetResult",
    "StereoTriangulator",
    "TRACK_STATES",
    "TargetTracker",
    "TrackedObject",
    "TrackedTarget",
    "to_gray",
]
