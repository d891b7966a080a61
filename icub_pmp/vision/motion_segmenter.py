"""MotionSegmenter: independent-motion segmentation from Lucas-Kanade failures (motionCUT).

Sect. 5 of Metta, Natale, Nori, Sandini, "Force control and reaching movements on the iCub
humanoid robot": LK optical flow is run on a fixed, uniform grid of image points; for each
point ``p`` with estimated flow ``v`` the discrepancy of eq. 13

    M(p) = sum_{q in W} (I_t(p + q) - I_{t+1}(p + v + q))^2

says whether tracking succeeded (``M < Theta_M``) or failed (``M >= Theta_M``). Fast motion
(of the object or of the camera) is absorbed by the LK pyramid; failures from local rotation
and occlusion (cover/uncover at an object's border) mark motion independent of the observer.
Isolated failures are filtered out (a failing node needs failing grid neighbours), kept nodes
persist a few frames and are grouped into 8-connected blobs on the grid.

The pipeline as coded in motionCUT (icub-main ``src/modules/motionCUT/main.cpp``) is followed,
with eq. 13 evaluated
explicitly (OpenCV's own LK error is a mean absolute difference, not eq. 13). The eq. 13 test
stays the failure criterion; additions, each measured in ``bench/motion.py`` and switchable in
:class:`MotionSegmenterConfig`:

- temporal confirmation of kept failures (``confirm_frames``);
- the looming detector (:mod:`icub_pmp.vision.looming_detector`, ``accum_decay`` > 0): the
  ego-motion residuals of the nodes' LK flows, accumulated along their tracks over about ten
  frames; components that expand or contract (objects approaching or receding, too slow for
  eq. 13 between consecutive frames) count as failures, uniformly drifting ones (motion
  parallax of the off-axis eyes) do not;
- blob growth over adjacent nodes whose flow contradicts the ego-motion homography
  (``grow_by_flow``): the interior of a translating textured object does not fail eq. 13;
- results about frame t+1, the current frame: centroids from the nodes' tracked positions
  (``warp_to_current``), masks carried by each blob's object motion (``mask_to_current``)
  and, for objects moving against the ego-motion, refined per pixel by which of the two
  motions explains the pixel (``mask_refine``).
"""

from __future__ import annotations

import cv2
import numpy as np

from icub_pmp.vision.image_checks import to_gray
from icub_pmp.vision.looming_detector import LoomingDetector
from icub_pmp.vision.motion_blobs import MotionBlob, MotionBlobs
from icub_pmp.vision.motion_segmenter_config import MotionSegmenterConfig

__all__ = ["MotionSegmenter"]

_NEIGHBOURS_8 = np.array([[1, 1, 1], [1, 0, 1], [1, 1, 1]], np.float32)


class MotionSegmenter:
    """Stateful motion segmenter for one camera: feed frames in order with :meth:`process`.

    The grid is fixed: every frame the same grid points of frame t are tracked into frame t+1.
    State kept between frames: the previous grey image, the previous patches of eq. 13 and
    the persistence counters of the grid nodes.
    """

    def __init__(self, config: MotionSegmenterConfig | None = None):
        self.config = config or MotionSegmenterConfig()
        c = self.config
        self.grid_shape: tuple[int, int] = c.grid_shape
        rows, cols = self.grid_shape
        s = c.grid_step
        x0, y0 = c.grid_origin
        self.grid_origin = (x0, y0)
        gy, gx = np.mgrid[0:rows, 0:cols]
        #: (rows*cols, 2) float32 node positions (u, v) [px], row-major over the grid.
        self.nodes = np.stack([x0 + gx * s, y0 + gy * s], axis=-1).reshape(-1, 2).astype(np.float32)
        self.nodes.setflags(write=False)
        half = c.win_size // 2
        qy, qx = np.mgrid[-half : half + 1, -half : half + 1]
        # All eq. 13 patches tiled in one (rows*w, cols*w) image, patch of node (r, c) at
        # [r*w:(r+1)*w, c*w:(c+1)*w] (a wide layout keeps OpenCV's remap vectorised).
        gx_n = self.nodes[:, 0].reshape(rows, cols)
        gy_n = self.nodes[:, 1].reshape(rows, cols)
        map_x = _tile(gx_n[:, :, None, None] + qx[None, None]).astype(np.float32)
        map_y = _tile(gy_n[:, :, None, None] + qy[None, None]).astype(np.float32)
        #: (rows*w, cols*w, 2) float32 pixel coordinates of the tiled patches (remap map).
        self._map = np.ascontiguousarray(np.stack([map_x, map_y], axis=-1))
        self._patch_flat_idx = map_y.astype(np.intp) * c.image_width + map_x.astype(np.intp)
        border = np.zeros(self.grid_shape, bool)
        border[0, :] = border[-1, :] = border[:, 0] = border[:, -1] = True
        self._border = border
        self._checker = ((np.add.outer(np.arange(rows), np.arange(cols)) % 2) == 0).ravel()
        self._node_px = (self.nodes[:, 0].astype(np.intp), self.nodes[:, 1].astype(np.intp))
        self._criteria = (
            cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS,
            c.lk_max_iter,
            c.lk_epsilon,
        )
        e = 2 * c.mask_erosion + 1
        self._erode_kernel = cv2.getStructuringElement(cv2.MORPH_RECT, (e, e))
        self._cell_kernel = np.ones((s, s), np.uint8)
        self._region_kernel = np.ones((2 * s + 1, 2 * s + 1), np.uint8)
        self._looming = (
            LoomingDetector(self.nodes, self.grid_shape, s, c.accum_decay, c.accum_clip,
                            c.accum_tol, c.loom_tol, c.blob_min_size, c.loom_fill_hull)
            if c.accum_decay > 0.0 else None
        )
        self.reset()

    # ------------------------------------------------------------------ state
    def reset(self) -> None:
        """Forget the previous frame and the persistence counters (e.g. after a stream gap)."""
        self._prev_gray: np.ndarray | None = None
        self._prev_patches: np.ndarray | None = None
        self._prev_texture: np.ndarray | None = None
        self._ttl = np.zeros(self.grid_shape, np.int32)
        self._ego_flow: np.ndarray | None = None
        if self._looming is not None:
            self._looming.reset()
        self._recent: list[np.ndarray] = []
        self._frame_index = -1

    # ------------------------------------------------------------------ main step
    def process(self, image: np.ndarray) -> MotionBlobs:
        """Segment independent motion between the previous frame and ``image``.

        Args:
            image: (H, W) uint8 grey or (H, W, 3) uint8 RGB, of the configured size.

        Returns:
            The blobs of this frame (none on the first frame).

        Raises:
            InvalidInput: wrong dtype, channels or size (state unchanged).
        """
        c = self.config
        gray = to_gray(image, c.image_width, c.image_height)
        self._frame_index += 1
        patches = gray.ravel()[self._patch_flat_idx]
        rows, cols = self.grid_shape
        if self._prev_gray is None:
            self._store(gray, patches)
            return self._result(
                (),
                np.zeros((c.image_height, c.image_width), np.uint8),
                np.zeros(self.grid_shape, bool),
                np.zeros(self.grid_shape, bool),
                np.full((rows, cols, 2), np.nan, np.float32),
                np.zeros(self.grid_shape, np.float32),
            )
        prev_gray = self._prev_gray
        failures, flow, disc, tracked = self._failures(prev_gray, gray)
        self._store(gray, patches)
        self._ego_flow = None
        self._ego_h = None
        moving = reliable = np.zeros(self.grid_shape, bool)
        evidence = failures
        if self._looming is not None:
            moving, reliable = self._ego_residual(flow, tracked & ~failures)
            evidence = failures | self._looming.update(flow, self._ego_flow, reliable)
        kept = self._confirm(self._neighbour_filter(evidence))
        self._ttl = np.where(kept, c.frames_persistence, np.maximum(self._ttl - 1, 0))
        active = self._ttl > 0
        if c.grow_by_flow and active.any():
            if self._ego_flow is None:
                moving, reliable = self._ego_residual(flow, tracked & ~failures)
            # persisted nodes now tracked like the background have left the object
            left = active & ~kept & reliable & ~moving
            self._ttl[left] = 0
            active &= ~left
            active = self._grow(active, moving)
        disp = self._displacement(flow, tracked & ~failures)
        labels, blobs = self._blobs(active, disp, flow)
        if c.mask_to_current and blobs:
            mov = moving & reliable if self._ego_flow is not None else np.zeros_like(active)
            offsets, own = self._object_motions(labels, len(blobs), flow, mov, disp)
            mask = self._paint(labels > 0, offsets, c.mask_erosion)
            if c.mask_refine and self._ego_h is not None:
                mask = self._refine(mask, labels, offsets, own, prev_gray, gray)
        else:
            mask = self._mask(labels)
        return self._result(blobs, mask, failures, labels > 0, flow, disc)

    def _store(self, gray: np.ndarray, patches: np.ndarray) -> None:
        """Keep frame t for the next step: the image, its eq. 13 patches and each node's
        texture (grey-level standard deviation over its window)."""
        self._prev_gray = gray
        self._prev_patches = patches
        w = self.config.win_size
        f = gray.astype(np.float32)
        mean = cv2.boxFilter(f, -1, (w, w), borderType=cv2.BORDER_REPLICATE)
        sq = cv2.boxFilter(f * f, -1, (w, w), borderType=cv2.BORDER_REPLICATE)
        u, v = self._node_px
        self._prev_texture = np.sqrt(np.maximum(sq[v, u] - mean[v, u] ** 2, 0.0))

    def _result(self, blobs, mask, failures, active, flow, disc) -> MotionBlobs:
        return MotionBlobs(
            frame_index=self._frame_index,
            blobs=tuple(blobs),
            mask=mask,
            failures=failures,
            active=active,
            flow=flow,
            discrepancy=disc,
        )

    # ------------------------------------------------------------------ eq. 13
    def discrepancy(self, image_next: np.ndarray, flow: np.ndarray) -> np.ndarray:
        """Eq. 13 divided by |W| for every node, against the stored previous frame.

        Args:
            image_next: (H, W) uint8 grey frame t+1.
            flow: (N, 2) flow v of each node [px] (N = number of grid nodes).

        Returns:
            (N,) float32 ``M(p) / |W|`` [grey level^2]; bilinear interpolation at ``p + v``.
        """
        if self._prev_patches is None:
            raise RuntimeError("discrepancy() needs a previous frame: call process() first")
        rows, cols = self.grid_shape
        w = self.config.win_size
        v = np.ascontiguousarray(np.asarray(flow, np.float32).reshape(rows, cols, 2))
        # integer up-scaling with INTER_NEAREST = each node's flow over its w x w tile
        v_tiles = cv2.resize(v, (cols * w, rows * w), interpolation=cv2.INTER_NEAREST)
        nxt = cv2.remap(
            image_next,
            self._map + v_tiles,
            None,
            cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_REPLICATE,
        )
        # OpenCV rounds bilinear samples of uint8 images to integers: fine for a threshold.
        diff = cv2.subtract(self._prev_patches, nxt, dtype=cv2.CV_32F)
        # INTER_AREA by an integer factor = exact mean of each w x w patch: M(p) / |W|
        sq = cv2.multiply(diff, diff)
        return cv2.resize(sq, (cols, rows), interpolation=cv2.INTER_AREA).ravel()

    def _failures(
        self, prev_gray: np.ndarray, gray: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Eq. 13 test of every node: (failures, flow, M/|W|, tracked) on the grid.

        ``tracked``: LK found the node, its patch is textured and its track stays inside.
        """
        c = self.config
        rows, cols = self.grid_shape
        p0 = self.nodes.reshape(-1, 1, 2)
        p1, status, _err = cv2.calcOpticalFlowPyrLK(
            prev_gray,
            gray,
            p0,
            None,
            winSize=(c.win_size, c.win_size),
            maxLevel=c.pyramid_levels,
            criteria=self._criteria,
        )
        found = status.ravel().astype(bool)
        v = (p1.reshape(-1, 2) - self.nodes).astype(np.float32)
        v[~np.isfinite(v).all(axis=1)] = 0.0
        half = c.win_size // 2
        end = self.nodes + v
        inside = (
            (end[:, 0] >= half)
            & (end[:, 1] >= half)
            & (end[:, 0] < c.image_width - 1 - half)
            & (end[:, 1] < c.image_height - 1 - half)
        )
        disc = self.discrepancy(gray, np.where(found[:, None], v, 0.0))
        textured = self._prev_texture >= c.min_texture
        lk_fail = ~found if c.lk_status_is_failure else np.zeros_like(found)
        fail = textured & inside & ((found & (disc >= c.theta_m)) | lk_fail)
        fail = fail.reshape(rows, cols) & ~self._border
        flow = np.where(found[:, None], v, np.nan).reshape(rows, cols, 2).astype(np.float32)
        tracked = (found & textured & inside).reshape(rows, cols)
        return fail, flow, disc.reshape(rows, cols).astype(np.float32), tracked

    # ------------------------------------------------------------------ filters
    def _neighbour_filter(self, failures: np.ndarray) -> np.ndarray:
        """Failures with at least ``adj_nodes_thres`` failing 8-neighbours."""
        f = failures.astype(np.float32)
        counts = cv2.filter2D(f, -1, _NEIGHBOURS_8, borderType=cv2.BORDER_CONSTANT)
        return failures & (counts >= self.config.adj_nodes_thres - 0.5)

    def _confirm(self, kept: np.ndarray) -> np.ndarray:
        """Temporal confirmation: a kept failure counts only if kept failures were also found
        within ``confirm_radius`` nodes of it in each of the previous ``confirm_frames - 1``
        frames. Real motion makes LK fail frame after frame; a depth edge crossing a texture
        under ego-motion makes it fail once."""
        c = self.config
        if c.confirm_frames <= 1:
            return kept
        out = kept.copy()
        k = np.ones((2 * c.confirm_radius + 1, 2 * c.confirm_radius + 1), np.uint8)
        for prev in self._recent:
            out &= cv2.dilate(prev.astype(np.uint8), k).astype(bool)
        self._recent = ([kept] + self._recent)[: c.confirm_frames - 1]
        return out

    def _ego_residual(self, flow: np.ndarray, reliable: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
        """Nodes whose LK flow contradicts the ego-motion: (moving, reliable) grids.

        Ego-motion = homography fitted with RANSAC (tolerance ``flow_tol``) to the flow of the
        reliable nodes (tracked, textured, no eq. 13 failure); exact for a rotating camera and
        close to it for the small eye translation of a turning head. ``moving``: tracked
        nodes whose flow differs from it by ``flow_tol`` or more.
        """
        c = self.config
        rows, cols = self.grid_shape
        none = np.zeros(self.grid_shape, bool)
        v = flow.reshape(-1, 2)
        ok = reliable.ravel()
        self._ego_flow = None
        if ok.sum() < 8:
            return none, none
        fit = ok & self._checker  # every other node: as accurate, half the RANSAC time
        if fit.sum() < 8:
            fit = ok
        src = self.nodes[fit]
        h, _ = cv2.findHomography(src, src + v[fit], cv2.RANSAC, c.flow_tol)
        if h is None:
            return none, none
        self._ego_h = h
        pred = cv2.perspectiveTransform(self.nodes[None], h)[0] - self.nodes
        self._ego_flow = pred.reshape(rows, cols, 2)
        res = np.linalg.norm(np.nan_to_num(v - pred, nan=0.0), axis=1)
        moving = ((res >= c.flow_tol) & np.isfinite(v).all(axis=1)).reshape(rows, cols)
        return moving & ~self._border, reliable

    def _grow(self, active: np.ndarray, moving: np.ndarray) -> np.ndarray:
        """Extend the blobs that pass ``blob_min_size`` over adjacent ``moving`` nodes.

        The interior of a textured object that translates is tracked well (no eq. 13
        failure): only its border fails. Growth starts only from blobs motionCUT would
        report, so it never creates a blob in a scene without one.
        """
        c = self.config
        rows, cols = self.grid_shape
        n, labels, stats, _ = cv2.connectedComponentsWithStats(
            active.astype(np.uint8), connectivity=8
        )
        big = np.nonzero(stats[:, cv2.CC_STAT_AREA] > c.blob_min_size)[0]
        big = big[big > 0]
        if big.size == 0:
            return active
        grown = np.isin(labels, big)
        kernel = np.ones((3, 3), np.uint8)
        for _ in range(rows + cols):
            nxt = grown | (cv2.dilate(grown.astype(np.uint8), kernel).astype(bool) & moving)
            if (nxt == grown).all():
                break
            grown = nxt
        return active | grown

    def _displacement(self, flow: np.ndarray, reliable: np.ndarray) -> np.ndarray:
        """(rows, cols, 2) displacement from frame t to t+1 of each node's evidence: its LK
        flow where tracking succeeded, else the ego-motion (homography) flow, else 0."""
        rows, cols = self.grid_shape
        if not self.config.warp_to_current:
            return np.zeros((rows, cols, 2), np.float32)
        base = self._ego_flow if self._ego_flow is not None else np.zeros((rows, cols, 2))
        return np.where(reliable[:, :, None], np.nan_to_num(flow), base).astype(np.float32)

    def _blobs(self, active: np.ndarray, disp: np.ndarray, flow: np.ndarray
               ) -> tuple[np.ndarray, list[MotionBlob]]:
        """8-connected components of the ON nodes (holes filled), sorted by size.

        Returns the grid of blob ranks (0 = none, 1 = largest) and the blobs. The bounding
        box covers the nodes' cells at their grid positions (as the mask); the centroid is
        the mean of the nodes' positions in the current frame, ``p + disp``.
        """
        c = self.config
        grid = active.astype(np.uint8)
        if c.fill_holes and grid.any():
            grid = _fill_holes(grid)
        n, labels, stats, _ = cv2.connectedComponentsWithStats(grid, connectivity=8)
        s = c.grid_step
        x0, y0 = self.grid_origin
        half = s // 2
        out: list[MotionBlob] = []
        relabel = np.zeros(n, np.int32)
        candidates = [k for k in range(1, n) if stats[k, cv2.CC_STAT_AREA] > c.blob_min_size]
        candidates.sort(key=lambda k: -stats[k, cv2.CC_STAT_AREA])
        for rank, k in enumerate(candidates, start=1):
            relabel[k] = rank
            rr, cc = np.nonzero(labels == k)
            fl = flow[rr, cc].astype(np.float64)
            good = np.isfinite(fl).all(axis=1)
            mf = fl[good].mean(axis=0) if good.any() else np.zeros(2)
            u, v = x0 + cc * s, y0 + rr * s
            d = disp[rr, cc].astype(np.float64)
            size = int(rr.size)
            out.append(
                MotionBlob(
                    centroid=(float((u + d[:, 0]).mean()), float((v + d[:, 1]).mean())),
                    size=size,
                    area=size * s * s,
                    bbox=(
                        int(u.min() - half),
                        int(v.min() - half),
                        int(u.max() - half + s - 1),
                        int(v.max() - half + s - 1),
                    ),
                    mean_flow=(float(mf[0]), float(mf[1])),
                )
            )
        return relabel[labels], out

    def _object_motions(self, labels: np.ndarray, n_blobs: int, flow: np.ndarray,
                        moving: np.ndarray, disp: np.ndarray
                        ) -> tuple[np.ndarray, list[np.ndarray | None]]:
        """Each blob's object motion from frame t to t+1 [px]: (offsets grid, per blob).

        ``v_obj`` is the median LK flow of the blob's nodes that move against the ego-motion
        (at least 3; the per-blob entry, else None), else the median displacement of its
        nodes. Every node of the blob gets ``v_obj`` in the (rows, cols, 2) offsets grid.
        """
        rows, cols = self.grid_shape
        offsets = np.zeros((rows * cols, 2), np.float32)
        own: list[np.ndarray | None] = []
        flat = labels.ravel()
        for k in range(1, n_blobs + 1):
            blob = flat == k
            m = blob & moving.ravel()
            d = flow.reshape(-1, 2)[m] if m.sum() >= 3 else disp.reshape(-1, 2)[blob]
            v_obj = np.median(np.nan_to_num(d), axis=0)
            offsets[blob] = v_obj
            own.append(v_obj if m.sum() >= 3 else None)
        return offsets.reshape(rows, cols, 2), own

    def _refine(self, mask: np.ndarray, labels: np.ndarray, offsets: np.ndarray,
                own: list[np.ndarray | None], prev_gray: np.ndarray, gray: np.ndarray
                ) -> np.ndarray:
        """Pixel-level masks of the blobs whose object moves against the ego-motion.

        For a blob with its own motion ``v_obj`` differing from the ego-motion by at least
        ``refine_min_motion`` px, every pixel x of its cells (carried to frame t+1, dilated
        by one cell) is explained by one of two motions: the object's, ``I_{t+1}(x)`` vs
        ``I_t(x - v_obj)``, or the background's, ``I_{t+1}(x)`` vs ``I_t(H^-1 x)`` (the
        ego-motion homography H). With ``e`` = mean squared difference over a
        ``refine_window`` box (eq. 13 per pixel): x is the object's if ``e_obj <
        refine_match`` and ``2 e_obj < e_ego``; if both motions explain it (untextured) the
        cell mask decides; otherwise (the background it uncovers, the background around it)
        it is not. Frame t+1 is the current frame: the mask is about it.
        """
        c = self.config
        out = mask.copy()
        hinv = np.linalg.inv(self._ego_h)
        ego = self._ego_flow.reshape(-1, 2)
        flat = labels.ravel()
        r = c.refine_window
        for k, v_obj in enumerate(own, start=1):
            if v_obj is None:
                continue
            blob = flat == k
            if np.linalg.norm(v_obj - np.median(ego[blob], axis=0)) < c.refine_min_motion:
                continue
            region = cv2.dilate(self._paint(blob.reshape(self.grid_shape), offsets, 0),
                                self._region_kernel)
            ys, xs = np.nonzero(region)
            if ys.size == 0:
                continue
            y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
            gy, gx = np.mgrid[y0:y1, x0:x1].astype(np.float32)
            now = gray[y0:y1, x0:x1].astype(np.float32)
            b_obj = cv2.remap(prev_gray, gx - np.float32(v_obj[0]), gy - np.float32(v_obj[1]),
                              cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            den = hinv[2, 0] * gx + hinv[2, 1] * gy + hinv[2, 2]
            ex = ((hinv[0, 0] * gx + hinv[0, 1] * gy + hinv[0, 2]) / den).astype(np.float32)
            ey = ((hinv[1, 0] * gx + hinv[1, 1] * gy + hinv[1, 2]) / den).astype(np.float32)
            b_ego = cv2.remap(prev_gray, ex, ey, cv2.INTER_LINEAR,
                              borderMode=cv2.BORDER_REPLICATE)
            e_obj = cv2.boxFilter((now - b_obj) ** 2, -1, (r, r))
            e_ego = cv2.boxFilter((now - b_ego) ** 2, -1, (r, r))
            obj = (e_obj < c.refine_match) & (2.0 * e_obj < e_ego)
            both = (e_obj < c.refine_match) & (e_ego < c.refine_match) & ~obj
            reg = region[y0:y1, x0:x1] > 0
            keep = obj | (both & (mask[y0:y1, x0:x1] > 0))
            sub = out[y0:y1, x0:x1]
            sub[reg] = np.where(keep[reg], 255, 0).astype(np.uint8)
        return out

    def _paint(self, on: np.ndarray, offsets: np.ndarray, erosion: int) -> np.ndarray:
        """Paint a grid_step x grid_step cell (255) around ``p + offset`` of every ON node
        of the (rows, cols) grid ``on``, then erode by ``erosion`` px."""
        c = self.config
        mask = np.zeros((c.image_height, c.image_width), np.uint8)
        sel = on.ravel()
        pos = np.rint(self.nodes[sel] + offsets.reshape(-1, 2)[sel]).astype(np.intp)
        inside = ((pos[:, 0] >= 0) & (pos[:, 0] < c.image_width) & (pos[:, 1] >= 0)
                  & (pos[:, 1] < c.image_height))
        pos = pos[inside]
        if pos.size == 0:
            return mask
        mask[pos[:, 1], pos[:, 0]] = 255
        s = c.grid_step
        mask = cv2.dilate(mask, self._cell_kernel, anchor=(s // 2, s // 2))
        if erosion > 0:
            e = 2 * erosion + 1
            mask = cv2.erode(mask, cv2.getStructuringElement(cv2.MORPH_RECT, (e, e)))
        return mask

    def _mask(self, labels: np.ndarray) -> np.ndarray:
        """Paint each ON node of a kept blob as a grid_step x grid_step cell (255), then
        erode by ``mask_erosion`` px (the windows' overhang)."""
        c = self.config
        mask = np.zeros((c.image_height, c.image_width), np.uint8)
        if not labels.any():
            return mask
        s = c.grid_step
        rows, cols = self.grid_shape
        x0, y0 = self.grid_origin
        u0, v0 = x0 - s // 2, y0 - s // 2
        cells = np.repeat(np.repeat((labels > 0).astype(np.uint8) * 255, s, axis=0), s, axis=1)
        mask[v0 : v0 + rows * s, u0 : u0 + cols * s] = cells[
            : c.image_height - v0, : c.image_width - u0
        ]
        if c.mask_erosion > 0:
            mask = cv2.erode(mask, self._erode_kernel)
        return mask


def _fill_holes(grid: np.ndarray) -> np.ndarray:
    """Set to 1 the 0-regions (4-connected) of a uint8 grid that do not touch its border."""
    inv = (grid == 0).astype(np.uint8)
    _, labels = cv2.connectedComponents(inv, connectivity=4)
    edge = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    holes = (labels > 0) & ~np.isin(labels, edge)
    out = grid.copy()
    out[holes] = 1
    return out


def _tile(a: np.ndarray) -> np.ndarray:
    """(rows, cols, w, w) patches -> one (rows*w, cols*w) image."""
    rows, cols, h, w = a.shape
    return np.ascontiguousarray(a.transpose(0, 2, 1, 3).reshape(rows * h, cols * w))
