"""StereoTriangulator: a 3-D point in root_link from the blob centroids of both eyes.

The iCub eyes verge, so the pair is not rectified: each centroid defines a ray from its
camera centre (REP-103 optical frame, pose ``T_root_camera`` from
:class:`~icub_pmp.kinematics.eye_kinematics.EyeKinematics`); the point is the midpoint of the
shortest segment between the two rays (closest approach).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics

__all__ = ["StereoTriangulator", "StereoPoint"]


@dataclasses.dataclass(frozen=True)
class StereoPoint:
    """A triangulated point.

    Attributes:
        position: (3,) point in root_link [m] (read-only).
        ray_gap: distance between the two rays at closest approach [m].
        depth_left: depth of the point along the left optical axis [m].
        depth_right: depth along the right optical axis [m].
    """

    position: np.ndarray
    ray_gap: float
    depth_left: float
    depth_right: float

    def __post_init__(self) -> None:
        p = np.array(self.position, dtype=float, copy=True)
        p.setflags(write=False)
        object.__setattr__(self, "position", p)


class StereoTriangulator:
    """Triangulate pixel pairs with known intrinsics and camera poses."""

    def __init__(self, left: CameraIntrinsics | None = None, right: CameraIntrinsics | None = None):
        self.left = left or CameraIntrinsics()
        self.right = right or self.left

    @staticmethod
    def ray(uv: tuple[float, float], camera: CameraIntrinsics, T_root_camera: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
        """Origin (3,) and unit direction (3,) in root_link of the ray through pixel ``uv``."""
        T = _pose(T_root_camera, "T_root_camera")
        u, v = _pixel(uv)
        d_cam = np.array([(u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0])
        d = T[:3, :3] @ d_cam
        return T[:3, 3].copy(), d / np.linalg.norm(d)

    def triangulate(
        self,
        uv_left: tuple[float, float],
        uv_right: tuple[float, float],
        T_root_left: np.ndarray,
        T_root_right: np.ndarray,
    ) -> StereoPoint:
        """Closest-approach midpoint of the two pixel rays.

        Args:
            uv_left: pixel (u, v) in the left image [px].
            uv_right: pixel (u, v) in the right image [px].
            T_root_left: (4, 4) left optical frame in root_link.
            T_root_right: (4, 4) right optical frame in root_link.

        Raises:
            InvalidInput: malformed input, parallel rays, or a point behind a camera.
        """
        o1, d1 = self.ray(uv_left, self.left, T_root_left)
        o2, d2 = self.ray(uv_right, self.right, T_root_right)
        w0 = o1 - o2
        b = float(d1 @ d2)
        dd, e = float(d1 @ w0), float(d2 @ w0)
        den = 1.0 - b * b
        if den < 1e-12:
            raise InvalidInput(
                f"stereo rays through {tuple(uv_left)} and {tuple(uv_right)} are parallel: "
                "no depth"
            )
        s = (b * e - dd) / den  # distance along ray 1 [m]
        t = (e - b * dd) / den  # distance along ray 2 [m]
        if s <= 0.0 or t <= 0.0:
            raise InvalidInput(
                f"stereo rays through {tuple(uv_left)} and {tuple(uv_right)} meet behind a "
                f"camera (s = {s:.3f} m, t = {t:.3f} m)"
            )
        p1, p2 = o1 + s * d1, o2 + t * d2
        p = 0.5 * (p1 + p2)
        zl = float(np.asarray(T_root_left)[:3, 2] @ (p - o1))
        zr = float(np.asarray(T_root_right)[:3, 2] @ (p - o2))
        return StereoPoint(p, float(np.linalg.norm(p1 - p2)), zl, zr)

    def triangulate_many(
        self,
        uv_left: np.ndarray,
        uv_right: np.ndarray,
        T_root_left: np.ndarray,
        T_root_right: np.ndarray,
    ) -> np.ndarray:
        """Closest-approach midpoints of many pixel pairs (vectorised :meth:`triangulate`).

        Args:
            uv_left: (n, 2) pixels in the left image [px].
            uv_right: (n, 2) corresponding pixels in the right image [px].
            T_root_left: (4, 4) left optical frame in root_link.
            T_root_right: (4, 4) right optical frame in root_link.

        Returns:
            (n, 3) points in root_link [m]; NaN rows where the rays are parallel or meet
            behind a camera.

        Raises:
            InvalidInput: malformed pixels or poses.
        """
        Tl, Tr = _pose(T_root_left, "T_root_left"), _pose(T_root_right, "T_root_right")
        a = np.atleast_2d(np.asarray(uv_left, dtype=float))
        b = np.atleast_2d(np.asarray(uv_right, dtype=float))
        if a.shape != b.shape or a.ndim != 2 or a.shape[1] != 2:
            raise InvalidInput(f"pixels: expected two (n, 2) arrays, got {a.shape} and {b.shape}")
        if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
            raise InvalidInput("pixels: non-finite pixel coordinates")

        def rays(uv: np.ndarray, cam: CameraIntrinsics, T: np.ndarray) -> np.ndarray:
            d = np.stack([(uv[:, 0] - cam.cx) / cam.fx, (uv[:, 1] - cam.cy) / cam.fy,
                          np.ones(len(uv))], axis=1) @ T[:3, :3].T
            return d / np.linalg.norm(d, axis=1, keepdims=True)

        d1, d2 = rays(a, self.left, Tl), rays(b, self.right, Tr)
        o1, o2 = Tl[:3, 3], Tr[:3, 3]
        w0 = o1 - o2
        bb = np.einsum("ij,ij->i", d1, d2)
        dd, e = d1 @ w0, d2 @ w0
        den = 1.0 - bb * bb
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (bb * e - dd) / den
            t = (e - bb * dd) / den
        p = 0.5 * (o1 + s[:, None] * d1 + o2 + t[:, None] * d2)
        p[(den < 1e-12) | ~(s > 0.0) | ~(t > 0.0)] = np.nan
        return p


def _pose(T: np.ndarray, name: str) -> np.ndarray:
    a = np.asarray(T, dtype=float)
    if a.shape != (4, 4) or not np.all(np.isfinite(a)):
        raise InvalidInput(f"{name}: expected a finite (4, 4) pose, got shape {a.shape}")
    return a


def _pixel(uv: tuple[float, float]) -> tuple[float, float]:
    a = np.asarray(uv, dtype=float).ravel()
    if a.shape != (2,) or not np.all(np.isfinite(a)):
        raise InvalidInput(f"pixel: expected finite (u, v), got {uv!r}")
    return float(a[0]), float(a[1])
