"""MotionSegmenterConfig: the parameters of the motionCUT-style segmenter and its node.

Defaults follow motionCUT as coded in icub-main (``src/modules/motionCUT/main.cpp``): grid step
6 px,
LK 30 iterations / eps 0.3, at least 4 of 8 failing neighbours, 3-frame persistence, blobs of
more than 10 nodes, grid over the central 0.75 x 0.75 of the image. Departures, each measured
in ``bench/motion.py`` (BENCHMARKS.md): an 11x11 window instead of 15x15 (13x13 gave the same
F1 at 1.2x the speed, 11x11 the same F1 again at a further 1.35x: the 100 frames/s goal), 3
pyramid levels instead of 5 (same F1: the fastest image motion of the evaluation, about
28 px/frame, is within the reach of 3 levels; each level costs the same per node, so LK is
about 16 % faster), motionCUT's rule that only LK-found nodes can fail
(``lk_status_is_failure`` false), and these additions: temporal confirmation, flow-based blob
growth, ego-motion-warped centroids and masks (refined per pixel for objects that move against
the ego-motion), and a looming detector (accumulated ego-motion residuals whose components
expand: objects approaching or receding, which eq. 13 between consecutive frames cannot see).
``theta_m`` is the eq. 13 threshold of Sect. 5 of the force-control paper (Metta et al.),
expressed per window pixel.
"""

from __future__ import annotations

import dataclasses

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["MotionSegmenterConfig"]


@dataclasses.dataclass(frozen=True)
class MotionSegmenterConfig(ConfigBase):
    """Parameters of :class:`~icub_pmp.vision.MotionSegmenter` (names = ROS parameter names).

    Attributes:
        image_width: expected image width [px]; other sizes are rejected.
        image_height: expected image height [px].
        grid_step: spacing of the fixed grid of LK nodes [px] (motionCUT ``nodesStep``).
        cover_x_ratio: fraction of the image width covered by the grid (centred) [-].
        cover_y_ratio: fraction of the image height covered by the grid (centred) [-].
        win_size: side of the square LK window and of the eq. 13 patch W [px] (odd).
        pyramid_levels: LK pyramid levels above the full image (OpenCV ``maxLevel``).
        lk_max_iter: LK iterations per level.
        lk_epsilon: LK stop threshold on the update [px].
        theta_m: eq. 13 threshold divided by the window area: a node fails when
            ``M(p) / win_size**2 >= theta_m`` [grey level^2], grey levels in 0..255.
        min_texture: nodes whose frame-t patch has a grey-level standard deviation below this
            carry no evidence (LK cannot track them) and never fail [grey level].
        lk_status_is_failure: count an LK "not found" status of a textured node whose track
            stays inside the image as a failure (the issue's "LK fails").
        adj_nodes_thres: a failing node is kept only if at least this many of its 8 grid
            neighbours also fail (isolated-failure filter, motionCUT ``adjNodesThres``).
        confirm_frames: a kept failure counts only if there were kept failures near it
            (``confirm_radius``) in each of the last ``confirm_frames - 1`` frames too
            (1 = off, motionCUT; 2 = one frame of latency, no one-frame flashes).
        confirm_radius: neighbourhood of the temporal confirmation [grid nodes]; must cover
            the fastest object's image motion per frame.
        frames_persistence: a kept node stays ON this many frames (motionCUT).
        blob_min_size: blobs with at most this many nodes are discarded (motionCUT).
        grow_by_flow: extend failure blobs over adjacent tracked nodes whose LK flow differs
            from the ego-motion (a homography fitted to the tracked nodes) by ``flow_tol``.
        flow_tol: flow residual to the ego-motion marking a tracked node as moving, and the
            RANSAC tolerance of the ego-motion fit [px/frame].
        fill_holes: mark grid nodes enclosed by a blob as part of it (the interior of a
            uniformly textured object tracks well; only its border fails).
        warp_to_current: blob centroids from the nodes' positions in the current frame:
            ``p + v`` for nodes tracked without failure, ``p`` + the ego-motion flow for the
            others (the grid is fixed in frame t, the result is about frame t+1). The bbox
            stays on the grid cells (motionCUT); for the mask see ``mask_to_current``.
        mask_erosion: erosion of the output mask [px]: a node fails as soon as its window
            (half side ``win_size // 2``) reaches the object, so failure regions overhang the
            object by about that much.
        mask_to_current: paint each blob's mask cells shifted by its object's image motion
            from frame t to t+1 (median LK flow of its nodes that move against the
            ego-motion, else of all its nodes), so the mask is about the current frame as the
            ground truth is; false: the cells at the grid positions of frame t (motionCUT).
        mask_refine: with ``mask_to_current``, refine per pixel the masks of blobs whose
            object moves against the ego-motion by ``refine_min_motion`` or more: a pixel is
            the object's when the object's motion explains it (``I_{t+1}(x)`` vs
            ``I_t(x - v_obj)``, mean squared difference over ``refine_window`` below
            ``refine_match`` and under half that of the ego-motion homography); untextured
            pixels both explain keep the cell mask.
        refine_min_motion: object motion relative to the ego-motion needed to refine [px/frame].
        refine_window: side of the box the pixel test averages over (odd) [px].
        refine_match: mean squared difference below which a motion explains a pixel
            [grey level^2].
        accum_decay: looming detector (an addition to motionCUT,
            :mod:`~icub_pmp.vision.looming_detector`): weight of the accumulated ego-motion
            residual carried along a node's track to the next frame, memory about
            ``1 / (1 - accum_decay)`` frames; 0 = off [-].
        accum_clip: largest per-frame ego-motion residual a node adds [px/frame].
        accum_tol: accumulated residual marking a node as a looming candidate [px].
        loom_tol: expansion (|a| * rms radius of the fit t + a d + w perp(d)) an 8-connected
            component of candidates (more than ``blob_min_size`` nodes) needs to count as
            failures: an object approaching or receding, not motion parallax [px].
        loom_fill_hull: a looming component counts with all nodes inside its convex hull on
            the grid (the expansion centre barely moves, so the candidates form a ring or a
            crescent around the object's interior).
        target_alpha: exponential smoothing of the tracked target centroid, weight of the
            new measurement in (0, 1] [-].
        target_hold_frames: frames the target is kept after its blob disappears.
        target_max_jump: a largest blob whose centroid is farther than this from the target
            needs ``target_switch_frames`` consecutive frames to take over [px].
        target_switch_frames: frames a distant largest blob must persist to become the target.

    The 3-D target (pairing the eyes' blobs, stereo measurement, tracking) has its own
    parameters: :class:`~icub_pmp.vision.stereo_target_config.StereoTargetConfig`.
    """

    image_width: int = 320
    image_height: int = 240
    grid_step: int = 6
    cover_x_ratio: float = 0.75
    cover_y_ratio: float = 0.75
    win_size: int = 11
    pyramid_levels: int = 3
    lk_max_iter: int = 30
    lk_epsilon: float = 0.3
    theta_m: float = 40.0
    min_texture: float = 2.0
    lk_status_is_failure: bool = False
    adj_nodes_thres: int = 4
    confirm_frames: int = 2
    confirm_radius: int = 3
    frames_persistence: int = 3
    blob_min_size: int = 10
    grow_by_flow: bool = True
    flow_tol: float = 0.5
    fill_holes: bool = True
    warp_to_current: bool = True
    mask_erosion: int = 5
    mask_to_current: bool = True
    mask_refine: bool = True
    refine_min_motion: float = 2.0
    refine_window: int = 5
    refine_match: float = 150.0
    accum_decay: float = 0.9
    accum_clip: float = 1.0
    accum_tol: float = 1.0
    loom_tol: float = 0.5
    loom_fill_hull: bool = True
    target_alpha: float = 0.5
    target_hold_frames: int = 10
    target_max_jump: float = 60.0
    target_switch_frames: int = 3

    def validate(self) -> None:
        """Check ranges; raise :class:`ConfigError` naming the field."""
        name = type(self).__name__

        def bad(field: str, expected: str) -> ConfigError:
            return ConfigError(f"{name}.{field}: expected {expected}, got {getattr(self, field)!r}")

        for f in ("image_width", "image_height"):
            if getattr(self, f) < 16:
                raise bad(f, "an image side >= 16 px")
        if self.grid_step < 1:
            raise bad("grid_step", ">= 1 px")
        for f in ("cover_x_ratio", "cover_y_ratio"):
            if not 0.0 < getattr(self, f) <= 1.0:
                raise bad(f, "a ratio in (0, 1]")
        if self.win_size < 3 or self.win_size % 2 == 0:
            raise bad("win_size", "an odd window side >= 3 px")
        if not 0 <= self.pyramid_levels <= 8:
            raise bad("pyramid_levels", "0..8")
        if self.lk_max_iter < 1:
            raise bad("lk_max_iter", ">= 1")
        if self.lk_epsilon <= 0.0:
            raise bad("lk_epsilon", "> 0 px")
        if self.theta_m <= 0.0:
            raise bad("theta_m", "> 0 grey level^2")
        if self.min_texture < 0.0:
            raise bad("min_texture", ">= 0 grey levels")
        if not 0 <= self.adj_nodes_thres <= 8:
            raise bad("adj_nodes_thres", "0..8 neighbours")
        if self.confirm_frames < 1:
            raise bad("confirm_frames", ">= 1 frame")
        if self.confirm_radius < 0:
            raise bad("confirm_radius", ">= 0 nodes")
        if self.frames_persistence < 1:
            raise bad("frames_persistence", ">= 1 frame")
        if self.blob_min_size < 0:
            raise bad("blob_min_size", ">= 0 nodes")
        if self.flow_tol <= 0.0:
            raise bad("flow_tol", "> 0 px/frame")
        if self.mask_erosion < 0:
            raise bad("mask_erosion", ">= 0 px")
        if self.refine_min_motion < 0.0:
            raise bad("refine_min_motion", ">= 0 px/frame")
        if self.refine_window < 1 or self.refine_window % 2 == 0:
            raise bad("refine_window", "an odd box side >= 1 px")
        if self.refine_match <= 0.0:
            raise bad("refine_match", "> 0 grey level^2")
        if not 0.0 <= self.accum_decay < 1.0:
            raise bad("accum_decay", "a weight in [0, 1)")
        for f in ("accum_clip", "accum_tol", "loom_tol"):
            if getattr(self, f) <= 0.0:
                raise bad(f, "> 0 px")
        if not 0.0 < self.target_alpha <= 1.0:
            raise bad("target_alpha", "a weight in (0, 1]")
        if self.target_hold_frames < 0:
            raise bad("target_hold_frames", ">= 0 frames")
        if self.target_max_jump <= 0.0:
            raise bad("target_max_jump", "> 0 px")
        if self.target_switch_frames < 1:
            raise bad("target_switch_frames", ">= 1 frame")
        if self.grid_shape[0] < 3 or self.grid_shape[1] < 3:
            raise ConfigError(
                f"{name}: grid of {self.grid_shape} nodes is too small (grid_step "
                f"{self.grid_step}, cover {self.cover_x_ratio}x{self.cover_y_ratio}, image "
                f"{self.image_width}x{self.image_height}); need at least 3x3"
            )
        rows, cols = self.grid_shape
        x0, y0 = self.grid_origin
        half = self.win_size // 2
        if (
            x0 - half < 0
            or y0 - half < 0
            or x0 + (cols - 1) * self.grid_step + half >= self.image_width
            or y0 + (rows - 1) * self.grid_step + half >= self.image_height
        ):
            raise ConfigError(
                f"{name}: windows of {self.win_size} px around the grid (cover "
                f"{self.cover_x_ratio}x{self.cover_y_ratio}, step {self.grid_step}) leave the "
                f"{self.image_width}x{self.image_height} image; reduce the cover ratios or win_size"
            )

    @property
    def grid_shape(self) -> tuple[int, int]:
        """Number of grid nodes (rows, cols): 31 x 41 for the defaults at 320x240."""
        cols = int(self.cover_x_ratio * self.image_width) // self.grid_step + 1
        rows = int(self.cover_y_ratio * self.image_height) // self.grid_step + 1
        return rows, cols

    @property
    def grid_origin(self) -> tuple[int, int]:
        """Image position (u, v) of grid node (0, 0) [px]: (40, 30) for the defaults."""
        rows, cols = self.grid_shape
        return (
            (self.image_width - (cols - 1) * self.grid_step) // 2,
            (self.image_height - (rows - 1) * self.grid_step) // 2,
        )
