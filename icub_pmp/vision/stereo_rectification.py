"""StereoRectification: the verging eye pair turned into a rectified pair (rows = epipolar lines).

The iCub eyes verge, so corresponding points do not lie on the same image row. Bouguet's
rectification (OpenCV ``stereoRectify``) rotates both cameras virtually about their centres so
that their optical axes are parallel and orthogonal to the baseline: a scene point then
projects on the same row of both rectified images, at columns differing by the disparity
``d = f B / Z`` (f the rectified focal length [px], B the baseline [m], Z the depth [m]). The
relative pose comes from the head/eye kinematics (``T_root_left``, ``T_root_right``), exactly
as for ray triangulation; the images are pinhole images without distortion (the simulator's).

    rect = StereoRectification(cam, cam, poses.T_root_left, poses.T_root_right)
    left_r = rect.rectify(left_gray, "left")
    uv_r = rect.to_rectified(uv, "left")      # pixel -> rectified pixel
    uv = rect.from_rectified(uv_r, "left")    # and back
"""

from __future__ import annotations

import cv2
import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.eye_kinematics import EYE_SIDES, CameraIntrinsics

__all__ = ["StereoRectification"]


class StereoRectification:
    """Rectifying rotations, projections and pixel maps of one pair of camera poses.

    Args:
        left: intrinsics of the left camera.
        right: intrinsics of the right camera (same image size as the left).
        T_root_left: (4, 4) left optical frame (REP-103) in root_link.
        T_root_right: (4, 4) right optical frame in root_link.

    Raises:
        InvalidInput: malformed poses, different image sizes, or coincident cameras.
    """

    def __init__(self, left: CameraIntrinsics, right: CameraIntrinsics,
                 T_root_left: np.ndarray, T_root_right: np.ndarray):
        if (left.width, left.height) != (right.width, right.height):
            raise InvalidInput(f"StereoRectification: image sizes differ, left "
                               f"{left.width}x{left.height}, right {right.width}x{right.height}")
        self.left, self.right = left, right
        self.size = (left.width, left.height)
        self.T_root_left = _pose(T_root_left, "T_root_left")
        self.T_root_right = _pose(T_root_right, "T_root_right")
        T_rl = np.linalg.inv(self.T_root_right) @ self.T_root_left  # left frame -> right frame
        baseline = float(np.linalg.norm(T_rl[:3, 3]))
        if baseline < 1e-4:
            raise InvalidInput(f"StereoRectification: the cameras are {baseline:.2e} m apart; "
                               "need a baseline")
        zero = np.zeros(5)
        R1, R2, P1, P2, Q, _, _ = cv2.stereoRectify(
            left.K, zero, right.K, zero, self.size, T_rl[:3, :3].copy(),
            T_rl[:3, 3].reshape(3, 1).copy(), flags=cv2.CALIB_ZERO_DISPARITY, alpha=0.0)
        #: rotations (3, 3) from each optical frame to its rectified frame.
        self.R = {"left": R1, "right": R2}
        #: projections (3, 4) of the rectified cameras (in the left rectified frame).
        self.P = {"left": P1, "right": P2}
        self.Q = Q
        #: rectified focal length [px] and baseline [m].
        self.focal = float(P1[0, 0])
        self.baseline = baseline
        K = {"left": left.K, "right": right.K}
        # homographies original pixel <-> rectified pixel (no distortion)
        self._H = {s: self.P[s][:, :3] @ self.R[s] @ np.linalg.inv(K[s]) for s in EYE_SIDES}
        self._H_inv = {s: np.linalg.inv(h) for s, h in self._H.items()}
        self._maps: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    # ------------------------------------------------------------------ geometry
    def disparity_at(self, depth: float) -> float:
        """Disparity [px] of a point ``depth`` [m] in front of the rectified cameras."""
        return self.focal * self.baseline / depth

    def to_rectified(self, uv: np.ndarray, side: str) -> np.ndarray:
        """Pixels (n, 2) of ``side``'s image -> its rectified image [px]."""
        return _apply(self._H[_side(side)], uv)

    def from_rectified(self, uv: np.ndarray, side: str) -> np.ndarray:
        """Rectified pixels (n, 2) of ``side`` -> pixels of its original image [px]."""
        return _apply(self._H_inv[_side(side)], uv)

    def rectified_flow(self, uv: np.ndarray, flow: np.ndarray, side: str) -> np.ndarray:
        """Image motion (n, 2) [px] of pixels ``uv`` (n, 2) of ``side``, in rectified pixels."""
        uv = np.atleast_2d(np.asarray(uv, dtype=float))
        return self.to_rectified(uv + np.atleast_2d(flow), side) - self.to_rectified(uv, side)

    # ------------------------------------------------------------------ images
    def _map(self, side: str) -> tuple[np.ndarray, np.ndarray]:
        s = _side(side)
        if s not in self._maps:
            K = self.left.K if s == "left" else self.right.K
            self._maps[s] = cv2.initUndistortRectifyMap(K, np.zeros(5), self.R[s], self.P[s],
                                                        self.size, cv2.CV_32FC1)
        return self._maps[s]

    def rectify(self, image: np.ndarray, side: str) -> np.ndarray:
        """The rectified image of ``side`` (same size and dtype; bilinear)."""
        mx, my = self._map(side)
        return cv2.remap(_image(image, self.size), mx, my, cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT)

    def rectify_mask(self, mask: np.ndarray, side: str) -> np.ndarray:
        """A (H, W) bool mask of ``side``'s image carried to its rectified image."""
        mx, my = self._map(side)
        m = _image(np.asarray(mask).astype(np.uint8), self.size)
        return cv2.remap(m, mx, my, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT) > 0

    def valid_region(self, side: str) -> np.ndarray:
        """(H, W) bool: rectified pixels that see inside ``side``'s original image."""
        w, h = self.size
        return self.rectify_mask(np.ones((h, w), bool), side)


def _side(side: str) -> str:
    if side not in EYE_SIDES:
        raise UnknownName("eye side", side, EYE_SIDES)
    return side


def _apply(H: np.ndarray, uv: np.ndarray) -> np.ndarray:
    a = np.atleast_2d(np.asarray(uv, dtype=float))
    if a.ndim != 2 or a.shape[1] != 2 or not np.all(np.isfinite(a)):
        raise InvalidInput(f"pixels: expected finite (n, 2) [px], got shape {a.shape}")
    p = np.hstack([a, np.ones((len(a), 1))]) @ H.T
    return p[:, :2] / p[:, 2:3]


def _pose(T: np.ndarray, name: str) -> np.ndarray:
    a = np.asarray(T, dtype=float)
    if a.shape != (4, 4) or not np.all(np.isfinite(a)):
        raise InvalidInput(f"{name}: expected a finite (4, 4) pose, got shape {a.shape}")
    return a.copy()


def _image(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    a = np.asarray(image)
    if a.shape[:2] != (size[1], size[0]):
        raise InvalidInput(f"image: expected {size[0]}x{size[1]} (W x H), got shape {a.shape}")
    return np.ascontiguousarray(a)
