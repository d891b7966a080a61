"""Stereo samples of hand positions for the eye-hand map (force paper eq 12), no ROS.

What the eyes would see of a hand marker at known positions: the marker is projected into both
cameras (the *real* cameras, which may differ from the nominal model the triangulator assumes:
other principal points, a rotated left camera) with pixel noise, and the sample is kept when
both images see it. Where the eyes look:

- :func:`gaze_samples` (what the maps are learned from): the gaze controller follows the
  babbling hand with the neck and the eyes (:meth:`GazeController.solve`) and lags behind it,
  so the hand is seen anywhere around the image centre, from every head posture the gaze takes
  at use (looking down at the table too); :func:`babbled_hands` babbles the trunk with the arms
  so the hands cover the table in front of the robot;
- :func:`stereo_samples`: the eyes fixate each hand (closed-form eyes, head still) up to a
  random error (the hand always near the image centre);
- :func:`view_samples`: the eyes still, points anywhere in view.

The bench and the tests train and test eye-hand maps on these (decision 0070).
"""

from __future__ import annotations

from typing import Mapping, NamedTuple, Sequence

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics, EyeKinematics, project_point
from icub_pmp.kinematics.robot_spec import RobotSpec

__all__ = ["StereoSamples", "stereo_samples", "view_samples", "gaze_samples", "babbled_hands",
           "perturbed_cameras", "gaze_lag_offset"]


class StereoSamples(NamedTuple):
    """Samples as arrays."""

    inputs: np.ndarray  # (n, 7) EYE_HAND_INPUTS: pixels [px], eye angles [rad]
    hands: np.ndarray  # (n, 3) hand positions in root_link [m]
    poses: np.ndarray  # (n, 2, 4, 4) the nominal camera poses (left, right) in root_link
    heads: np.ndarray  # (n, 4, 4) the head frame (T_root_head) of each sample

    def hands_in_head(self) -> np.ndarray:
        """The hand positions (n, 3) [m] in each sample's head frame (eq 12's output)."""
        rel = self.hands - self.heads[:, :3, 3]
        return np.einsum("nij,ni->nj", self.heads[:, :3, :3], rel)

    def head_to_root(self, points_head: np.ndarray) -> np.ndarray:
        """Points (n, 3) [m] given in each sample's head frame, in root_link."""
        p = np.asarray(points_head, dtype=float).reshape(-1, 3)
        return np.einsum("nij,nj->ni", self.heads[:, :3, :3], p) + self.heads[:, :3, 3]

    def projected(self, camera: CameraIntrinsics) -> "StereoSamples":
        """The same samples with the pixels where cameras of intrinsics ``camera`` at the
        nominal poses :attr:`poses` see the hands (what the nominal model predicts of what
        the eyes see)."""
        rel = self.hands[:, None, :] - self.poses[:, :, :3, 3]  # (n, 2, 3)
        pc = np.einsum("nsji,nsj->nsi", self.poses[:, :, :3, :3], rel)
        uv = np.stack([camera.fx * pc[..., 0] / pc[..., 2] + camera.cx,
                       camera.fy * pc[..., 1] / pc[..., 2] + camera.cy], axis=-1)
        inputs = self.inputs.copy()
        inputs[:, :4] = uv.reshape(-1, 4)
        return self._replace(inputs=inputs)


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
    return StereoSamples(np.array(x), np.array(p), np.array(poses),
                         np.broadcast_to(T_root_head, (len(x), 4, 4)).copy())


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
    return StereoSamples(np.array(x), np.array(p), np.array(poses),
                         np.broadcast_to(T_root_head, (len(x), 4, 4)).copy())


def babbled_hands(n: int, seed: int, provider, arms: Sequence[str] = ("right", "left"),
                  trunk: bool = True, region: tuple[Sequence[float], Sequence[float]] | None = None,
                  region_fraction: float = 0.5, spec: RobotSpec | None = None,
                  offset: Sequence[float] | None = None
                  ) -> tuple[np.ndarray, list[dict[str, float]]]:
    """Motor babbling of the hands for the eye-hand map: ``n`` postures, each of one of
    ``arms`` (in turn) with its 7 joints (and the 3 trunk joints with ``trunk``, as
    ``icub babble`` does with the torso) uniform within the body model's limits, the other
    joints at rest. With ``region`` (lower, upper corners [m] in root_link, e.g. over the table
    where the robot acts), a ``region_fraction`` of the postures are babbles whose hand falls in
    it (the others are drawn again: babbling directed at that region). Returns the hand
    positions (n, 3) [m] in root_link (``provider``'s forward kinematics, e.g.
    :class:`~icub_pmp.pmp.pinocchio_provider.PinocchioJacobianProvider`) and the postures
    {joint: rad} (the trunk moves the head the gaze looks from). With ``offset`` (3,) [m] the
    babbled point is that point of the hand frame (a marker, a held tool's tip), not its
    origin.

    Raises :class:`InvalidInput` for no arm, ``n`` < 1, a fraction outside [0, 1] or a region
    the hands do not reach (none of 5,000 babbles per wanted posture in it)."""
    spec = spec or RobotSpec.load()
    if int(n) < 1 or not arms or not 0.0 <= region_fraction <= 1.0:
        raise InvalidInput(f"babbled_hands: need n >= 1, an arm and a region fraction in "
                           f"[0, 1], got {n}, {arms}, {region_fraction}")
    lo, hi = (None, None) if region is None else (np.asarray(region[0], float),
                                                  np.asarray(region[1], float))
    names = list(provider.joint_names)
    rest = spec.posture("rest")
    q0 = np.array([rest.get(j, 0.0) for j in names])
    rng = np.random.default_rng(seed)
    n_region = 0 if region is None else int(round(region_fraction * int(n)))
    hands, postures = np.empty((int(n), 3)), []
    for k in range(int(n)):
        arm = arms[k % len(arms)]
        joints = spec.arm_joints(arm) + (spec.torso_joints if trunk else ())
        idx = [names.index(j) for j in joints]
        for _ in range(5000):
            q = q0.copy()
            q[idx] = rng.uniform(provider.lower[idx], provider.upper[idx])
            if offset is None:
                hand = provider.positions(q, [spec.hand_frame(arm)])[0]
            else:
                kin = provider.kinematics(q, [spec.hand_frame(arm)])
                hand = kin.positions[0] + kin.rotations[0] @ np.asarray(offset, dtype=float)
            if k >= n_region or bool(np.all((hand >= lo) & (hand <= hi))):
                break
        else:
            raise InvalidInput(f"babbled_hands: the {arm} hand does not reach the region "
                               f"{np.round(lo, 3).tolist()} - {np.round(hi, 3).tolist()}")
        hands[k] = hand
        postures.append(dict(zip(names, (float(v) for v in q))))
    return hands, postures


def gaze_lag_offset(rng: np.random.Generator, lag: float) -> np.ndarray:
    """Where the gaze fixates relative to the hand it follows: a point (3,) [m] uniform in the
    ball of radius ``lag`` [m] (the gaze lags the moving hand)."""
    off = rng.normal(size=3)
    return off * lag * rng.uniform() ** (1.0 / 3.0) / max(float(np.linalg.norm(off)), 1e-12)


def gaze_samples(n: int, seed: int, eyes: EyeKinematics, gaze, hands: np.ndarray,
                 postures: Sequence[Mapping[str, float]], cams: Mapping[str, CameraIntrinsics],
                 rot_left: np.ndarray, noise: float, lag: float = 0.2) -> StereoSamples:
    """``n`` samples of the hands ``hands`` (m, 3) [m] at the body postures ``postures``
    (m dicts, e.g. :func:`babbled_hands`), drawn at random, while the gaze follows them: the
    gaze controller (``gaze``, :class:`~icub_pmp.gaze.gaze_controller.GazeController`) fixates
    a point within ``lag`` [m] of the hand (uniform in the ball: the gaze lags the moving hand)
    with the neck and the eyes from the posture's trunk; the hand is seen by the cameras
    ``cams`` (left extrinsic rotation ``rot_left``) with pixel noise ``noise`` [px].

    Raises :class:`InvalidInput` when fewer than ``n`` hands are in view of both cameras
    within 50 n tries."""
    rng = np.random.default_rng(seed)
    hands = np.asarray(hands, dtype=float).reshape(-1, 3)
    if len(hands) == 0 or len(hands) != len(postures) or n < 1:
        raise InvalidInput(f"gaze_samples: need as many postures as hands and n >= 1, got "
                           f"{len(hands)} hands, {len(postures)} postures, n {n}")
    x, p, poses, heads = [], [], [], []
    k = 0
    while len(x) < n:
        if k > 50 * n:
            raise InvalidInput(f"gaze_samples: only {len(x)} of {n} hands in view of both "
                               "cameras")
        k += 1
        i = int(rng.integers(len(hands)))
        h = hands[i]
        off = gaze_lag_offset(rng, lag)
        try:
            sol = gaze.solve(h + off, postures[i])
        except InvalidInput:  # the fixation point is behind the head or too near the eyes
            continue
        q, _ = gaze.configuration(postures[i])
        q[gaze.neck.idx] = sol.neck
        T_head = gaze.neck.head_pose(q)
        Tn = {s: eyes.T_root_camera(T_head, s, *sol.eyes) for s in ("left", "right")}
        uv = _seen(Tn, rot_left, h, cams, rng, noise)
        if uv is None:
            continue
        x.append(np.r_[uv[0], uv[1], sol.eyes])
        p.append(h)
        poses.append([Tn["left"], Tn["right"]])
        heads.append(T_head)
    return StereoSamples(np.array(x), np.array(p), np.array(poses), np.array(heads))
