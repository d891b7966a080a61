"""ObjectLocator: the 3-D position of an object on a support, from the stereo pair.

Why not triangulate the two blobs' centroids: each eye sees a different part of an object
(and the motion masks cover the moving object only approximately), so the centroid rays pass
through different surface points, and their "intersection" is none of the object's points
(the cylinder of the demo came out 3-7 cm away). Here the motion mask only says *where to
look*; the object's 3-D shape is measured from the current images:

1. both images are rectified (:class:`~icub_pmp.vision.stereo_rectification.
   StereoRectification`) and a disparity map is computed over the seed's region by semi-global
   block matching (Hirschmueller, "Stereo processing by semiglobal matching and mutual
   information", IEEE TPAMI 30(2), 2008; OpenCV ``StereoSGBM``, with its left-right check);
2. every matched pixel pair ``(u_l, v_l, u_r, v_r)`` becomes a point in root_link through
   ``points_fn``: ray triangulation with the head/eye kinematics by default
   (:meth:`~icub_pmp.vision.StereoTriangulator.triangulate_many`), or a learned eye-hand map
   (eq. 12 of the force-control paper, Metta et al.) that takes the same pixel pairs;
3. the support (the table) is the plane with most points around the seed (RANSAC, Fischler and
   Bolles 1981), its normal near root_link's z;
4. the object is the connected region of pixels standing above the support that overlaps the
   seed (the region grows while it touches the search window's border); its top face is the
   band of its highest points.

The estimate: the top face's centre (median of the top points: the whole top face is visible
from the iCub's eyes looking down at the table, so its centre is the object's axis for any
object symmetric about a vertical axis or plane), and the object's centre half its height
below, on the support normal. Its covariance combines the disparity noise of the top face
(``disparity_sigma`` per pixel, averaged over the top points in independent blocks), the top
points' scatter and ``model_sigma``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Callable, NamedTuple

import cv2
import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics, project_point
from icub_pmp.vision.exceptions import ObjectNotFound
from icub_pmp.vision.image_checks import to_gray
from icub_pmp.vision.stereo_rectification import StereoRectification
from icub_pmp.vision.stereo_target_config import StereoTargetConfig
from icub_pmp.vision.stereo_triangulator import StereoTriangulator

__all__ = ["ObjectLocator", "ObjectEstimate", "ObjectGate", "PointsFn"]

#: maps matched pixels (n, 2) left, (n, 2) right [px] to points (n, 3) in root_link [m]
PointsFn = Callable[[np.ndarray, np.ndarray], np.ndarray]

_UP = np.array([0.0, 0.0, 1.0])
_MAX_GROW = 3
_RANSAC_ITERATIONS = 64


class ObjectGate(NamedTuple):
    """Where a known object may be: its top centre (3,) [m] in root_link, its horizontal
    radius [m] and a margin [m] around both (points outside do not count)."""

    top: np.ndarray
    radius: float
    margin: float


@dataclasses.dataclass(frozen=True)
class ObjectEstimate:
    """One stereo measurement of an object resting on a support.

    Attributes:
        position: (3,) object centre in root_link [m] (top centre lowered by half the height).
        top: (3,) centre of the object's top face in root_link [m].
        covariance: (3, 3) covariance of ``position`` (and of ``top``) [m^2].
        height: height of the top face above the support [m].
        radius: horizontal extent of the object about its axis (90th percentile) [m].
        support_normal: (3,) unit normal of the support plane (upwards).
        support_point: (3,) a point of the support plane [m].
        n_points: 3-D points on the object.
        n_top: of which on the top face.
        seed_overlap: fraction of the rectified seed pixels that the object covers [-].
    """

    position: np.ndarray
    top: np.ndarray
    covariance: np.ndarray
    height: float
    radius: float
    support_normal: np.ndarray
    support_point: np.ndarray
    n_points: int
    n_top: int
    seed_overlap: float

    def __post_init__(self) -> None:
        for name in ("position", "top", "covariance", "support_normal", "support_point"):
            a = np.array(getattr(self, name), dtype=float, copy=True)
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    @property
    def sigma(self) -> float:
        """Root of the largest eigenvalue of the covariance [m] (1-sigma, worst axis)."""
        return float(math.sqrt(max(np.linalg.eigvalsh(self.covariance)[-1], 0.0)))


class ObjectLocator:
    """Measure objects in stereo pairs (module doc); parameters in :class:`StereoTargetConfig`."""

    def __init__(self, config: StereoTargetConfig | None = None):
        self.config = config or StereoTargetConfig()
        c = self.config
        self._open = np.ones((3, 3), np.uint8)
        self._block = c.block_size

    # ------------------------------------------------------------------ main
    def locate(self, rect: StereoRectification, left: np.ndarray, right: np.ndarray,
               seed: np.ndarray, points_fn: PointsFn | None = None,
               gate: ObjectGate | None = None) -> ObjectEstimate:
        """Measure the object the ``seed`` mask points at.

        Args:
            rect: rectification of the camera poses the images were taken at.
            left: (H, W) uint8 grey or (H, W, 3) RGB left image.
            right: the right image, same size.
            seed: (H, W) bool mask of the left image on (part of) the object, e.g. its motion
                blob or its projected previous estimate.
            points_fn: pixel pairs -> root_link points; default ray triangulation with the
                poses of ``rect``.
            gate: only points near a known object count (None: any).

        Raises:
            ObjectNotFound: no object measurable there (``reason`` says why).
            InvalidInput: malformed images or seed.
        """
        c = self.config
        w, h = rect.size
        gl = to_gray(left, w, h, "left")
        gr = to_gray(right, w, h, "right")
        seed = np.asarray(seed)
        if seed.shape != (h, w):
            raise InvalidInput(f"seed: expected a ({h}, {w}) mask, got shape {seed.shape}")
        if points_fn is None:
            tri = StereoTriangulator(rect.left, rect.right)

            def points_fn(ul: np.ndarray, ur: np.ndarray) -> np.ndarray:
                return tri.triangulate_many(ul, ur, rect.T_root_left, rect.T_root_right)

        seed_r = rect.rectify_mask(seed.astype(bool), "left")
        if not seed_r.any():
            raise ObjectNotFound("empty_seed", "the seed mask is empty (or outside the "
                                 "rectified view)")
        rl, rr = rect.rectify(gl, "left"), rect.rectify(gr, "right")
        valid = cv2.erode(rect.valid_region("left").astype(np.uint8),
                          np.ones((5, 5), np.uint8)) > 0
        ys, xs = np.nonzero(seed_r)
        m = c.roi_margin
        box = [max(int(xs.min()) - m, 0), max(int(ys.min()) - m, 0),
               min(int(xs.max()) + m + 1, w), min(int(ys.max()) + m + 1, h)]
        for _ in range(_MAX_GROW + 1):
            result = self._measure(rect, rl, rr, seed_r, valid, box, points_fn, gate)
            grow = result
            if isinstance(grow, ObjectEstimate):
                return grow
            x0, y0, x1, y1 = box
            g = 2 * max(m, 8)
            box = [max(x0 - g * grow[0], 0), max(y0 - g * grow[1], 0),
                   min(x1 + g * grow[2], w), min(y1 + g * grow[3], h)]
        raise ObjectNotFound("no_object", "the object region keeps growing beyond the search "
                             "window (no separate object on a support)")

    # ------------------------------------------------------------------ steps
    def _disparity(self, rect: StereoRectification, rl: np.ndarray, rr: np.ndarray,
                   box: list[int]) -> np.ndarray:
        """Disparity [px] over ``box`` of the rectified left image (NaN where unmatched)."""
        c = self.config
        x0, y0, x1, y1 = box
        nd = int(math.ceil(min(rect.disparity_at(c.min_depth), 512.0) / 16.0)) * 16
        xa = x0 - nd
        L, R = rl[y0:y1, max(xa, 0):x1], rr[y0:y1, max(xa, 0):x1]
        if xa < 0:
            L = cv2.copyMakeBorder(L, 0, 0, -xa, 0, cv2.BORDER_CONSTANT, value=0)
            R = cv2.copyMakeBorder(R, 0, 0, -xa, 0, cv2.BORDER_CONSTANT, value=0)
        b = self._block
        sgbm = cv2.StereoSGBM_create(
            minDisparity=0, numDisparities=nd, blockSize=b, P1=8 * b * b, P2=32 * b * b,
            disp12MaxDiff=1, uniquenessRatio=c.uniqueness_ratio, speckleWindowSize=30,
            speckleRange=2, mode=cv2.STEREO_SGBM_MODE_SGBM)
        d = sgbm.compute(np.ascontiguousarray(L), np.ascontiguousarray(R))[:, nd:]
        d = d.astype(np.float32) / 16.0
        d[d < max(rect.disparity_at(c.max_depth), 0.5)] = np.nan
        # untextured blocks (sky, flat walls) match anywhere: no disparity there
        f = rl[y0:y1, x0:x1].astype(np.float32)
        mean = cv2.boxFilter(f, -1, (b, b))
        var = cv2.boxFilter(f * f, -1, (b, b)) - mean * mean
        d[var < c.stereo_min_texture**2] = np.nan
        return d

    def _support(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Support plane (point, upward unit normal) of ``pts`` (m, 3) by RANSAC."""
        c = self.config
        if len(pts) < 30:
            raise ObjectNotFound("no_support", f"only {len(pts)} 3-D points around the object: "
                                 "no support plane")
        rng = np.random.default_rng(0)
        idx = rng.integers(0, len(pts), size=(_RANSAC_ITERATIONS, 3))
        a, b, cc = pts[idx[:, 0]], pts[idx[:, 1]], pts[idx[:, 2]]
        n = np.cross(b - a, cc - a)
        norm = np.linalg.norm(n, axis=1)
        ok = norm > 1e-9
        n[ok] /= norm[ok, None]
        n *= np.sign(n[:, 2:3] + 1e-12)
        ok &= np.arccos(np.clip(n[:, 2], -1.0, 1.0)) <= c.max_support_tilt
        if not ok.any():
            raise ObjectNotFound("no_support", "no level support plane around the object")
        n, a = n[ok], a[ok]
        sub = pts[rng.choice(len(pts), size=min(len(pts), 1500), replace=False)]
        counts = (np.abs((sub[None, :, :] - a[:, None, :]) @ n[:, :, None])[..., 0]
                  < c.plane_band).sum(axis=1)
        k = int(np.argmax(counts))
        p0, normal = a[k], n[k]
        for _ in range(2):
            inl = np.abs((pts - p0) @ normal) < c.plane_band
            if inl.sum() < 10:
                break
            p0 = pts[inl].mean(axis=0)
            _, _, vt = np.linalg.svd(pts[inl] - p0, full_matrices=False)
            normal = vt[2] * np.sign(vt[2][2] + 1e-12)
        if math.acos(min(abs(float(normal @ _UP)), 1.0)) > c.max_support_tilt:
            raise ObjectNotFound("no_support", "the best support plane is not level")
        if (np.abs((pts - p0) @ normal) < c.plane_band).mean() < 0.3:
            raise ObjectNotFound("no_support", "the points around the object are not a plane")
        return p0, normal

    def _measure(self, rect: StereoRectification, rl: np.ndarray, rr: np.ndarray,
                 seed_r: np.ndarray, valid: np.ndarray, box: list[int], points_fn: PointsFn,
                 gate: ObjectGate | None) -> ObjectEstimate | tuple[int, int, int, int]:
        """One measurement in ``box``; returns the estimate, or the sides (left, top, right,
        bottom: 1 = grow) the object touches."""
        c = self.config
        x0, y0, x1, y1 = box
        d = self._disparity(rect, rl, rr, box)
        yy, xx = np.mgrid[y0:y1, x0:x1]
        ok = np.isfinite(d) & valid[y0:y1, x0:x1]
        uv_l = np.stack([xx[ok], yy[ok]], axis=1).astype(float)
        uv_r = uv_l - np.stack([d[ok], np.zeros(int(ok.sum()))], axis=1)
        P = np.full(d.shape + (3,), np.nan)
        if len(uv_l):
            P[ok] = points_fn(rect.from_rectified(uv_l, "left"),
                              rect.from_rectified(uv_r, "right"))
        ok &= np.isfinite(P).all(axis=2)
        seed_box = seed_r[y0:y1, x0:x1]
        around = ok & ~(cv2.dilate(seed_box.astype(np.uint8), np.ones((9, 9), np.uint8)) > 0)
        p0, n = self._support(P[around])
        hgt = np.where(ok, np.nan_to_num((P - p0) @ n), -1.0)
        above = ok & (hgt > c.min_object_height) & (hgt < c.max_object_height)
        if gate is not None:
            top = np.asarray(gate.top, float)
            rel = np.nan_to_num(P - top)
            radial = np.linalg.norm(rel - (rel @ n)[..., None] * n, axis=-1)
            above &= (radial <= gate.radius + gate.margin) & (
                hgt <= float((top - p0) @ n) + gate.margin)
        above &= ~_depth_steps(P, c.max_depth_step)
        above = cv2.morphologyEx(above.astype(np.uint8), cv2.MORPH_OPEN, self._open) > 0
        n_lab, labels = cv2.connectedComponents(above.astype(np.uint8), connectivity=8)
        if n_lab <= 1:
            raise ObjectNotFound("no_object", "nothing stands above the support at the seed")
        overlap = np.bincount(labels[seed_box], minlength=n_lab)
        overlap[0] = 0
        k = int(np.argmax(overlap))
        if overlap[k] == 0:
            raise ObjectNotFound("no_object", "nothing stands above the support at the seed")
        obj = labels == k
        # the region grows while it touches the window's border (inside the image)
        W, H = rect.size
        touch = (int(obj[:, 0].any() and x0 > 0), int(obj[0, :].any() and y0 > 0),
                 int(obj[:, -1].any() and x1 < W), int(obj[-1, :].any() and y1 < H))
        if any(touch):
            return touch
        edge = ~valid[y0:y1, x0:x1]
        if (cv2.dilate(edge.astype(np.uint8), self._open) > 0)[obj].any() or (
                obj[:, 0].any() or obj[0, :].any() or obj[:, -1].any() or obj[-1, :].any()):
            raise ObjectNotFound("image_border", "the object is cut by the image border")
        core = cv2.erode(obj.astype(np.uint8), self._open) > 0  # off the silhouette's rim
        if core.sum() >= c.min_object_points:
            obj = core
        pts, hs = P[obj], hgt[obj]
        if len(pts) < c.min_object_points:
            raise ObjectNotFound("too_few_points", f"{len(pts)} 3-D points on the object "
                                 f"(< min_object_points {c.min_object_points})")
        h_top = float(np.percentile(hs, 95))
        for _ in range(2):
            sel = np.abs(hs - h_top) < c.top_band
            h_top = float(np.median(hs[sel]))
        sel = np.abs(hs - h_top) < c.top_band
        if sel.sum() < c.min_top_points:
            raise ObjectNotFound("too_few_points", f"{int(sel.sum())} points on the top face "
                                 f"(< min_top_points {c.min_top_points})")
        tp = pts[sel]
        top = self._top_centre(tp, p0, n, h_top)
        centre = top - n * (0.5 * h_top)
        rel = pts - top
        radial = np.linalg.norm(rel - np.outer(rel @ n, n), axis=1)
        cov = self._covariance(rect, top, tp, int(sel.sum()))
        return ObjectEstimate(
            position=centre, top=top, covariance=cov, height=h_top,
            radius=float(np.percentile(radial, 90)), support_normal=n, support_point=p0,
            n_points=int(len(pts)), n_top=int(sel.sum()),
            seed_overlap=float(overlap[k] / max(int(seed_box.sum()), 1)),
        )

    @staticmethod
    def _top_centre(tp: np.ndarray, p0: np.ndarray, n: np.ndarray, h_top: float
                    ) -> np.ndarray:
        """Centre (3,) of the top face from its points ``tp`` (m, 3), on the top plane: the
        centre of the smallest circle enclosing them in the support's plane (the 1 % farthest
        from their median dropped as outliers). The band of the top face also holds the upper
        rim of the side facing the eyes; those points lie on the object's outline, so they do
        not move the enclosing circle, where they would pull a mean or a median."""
        e1 = np.cross(n, [1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.cross(n, [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        xy = np.stack([tp @ e1, tp @ e2], axis=1)
        d = np.linalg.norm(xy - np.median(xy, axis=0), axis=1)
        xy = xy[d <= np.percentile(d, 99)]
        (cx, cy), _ = cv2.minEnclosingCircle(xy.astype(np.float32))
        c = cx * e1 + cy * e2
        return c + n * (h_top + float(p0 @ n) - float(c @ n))

    def _covariance(self, rect: StereoRectification, top: np.ndarray, tp: np.ndarray,
                    n_top: int) -> np.ndarray:
        """Covariance (3, 3) of the top centre (module doc)."""
        c = self.config
        n_eff = max(n_top / float(self._block**2), 1.0)
        origin = rect.T_root_left[:3, 3]
        ray = top - origin
        z = float(np.linalg.norm(ray))
        ray /= z
        sd = z * z * c.disparity_sigma / (rect.focal * rect.baseline) / math.sqrt(n_eff)
        scatter = np.cov(tp.T) / n_eff if len(tp) > 3 else np.zeros((3, 3))
        return sd * sd * np.outer(ray, ray) + scatter + c.model_sigma**2 * np.eye(3)

    # ------------------------------------------------------------------ seeds
    @staticmethod
    def seed_from_object(top: np.ndarray, radius: float, height: float,
                         T_root_camera: np.ndarray, camera: CameraIntrinsics,
                         normal: np.ndarray = _UP, margin: float = 0.01) -> np.ndarray:
        """(H, W) bool mask of the image region an upright object covers: the convex hull of
        its top and bottom rims (``radius`` + ``margin`` about the axis through ``top``
        along ``normal``, ``height`` [m] tall) projected into a camera. Empty when it is out
        of view."""
        top = np.asarray(top, float)
        ang = np.linspace(0.0, 2.0 * math.pi, 16, endpoint=False)
        n = np.asarray(normal, float) / np.linalg.norm(normal)
        e1 = np.cross(n, [1.0, 0.0, 0.0])
        if np.linalg.norm(e1) < 1e-6:
            e1 = np.cross(n, [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        r = radius + margin
        ring = r * (np.outer(np.cos(ang), e1) + np.outer(np.sin(ang), e2))
        pts = np.vstack([top + ring + margin * n, top - height * n + ring])
        mask = np.zeros((camera.height, camera.width), np.uint8)
        uv = []
        for p in pts:
            try:
                uv.append(project_point(T_root_camera, p, camera))
            except InvalidInput:  # behind the camera
                return mask.astype(bool)
        hull = cv2.convexHull(np.round(np.array(uv)).astype(np.int32))
        cv2.fillConvexPoly(mask, hull, 1)
        return mask.astype(bool)


def _depth_steps(P: np.ndarray, step: float) -> np.ndarray:
    """(H, W) bool: pixels of the point image ``P`` (H, W, 3) [m] more than ``step`` [m] from
    a 4-neighbour's point (depth discontinuities, which separate objects in the image)."""
    out = np.zeros(P.shape[:2], bool)
    with np.errstate(invalid="ignore"):
        dx = np.linalg.norm(P[:, 1:] - P[:, :-1], axis=2) > step
        dy = np.linalg.norm(P[1:] - P[:-1], axis=2) > step
    out[:, 1:] |= dx
    out[:, :-1] |= dx
    out[1:] |= dy
    out[:-1] |= dy
    return out
