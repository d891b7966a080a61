"""Stereo samples of hand positions for the eye-hand map (force paper eq 12), no ROS.

What the eyes would see of a hand marker at known positions: the eyes fixate each hand (the
gaze controller's closed-form eyes, head still) up to a random error, the marker is projected
into both cameras (the *real* cameras, which may differ from the nominal model the triangulator
assumes: other principal points, a rotated left camera) with pixel noise, and the sample is kept
when both images see it. The bench and the tests train and test eye-hand maps on these.
"""

from __future__ import annotations

from typing import Mapping, NamedTuple

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics, EyeKinematics, project_point

__all__ = ["StereoSamples", "stereo_samples", "view_samples", "perturbed_cameras"]


class StereoSamples(NamedTuple):
    """Samples as arrays."""

    inputs: np.ndarray  # (n, 7) EYE_HAND_INPUTS: pixels [px], eye angles [rad]
    hands: np.ndarray  # (n, 3) hand positions in root_link [m]
    poses: np.ndarray  # (n, 2, 4, 4) the nominal camera poses (left, right) in root_link


def _seen(Tn: Mapping[str, np.ndarray], rot_left: np.ndarray, h: np.ndarray,
          cams: Mapping[str, CameraIntrinsics], rng: np.random.Generator, noise: float
          ) -> list[np.ndarray] | None:
    """Noisy pixels of ``h`` in the real cameras (the nominal poses ``Tn``, the left one
    rotated by ``rot_left``), or None when a camera does not see it."""
    Tr = dict(Tn)
    Tr["left"] = Tn["left"].copy()
    Tr["left"][:3, :3] = Tn["left"][:3, :3] @ rot_left
    try:
        uv = [project_point(Tr[s], h, cams[s]) + rng.normal(0, noise, 2) for s in ("left", "right")]
    except InvalidInput:
        return None
    if not all(0 <= w[0] < cams[s].width and 0 <= w[1] < cams[s].height
               for w, s in zip(uv, ("left", "right"))):
        return None
    return uv


def perturbed_cameras(principal_shift: float = 1.0, rotation_deg: float = 1.0
                      ) -> tuple[dict[str, CameraIntrinsics], np.ndarray]:
    """Real cameras that differ from the nominal ones: principal points shifted (+3, -2) px
    (left) and (-2, +3) px (right), times ``principal_shift``, and the left camera rotated
    ``rotation_deg`` about its y axis. Returns (intrinsics per side, left rotation (3, 3))."""
    n = CameraIntrinsics()
    s = float(principal_shift)
    cams = {"left": CameraIntrinsics(cx=n.cx + 3.0 * s, cy=n.cy - 2.0 * s),
            "right": CameraIntrinsics(cx=n.cx - 2.0 * s, cy=n.cy + 3.0 * s)}
    a = np.radians(rotation_deg)
    rot = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    return cams, rot


def stereo_samples(n: int, seed: int, eyes: EyeKinematics, T_root_head: np.ndarray,
                   hands: np.ndarray, cams: Mapping[str, CameraIntrinsics],
                   rot_left: np.ndarray, noise: float, gaze, q_head: np.ndarray,
                   eye_error: float = 0.03) -> StereoSamples:
    """``n`` samples of the hand positions ``hands`` (m, 3) [m] (cycled) seen by the cameras
    ``cams`` (left extrinsic rotation ``rot_left``), the eyes fixating each hand from the head
    at ``q_head`` up to a normal ``eye_error`` [rad], pixel noise ``noise`` [px].

    Raises :class:`InvalidInput` when fewer than ``n`` hands are in view of both cameras
    within 50 n tries."""
    rng = np.random.default_rng(seed)
    hands = np.asarray(hands, dtype=float).reshape(-1, 3)
    if len(hands) == 0 or n < 1:
        raise InvalidInput(f"stereo_samples: need hands and n >= 1, got {len(hands)}, {n}")
    x, p, poses = [], [], []
    k = 0
    while len(x) < n:
        if k > 50 * n:
            raise InvalidInput(f"stereo_samples: only {len(x)} of {n} hands in view of both "
                               "cameras")
        h = hands[k % len(hands)]
        k += 1
        if h[0] > -0.1:  # behind the eyes' reach of view: not a sample
            continue
        try:
            (tilt, version, verg), _ = gaze.eyes_for(q_head, h)
        except InvalidInput:
            continue
        tilt, version = tilt + rng.normal(0, eye_error), version + rng.normal(0, eye_error)
        try:
            Tn = {s: eyes.T_root_camera(T_root_head, s, tilt, version, verg)
                  for s in ("left", "right")}
        except InvalidInput:
            continue
        uv = _seen(Tn, rot_left, h, cams, rng, noise)
        if uv is None:
            continue
        x.append(np.r_[uv[0], uv[1], tilt, version, verg])
        p.append(h)
        poses.append([Tn["left"], Tn["right"]])
    return StereoSamples(np.array(x), np.array(p), np.array(poses))


def view_samples(n: int, seed: int, eyes: EyeKinematics, T_root_head: np.ndarray,
                 eye_angles: np.ndarray, cams: Mapping[str, CameraIntrinsics],
                 rot_left: np.ndarray, noise: float, eye_jitter: float = 0.05,
                 depth: tuple[float, float] = (0.3, 0.8)) -> StereoSamples:
    """``n`` samples of points anywhere in view: the eyes at ``eye_angles`` (tilt, version,
    vergence) [rad] plus a normal ``eye_jitter`` [rad] on tilt and version, a point drawn at a
    uniform left pixel and depth [m] along the real left camera's ray, projected into both real
    cameras with pixel noise ``noise`` [px] and kept when the right one sees it too (the eyes
    still, the marker anywhere in the images: what a map for a still gaze learns from)."""
    rng = np.random.default_rng(seed)
    base = np.asarray(eye_angles, dtype=float).reshape(3)
    left = cams["left"]
    x, p, poses = [], [], []
    k = 0
    while len(x) < n:
        if k > 50 * n:
            raise InvalidInput(f"view_samples: only {len(x)} of {n} points in view of both "
                               "cameras")
        k += 1
        tilt, version = base[:2] + rng.normal(0, eye_jitter, 2)
        Tn = {s: eyes.T_root_camera(T_root_head, s, tilt, version, base[2])
              for s in ("left", "right")}
        Rl = Tn["left"][:3, :3] @ rot_left
        u, v = rng.uniform(0, left.width), rng.uniform(0, left.height)
        z = rng.uniform(*depth)
        h = Tn["left"][:3, 3] + Rl @ np.array([(u - left.cx) / left.fx * z,
                                               (v - left.cy) / left.fy * z, z])
        uv = _seen(Tn, rot_left, h, cams, rng, noise)
        if uv is None:
            continue
        x.append(np.r_[uv[0], uv[1], tilt, version, base[2]])
        p.append(h)
        poses.append([Tn["left"], Tn["right"]])
    return StereoSamples(np.array(x), np.array(p), np.array(poses))
