"""FlowResidualDetector: dense flow minus the dominant global motion, the second baseline.

Farneback dense optical flow between consecutive frames; the dominant (ego-)motion is a
homography fitted with RANSAC to a sparse sample of the flow field (exact for a rotating
camera); pixels whose flow differs from it by more than a threshold are independently moving.
Only textured pixels vote (minimum eigenvalue of the structure tensor, as for LK): dense flow
in a uniform region is the smoothness prior's guess, not a measurement.
"""

from __future__ import annotations

import cv2
import numpy as np

from icub_pmp.vision.image_checks import to_gray

__all__ = ["FlowResidualDetector"]


class FlowResidualDetector:
    """Independent-motion mask from the residual of Farneback flow to a global homography.

    Args:
        width, height: image size [px].
        residual_threshold: flow residual marking a pixel as moving [px/frame].
        sample_step: spacing of the flow samples used to fit the homography [px].
        open_size: side of the square opening removing speckle [px] (0: none).
        min_eigen: minimum eigenvalue (``cv2.cornerMinEigenVal``, 7x7 block) below which a
            pixel is textureless and never moving.
    """

    def __init__(self, width: int = 320, height: int = 240, residual_threshold: float = 1.0,
                 sample_step: int = 8, open_size: int = 5, min_eigen: float = 1e-4):
        self.width, self.height = width, height
        self.residual_threshold = residual_threshold
        self.min_eigen = min_eigen
        self._prev: np.ndarray | None = None
        ys, xs = np.mgrid[0:height, 0:width].astype(np.float32)
        self._xs, self._ys = xs, ys
        s = sample_step
        self._sample = (slice(s // 2, None, s), slice(s // 2, None, s))
        self._kernel = (
            cv2.getStructuringElement(cv2.MORPH_RECT, (open_size, open_size))
            if open_size > 0 else None
        )

    def reset(self) -> None:
        """Forget the previous frame."""
        self._prev = None

    def process(self, image: np.ndarray) -> np.ndarray:
        """(H, W) bool mask of pixels moving independently between the last frame and this."""
        gray = to_gray(image, self.width, self.height)
        prev, self._prev = self._prev, gray
        if prev is None:
            return np.zeros((self.height, self.width), bool)
        flow = cv2.calcOpticalFlowFarneback(prev, gray, None, 0.5, 3, 15, 3, 5, 1.2, 0)
        textured = cv2.cornerMinEigenVal(prev, 7) >= self.min_eigen
        ok = textured[self._sample].ravel()
        src = np.stack([self._xs[self._sample], self._ys[self._sample]], -1).reshape(-1, 2)[ok]
        dst = src + flow[self._sample].reshape(-1, 2)[ok]
        h = cv2.findHomography(src, dst, cv2.RANSAC, 1.0)[0] if len(src) >= 8 else None
        if h is None:
            h = np.eye(3)
        den = h[2, 0] * self._xs + h[2, 1] * self._ys + h[2, 2]
        px = (h[0, 0] * self._xs + h[0, 1] * self._ys + h[0, 2]) / den - self._xs
        py = (h[1, 0] * self._xs + h[1, 1] * self._ys + h[1, 2]) / den - self._ys
        res = np.hypot(flow[..., 0] - px, flow[..., 1] - py)
        m = ((res > self.residual_threshold) & textured).astype(np.uint8)
        if self._kernel is not None:
            m = cv2.morphologyEx(m, cv2.MORPH_OPEN, self._kernel)
        return m > 0
