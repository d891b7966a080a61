"""MarkerDetector: the hand's coloured marker in a camera image (OpenCV colour threshold).

iCub babbling experiments track a coloured marker (or an LED) on the hand. The image is
converted to HSV, thresholded around the marker's hue with minimum saturation and value
(``cv2.inRange``), and the largest connected blob (``cv2.connectedComponentsWithStats``) of at
least ``min_area`` pixels gives the marker's centroid [px]. Pixel convention: (u, v) = (column,
row) of the pixel centre, as the stereo triangulator takes them.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import cv2
import numpy as np

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError, InvalidInput

__all__ = ["MarkerDetector", "MarkerDetectorConfig", "MarkerDetection"]


@dataclasses.dataclass(frozen=True)
class MarkerDetectorConfig(ConfigBase):
    """Colour window of the marker (OpenCV HSV: hue 0-179, saturation and value 0-255).

    Attributes:
        hue_min, hue_max: hue window (the simulator's green marker: about 60).
        saturation_min: least saturation (excludes greys and white).
        value_min: least brightness (excludes dark shadows).
        min_area: least blob area [px] (smaller blobs are noise or a marker seen edge-on).
    """

    hue_min: int = 45
    hue_max: int = 75
    saturation_min: int = 120
    value_min: int = 60
    min_area: int = 4

    def validate(self) -> None:
        """Ranges (raise :class:`ConfigError` naming the field)."""
        if not 0 <= self.hue_min <= self.hue_max <= 179:
            raise ConfigError(f"hue window: expected 0 <= hue_min <= hue_max <= 179, got "
                              f"{self.hue_min}, {self.hue_max}")
        if not (0 <= self.saturation_min <= 255 and 0 <= self.value_min <= 255):
            raise ConfigError("saturation_min, value_min: expected 0-255")
        if self.min_area < 1:
            raise ConfigError(f"min_area: expected >= 1 px, got {self.min_area}")



class MarkerDetection(NamedTuple):
    """The marker in one image: ``found``, centroid (u, v) [px], area [px] (NaN/0 if not)."""

    found: bool
    u: float
    v: float
    area: int


_NONE = MarkerDetection(False, float("nan"), float("nan"), 0)


class MarkerDetector:
    """Finds the marker's centroid in RGB images (module doc)."""

    def __init__(self, config: MarkerDetectorConfig | None = None):
        self.config = config or MarkerDetectorConfig()
        c = self.config
        self._lo = np.array([c.hue_min, c.saturation_min, c.value_min], dtype=np.uint8)
        self._hi = np.array([c.hue_max, 255, 255], dtype=np.uint8)

    def mask(self, rgb: np.ndarray) -> np.ndarray:
        """Marker-coloured pixels (H, W) uint8 (255 = marker colour) of an RGB image."""
        img = np.asarray(rgb)
        if img.ndim != 3 or img.shape[2] != 3 or img.dtype != np.uint8:
            raise InvalidInput(f"image: expected (H, W, 3) uint8 RGB, got {img.shape} "
                               f"{img.dtype}")
        hsv = cv2.cvtColor(np.ascontiguousarray(img), cv2.COLOR_RGB2HSV)
        return cv2.inRange(hsv, self._lo, self._hi)

    def detect(self, rgb: np.ndarray) -> MarkerDetection:
        """Centroid of the largest marker-coloured blob of at least ``min_area`` px."""
        n, _, stats, centroids = cv2.connectedComponentsWithStats(self.mask(rgb), 8)
        if n <= 1:
            return _NONE
        areas = stats[1:, cv2.CC_STAT_AREA]
        k = int(np.argmax(areas))
        if areas[k] < self.config.min_area:
            return _NONE
        u, v = centroids[k + 1]
        return MarkerDetection(True, float(u), float(v), int(areas[k]))

    def detect_near(self, rgb: np.ndarray, uv: tuple[float, float], radius: float
                    ) -> MarkerDetection:
        """Centroid of the marker-coloured blob (of at least ``min_area`` px) nearest to the
        pixel ``uv`` [px], if within ``radius`` [px] of it: which of several markers in view
        (both hands carry one) is the one expected there."""
        if not (np.all(np.isfinite(uv)) and radius > 0):
            raise InvalidInput(f"detect_near: expected a finite pixel and radius > 0, got "
                               f"{uv}, {radius}")
        n, _, stats, centroids = cv2.connectedComponentsWithStats(self.mask(rgb), 8)
        best, best_d = 0, float(radius)
        for k in range(1, n):
            if stats[k, cv2.CC_STAT_AREA] < self.config.min_area:
                continue
            d = float(np.hypot(*(centroids[k] - np.asarray(uv, dtype=float))))
            if d <= best_d:
                best, best_d = k, d
        if best == 0:
            return _NONE
        u, v = centroids[best]
        return MarkerDetection(True, float(u), float(v), int(stats[best, cv2.CC_STAT_AREA]))
