"""Baselines the papers' methods are compared with, and the benchmark data that need no
simulator. No ROS imports; nothing in the other cores imports this package.

- :class:`DlsSolver`: damped-least-squares inverse kinematics, the classical baseline of the
  PMP paper (Sect. 1) and of the Cartesian solver (Sect. 4.1 of the reaching paper).
- :class:`Mog2Detector`, :class:`FlowResidualDetector`: motion-detection baselines of the
  motion segmenter.
- :class:`SyntheticSequence`: textured scenes seen by a rotating camera with a moving patch;
  :class:`SegmentationCounts`: pixel precision / recall / F1.

Benchmark data rendered by the simulator live in :mod:`icub_sim_bridge.harness`.
"""

from icub_pmp.baselines.dls_solver import PMP_DLS_CONFIG, DlsConfig, DlsResult, DlsSolver
from icub_pmp.baselines.flow_residual_detector import FlowResidualDetector
from icub_pmp.baselines.mog2_detector import Mog2Detector
from icub_pmp.baselines.segmentation_metrics import SegmentationCounts
from icub_pmp.baselines.synthetic_sequence import (
    SyntheticFrame,
    SyntheticSequence,
    textured_image,
    triangle_wave,
)

__all__ = [
    "PMP_DLS_CONFIG",
    "DlsConfig",
    "DlsResult",
    "DlsSolver",
    "FlowResidualDetector",
    "Mog2Detector",
    "SegmentationCounts",
    "SyntheticFrame",
    "SyntheticSequence",
    "textured_image",
    "triangle_wave",
]
