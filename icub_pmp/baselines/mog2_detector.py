"""Mog2Detector: OpenCV MOG2 background subtraction, the first baseline of the benchmark.

A per-pixel Gaussian-mixture background model (Zivkovic 2004). It assumes a still camera:
the benchmark shows what ego-motion does to it next to the LK-failure segmenter.
"""

from __future__ import annotations

import cv2
import numpy as np

from icub_pmp.vision.image_checks import to_gray

__all__ = ["Mog2Detector"]


class Mog2Detector:
    """Foreground mask of each frame from ``cv2.BackgroundSubtractorMOG2``.

    Args:
        width, height: image size [px].
        history: frames of the background model.
        var_threshold: squared Mahalanobis distance that marks a pixel foreground.
        open_size: side of the square opening removing speckle [px] (0: none).
    """

    def __init__(self, width: int = 320, height: int = 240, history: int = 60,
                 var_threshold: float = 16.0, open_size: int = 3):
        self.width, self.height = width, height
        self._mog = cv2.createBackgroundSubtractorMOG2(
            history=history, varThreshold=var_threshold, detectShadows=False
        )
        self._kernel = (
            cv2.getStructuringElement(cv2.MORPH_RECT, (open_size, open_size))
            if open_size > 0 else None
        )

    def process(self, image: np.ndarray) -> np.ndarray:
        """(H, W) bool foreground mask of ``image`` ((H, W) grey or (H, W, 3) RGB uint8)."""
        gray = to_gray(image, self.width, self.height)
        fg = self._mog.apply(gray)
        if self._kernel is not None:
            fg = cv2.morphologyEx(fg, cv2.MORPH_OPEN, self._kernel)
        return fg > 0
