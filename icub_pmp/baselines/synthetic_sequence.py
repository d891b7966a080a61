"""SyntheticSequence: textured scenes seen by a rotating pinhole camera, with a moving patch.

Test and benchmark data that need no simulator. A large textured canvas is the image plane of
a reference camera with the same intrinsics; a camera rotated by ``R`` sees it through the
homography ``H = K R K_ref^-1`` (pure rotation: no parallax, exactly the ego-motion a
rotating eye produces on a distant scene). An optional textured patch moves on the canvas
(translation and in-plane rotation); its ground-truth mask is warped with the same homography.
"""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["SyntheticSequence", "SyntheticFrame", "textured_image", "triangle_wave"]


def textured_image(
    height: int, width: int, seed: int, scales: tuple[float, ...] = (1.5, 4.0, 12.0)
) -> np.ndarray:
    """A (height, width) uint8 grey texture: sum of blurred noise at several scales [px].

    Contrast-stretched to about 20..235 so LK has texture everywhere.
    """
    rng = np.random.default_rng(seed)
    acc = np.zeros((height, width), np.float32)
    for s in scales:
        n = rng.standard_normal((height, width)).astype(np.float32)
        b = cv2.GaussianBlur(n, (0, 0), s)
        acc += b / (b.std() + 1e-9)
    acc = (acc - acc.mean()) / (acc.std() + 1e-9)
    return np.clip(128.0 + 45.0 * acc, 0, 255).astype(np.uint8)


def triangle_wave(t: float, speed: float, half_range: float, phase: float) -> float:
    """Back-and-forth position in [-half_range, half_range] at constant ``speed`` (units of
    half_range per second), starting at 0 for phase 0 (phase in periods)."""
    if speed == 0.0:
        return 0.0
    period = 4.0 * half_range / speed
    ph = (t / period + phase) % 1.0
    a = 4 * ph if ph < 0.25 else (2 - 4 * ph if ph < 0.75 else 4 * ph - 4)
    return half_range * a


@dataclasses.dataclass(frozen=True)
class SyntheticFrame:
    """One rendered frame: (H, W, 3) uint8 RGB image and (H, W) bool ground-truth mask."""

    image: np.ndarray
    mask: np.ndarray
    object_center: tuple[float, float]


class SyntheticSequence:
    """Frames of a rotating camera looking at a textured canvas with an optional moving patch.

    Args:
        width, height: image size [px].
        fx: focal length [px] (fx = fy); principal point at the image centre.
        fps: frame rate [frames/s].
        yaw_rate, pitch_rate: camera rotation speed about its y (pan) and x (tilt) axes
            [deg/s]; the camera sweeps back and forth within +-``sweep`` [deg] at that speed.
        sweep: half amplitude of the back-and-forth camera rotation [deg].
        patch_size: side of the moving square patch (0: static scene) [px on the canvas].
        patch_velocity: patch velocity on the canvas (u, v) [px/s].
        patch_spin: in-plane patch rotation speed [deg/s].
        patch_start: patch centre at t = 0 relative to the canvas centre (u, v) [px].
        patch_scale_rate: growth of the patch's scale, ``1 + patch_scale_rate * t`` [1/s]
            (> 0: an object approaching along the optical axis, about speed / depth).
        noise: standard deviation of additive per-pixel image noise [grey levels].
        seed: texture and noise seed.
    """

    def __init__(
        self,
        width: int = 320,
        height: int = 240,
        fx: float = 343.12,
        fps: float = 30.0,
        yaw_rate: float = 0.0,
        pitch_rate: float = 0.0,
        sweep: float = 15.0,
        patch_size: int = 0,
        patch_velocity: tuple[float, float] = (0.0, 0.0),
        patch_spin: float = 0.0,
        patch_start: tuple[float, float] = (0.0, 0.0),
        patch_scale_rate: float = 0.0,
        noise: float = 1.0,
        seed: int = 0,
    ):
        if width < 16 or height < 16 or fx <= 0 or fps <= 0:
            raise InvalidInput(
                f"SyntheticSequence: need width, height >= 16 and fx, fps > 0; got "
                f"{width}x{height}, fx={fx}, fps={fps}"
            )
        self.width, self.height, self.fx, self.fps = width, height, fx, fps
        self.yaw_rate, self.pitch_rate, self.sweep = yaw_rate, pitch_rate, sweep
        self.patch_size = int(patch_size)
        self.patch_velocity = np.asarray(patch_velocity, float)
        self.patch_spin = patch_spin
        self.patch_start = np.asarray(patch_start, float)
        self.patch_scale_rate = patch_scale_rate
        self.noise = noise
        self._rng = np.random.default_rng(seed + 1000)
        # canvas wide enough for +-(sweep + 5) deg of rotation
        half_angle = math.radians(min(sweep + 5.0, 60.0))
        margin = int(fx * math.tan(half_angle)) + 16
        self.canvas_w = width + 2 * margin
        self.canvas_h = height + 2 * margin
        self.canvas = textured_image(self.canvas_h, self.canvas_w, seed)
        self.K = np.array([[fx, 0, (width - 1) / 2], [0, fx, (height - 1) / 2], [0, 0, 1]])
        self.K_ref = np.array(
            [[fx, 0, (self.canvas_w - 1) / 2], [0, fx, (self.canvas_h - 1) / 2], [0, 0, 1]]
        )
        if self.patch_size > 0:
            tex = textured_image(self.patch_size, self.patch_size, seed + 7, scales=(1.5, 3.0))
            # a patch brighter on average than the background keeps its border visible
            self.patch = np.clip(tex.astype(np.int16) + 30, 0, 255).astype(np.uint8)

    def _angles(self, t: float) -> tuple[float, float]:
        """Camera yaw and pitch [rad] at time t: triangle wave of the given speeds."""

        def tri(rate: float) -> float:
            a = triangle_wave(t, abs(rate), self.sweep, 0.0)
            return math.radians(math.copysign(a, rate))

        return tri(self.yaw_rate), tri(self.pitch_rate)

    def homography(self, t: float) -> np.ndarray:
        """3x3 homography canvas -> image at time t [s]."""
        yaw, pitch = self._angles(t)
        ry = cv2.Rodrigues(np.array([0.0, yaw, 0.0]))[0]
        rx = cv2.Rodrigues(np.array([pitch, 0.0, 0.0]))[0]
        return self.K @ (rx @ ry) @ np.linalg.inv(self.K_ref)

    def frame(self, k: int) -> SyntheticFrame:
        """Render frame k (time k / fps)."""
        t = k / self.fps
        canvas = self.canvas
        obj = np.zeros(canvas.shape, np.uint8)
        center = np.array([(self.canvas_w - 1) / 2, (self.canvas_h - 1) / 2])
        c = center + self.patch_start + self.patch_velocity * t
        if self.patch_size > 0:
            canvas = canvas.copy()
            s = self.patch_size
            ang = self.patch_spin * t
            scale = max(1.0 + self.patch_scale_rate * t, 0.05)
            m = cv2.getRotationMatrix2D(((s - 1) / 2, (s - 1) / 2), ang, scale)
            m[:, 2] += c - (s - 1) / 2
            size = (self.canvas_w, self.canvas_h)
            warped = cv2.warpAffine(self.patch, m, size, flags=cv2.INTER_LINEAR)
            inside = cv2.warpAffine(
                np.full((s, s), 255, np.uint8), m, (self.canvas_w, self.canvas_h),
                flags=cv2.INTER_LINEAR,
            )
            alpha = inside.astype(np.float32) / 255.0
            canvas = (canvas * (1 - alpha) + warped * alpha).astype(np.uint8)
            obj = inside
        h = self.homography(t)
        img = cv2.warpPerspective(canvas, h, (self.width, self.height), flags=cv2.INTER_LINEAR)
        mask = cv2.warpPerspective(obj, h, (self.width, self.height), flags=cv2.INTER_LINEAR) >= 128
        if self.noise > 0:
            n = self._rng.normal(0.0, self.noise, img.shape)
            img = np.clip(img + n, 0, 255).astype(np.uint8)
        p = h @ np.array([c[0], c[1], 1.0])
        return SyntheticFrame(
            image=np.repeat(img[:, :, None], 3, axis=2),
            mask=mask,
            object_center=(float(p[0] / p[2]), float(p[1] / p[2])),
        )

    def frames(self, n: int) -> list[SyntheticFrame]:
        """The first n frames."""
        return [self.frame(k) for k in range(n)]
