"""StereoTargetConfig: the parameters of the stereo object target (pairing, locating, tracking).

The motion segmenter finds *where* something moves in each eye; these parameters govern how
the two eyes' blobs are paired (:class:`~icub_pmp.vision.blob_pairing.BlobPairing`), how the
object's 3-D position is measured from the stereo pair
(:class:`~icub_pmp.vision.object_locator.ObjectLocator`: semi-global block matching over the
object's pixels, Hirschmueller 2008, as OpenCV's ``StereoSGBM``) and how the object is followed
in root_link (:class:`~icub_pmp.vision.object_tracker.ObjectTracker`). The numbers are set for
the iCub eyes (68 mm baseline, 320x240, fx 343 px) looking at objects on a table 0.3-0.7 m
away; ``bench/vision_reach.py`` measures them.
"""

from __future__ import annotations

import dataclasses

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["StereoTargetConfig"]


@dataclasses.dataclass(frozen=True)
class StereoTargetConfig(ConfigBase):
    """Parameters of the stereo target (names = ROS parameter names of motion_segmenter).

    Attributes:
        min_depth: nearest object distance searched along the optical axis; sets the
            disparity range of the block matching [m].
        max_depth: farthest accepted object [m].
        block_size: side of the block matching window (odd) [px].
        uniqueness_ratio: block matching uniqueness margin (OpenCV ``uniquenessRatio``) [%].
        stereo_min_texture: blocks of the rectified left image with a smaller grey-level
            standard deviation carry no disparity (untextured surfaces match anywhere)
            [grey level].
        roi_margin: the search region is the seed's bounding box grown by this on each side,
            and by as much again while the object's pixels touch its border [px].
        max_object_height: points higher than this above the support are not an object's [m].
        plane_band: points within this of the support plane are the support's [m].
        min_object_height: object pixels stand at least this high above the support [m].
        max_support_tilt: the support plane's normal may deviate this much from root_link's z
            (a table) [rad].
        top_band: points within this of the highest object level are its top face [m].
        max_depth_step: neighbouring pixels whose points are farther apart than this are on
            different surfaces (they do not connect an object's region) [m].
        min_object_points: fewer 3-D points on the object give no measurement [-].
        min_top_points: fewer top-face points give no measurement [-].
        disparity_sigma: standard deviation of one pixel's disparity [px] (covariance).
        model_sigma: standard deviation of the object model's own error (top face symmetry,
            silhouette fattening) added to the covariance on each axis [m].
        pair_max_row_offset: largest difference of the two blobs' rectified centroid rows
            (epipolar consistency) [px].
        pair_min_row_overlap: smallest overlap of the two blobs' rectified row ranges, as a
            fraction of the shorter one [-].
        pair_max_size_ratio: largest ratio of the two blobs' node counts [-].
        pair_max_flow_offset: largest difference of the two blobs' rectified vertical image
            motion (the same object moves by the same rows in both eyes) [px/frame].
        track_gate: a measurement farther than this from the predicted position is another
            object [m].
        still_speed: an object slower than this is still [m/s].
        still_frames: frames without a measurement after which a held target's velocity is
            zeroed (nobody sees it move: it stays) [-].
        hold_time: a target without any measurement is dropped after this [s].
        empty_hold_time: a target whose place both eyes see, with nothing there to measure
            (the object was taken away), is dropped after this [s] (``hold_time`` is for a
            place out of view or hidden by the robot's arm).
        switch_frames: frames another object must be measured, away from a followed one, to
            take over [-].
        position_noise: process noise of the constant-velocity tracker, as the standard
            deviation of the object's acceleration [m/s^2].
        self_radius: motion within this of the robot's hands or forearms is the robot's own
            (no target) [m].
        stereo_sync_tolerance: left and right frames pair when their stamps differ by at most
            this [s].
        joint_state_timeout: head/eye joint states farther than this from an image's stamp give
            no 3-D target [s].
        eye_calibration_file: the eye cameras as calibrated (``icub calibrate-eyes``,
            :class:`~icub_pmp.vision.eye_calibration.EyeCalibration`); empty = the nominal
            cameras of ``camera_info`` and the iKin eye chain. A relative path is taken from
            the repository root.
    """

    min_depth: float = 0.2
    max_depth: float = 1.5
    block_size: int = 5
    uniqueness_ratio: int = 10
    stereo_min_texture: float = 2.0
    roi_margin: int = 16
    max_object_height: float = 0.35
    plane_band: float = 0.006
    min_object_height: float = 0.012
    max_support_tilt: float = 0.35
    top_band: float = 0.004
    max_depth_step: float = 0.02
    min_object_points: int = 60
    min_top_points: int = 15
    disparity_sigma: float = 0.3
    model_sigma: float = 0.002
    pair_max_row_offset: float = 12.0
    pair_min_row_overlap: float = 0.5
    pair_max_size_ratio: float = 3.0
    pair_max_flow_offset: float = 3.0
    track_gate: float = 0.06
    still_speed: float = 0.02
    still_frames: int = 3
    hold_time: float = 30.0
    empty_hold_time: float = 1.0
    switch_frames: int = 3
    position_noise: float = 3.0
    self_radius: float = 0.07
    stereo_sync_tolerance: float = 0.02
    joint_state_timeout: float = 0.02
    eye_calibration_file: str = ""

    def validate(self) -> None:
        """Check ranges; raise :class:`ConfigError` naming the field."""
        name = type(self).__name__

        def bad(field: str, expected: str) -> ConfigError:
            return ConfigError(f"{name}.{field}: expected {expected}, got {getattr(self, field)!r}")

        if self.min_depth <= 0.0:
            raise bad("min_depth", "> 0 m")
        if self.max_depth <= self.min_depth:
            raise bad("max_depth", f"> min_depth ({self.min_depth} m)")
        if self.block_size < 3 or self.block_size % 2 == 0 or self.block_size > 21:
            raise bad("block_size", "an odd window side in 3..21 px")
        if not 0 <= self.uniqueness_ratio <= 50:
            raise bad("uniqueness_ratio", "0..50 %")
        if self.stereo_min_texture < 0.0:
            raise bad("stereo_min_texture", ">= 0 grey levels")
        if self.roi_margin < 0:
            raise bad("roi_margin", ">= 0 px")
        for f in ("plane_band", "min_object_height", "max_object_height", "top_band",
                  "max_depth_step", "track_gate", "self_radius"):
            if getattr(self, f) <= 0.0:
                raise bad(f, "> 0 m")
        if not 0.0 < self.max_support_tilt < 1.5:
            raise bad("max_support_tilt", "an angle in (0, 1.5) rad")
        for f in ("min_object_points", "min_top_points", "still_frames", "switch_frames"):
            if getattr(self, f) < 1:
                raise bad(f, ">= 1")
        for f in ("disparity_sigma", "position_noise", "pair_max_row_offset",
                  "pair_max_flow_offset"):
            if getattr(self, f) <= 0.0:
                raise bad(f, "> 0")
        if self.model_sigma < 0.0:
            raise bad("model_sigma", ">= 0 m")
        if not 0.0 <= self.pair_min_row_overlap <= 1.0:
            raise bad("pair_min_row_overlap", "a fraction in [0, 1]")
        if self.pair_max_size_ratio < 1.0:
            raise bad("pair_max_size_ratio", ">= 1")
        if self.still_speed < 0.0:
            raise bad("still_speed", ">= 0 m/s")
        if self.hold_time <= 0.0:
            raise bad("hold_time", "> 0 s")
        if self.empty_hold_time <= 0.0:
            raise bad("empty_hold_time", "> 0 s")
        for f in ("stereo_sync_tolerance", "joint_state_timeout"):
            if getattr(self, f) < 0.0:
                raise bad(f, ">= 0 s")
