"""EyeHandPoints: the learned eye-hand map as the vision pipeline's 3-D source (force paper eq 12).

The stereo target (:class:`~icub_pmp.vision.StereoTarget`) turns every matched pixel pair of an
object into a point through a ``points_fn``: ray triangulation with the nominal camera model by
default. With ``target_source: eye_hand_map`` the motion segmenter passes instead the map
M(u_l, v_l, u_r, v_r, tilt, version, vergence) learned from babbling (:class:`EyeHandMap`,
head-centred output), taken to root_link with the head pose of the same joint state. What the
map learned of the real cameras (principal points, a rotated eye) is then in the target; the
map only holds for the camera setup it was learned with (image size, focal lengths), which is
checked when it is loaded.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from icub_pmp.body_schema.eye_hand_map import EyeHandMap
from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError, InvalidInput, ModelError
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics

__all__ = ["EyeHandPoints", "EyeHandTargetConfig", "TARGET_SOURCES"]

TARGET_SOURCES = ("triangulation", "eye_hand_map")
_FOCAL_TOLERANCE = 0.02  # relative focal-length difference that makes another camera setup


@dataclasses.dataclass(frozen=True)
class EyeHandTargetConfig(ConfigBase):
    """Attributes:
        target_source: ``triangulation`` (rays of the nominal cameras) | ``eye_hand_map``
            (the learned map of ``eye_hand_map_file``).
        eye_hand_map_file: eye-hand map (.npz, ``EyeHandMap.save``) for ``eye_hand_map``.
    """

    target_source: str = "triangulation"
    eye_hand_map_file: str = ""

    def validate(self) -> None:
        """A known source (a missing file is the node's warning, not a bad value)."""
        if self.target_source not in TARGET_SOURCES:
            raise ConfigError(f"target_source: expected one of {TARGET_SOURCES}, got "
                              f"{self.target_source!r}")


class EyeHandPoints:
    """Pixel pairs -> root_link points through a learned eye-hand map (module doc).

    Args:
        eye_hand_map: the learned map (its ``camera`` metadata must match ``camera``).
        camera: the cameras the pixels come from (nominal intrinsics of both eyes).

    Raises:
        ModelError: the map was learned for another camera setup, or does not say which.
    """

    def __init__(self, eye_hand_map: EyeHandMap, camera: CameraIntrinsics):
        cam = eye_hand_map.camera
        if not cam:
            raise ModelError("the eye-hand map does not name the camera setup it was learned "
                             "with (image size, focal lengths): learn it again")
        want = {"width": camera.width, "height": camera.height, "fx": camera.fx,
                "fy": camera.fy}
        for key, value in want.items():
            have = cam.get(key)
            tol = 0.5 if key in ("width", "height") else _FOCAL_TOLERANCE * value
            if have is None or abs(have - value) > tol:
                raise ModelError(f"the eye-hand map was learned with another camera setup: "
                                 f"{key} {have} vs {value} here (map {cam}, cameras {want})")
        self.map = eye_hand_map

    @classmethod
    def from_file(cls, path: str | Path, camera: CameraIntrinsics) -> "EyeHandPoints":
        """Load the map at ``path`` (:class:`ModelError` when missing, unreadable, not an
        eye-hand map or for another camera setup)."""
        if not str(path):
            raise ModelError("target_source eye_hand_map needs eye_hand_map_file (a map "
                             "learned from babbling)")
        return cls(EyeHandMap.load(path), camera)

    def locate(self, uv_left: np.ndarray, uv_right: np.ndarray, T_root_head: np.ndarray,
               eyes: np.ndarray) -> np.ndarray:
        """Points (n, 3) [m] in root_link of the pixel pairs ``uv_left``, ``uv_right`` (n, 2)
        [px] seen with the eyes at ``eyes`` = (tilt, version, vergence) [rad] and the head at
        ``T_root_head`` (4, 4) (eq 12, then head -> root_link)."""
        ul = np.asarray(uv_left, dtype=float).reshape(-1, 2)
        ur = np.asarray(uv_right, dtype=float).reshape(-1, 2)
        e = np.asarray(eyes, dtype=float).reshape(-1)
        T = np.asarray(T_root_head, dtype=float)
        if len(ul) != len(ur) or e.shape != (3,) or T.shape != (4, 4):
            raise InvalidInput(f"eye-hand points: expected (n, 2) pixel pairs, 3 eye angles and "
                               f"a (4, 4) head pose, got {ul.shape}, {ur.shape}, {e.shape}, "
                               f"{T.shape}")
        if len(ul) == 0:
            return np.zeros((0, 3))
        x = np.hstack([ul, ur, np.broadcast_to(e, (len(ul), 3))])
        p_head = self.map.locate(x)
        return p_head @ T[:3, :3].T + T[:3, 3]

    def points_fn(self, T_root_head: np.ndarray, eyes: np.ndarray):
        """A :data:`~icub_pmp.vision.object_locator.PointsFn` for one stereo pair (the head
        pose and eye angles at its stamp)."""
        T, e = np.array(T_root_head, dtype=float), np.array(eyes, dtype=float)
        return lambda ul, ur: self.locate(ul, ur, T, e)
