"""Rendered views of the hand marker for eye-calibration and eye-hand-map learning, tests and
benchmarks.

The arm is posed kinematically at random postures (no stepping), the head fixates the marker's
kinematic position with the gaze controller's solution plus a random offset of the eyes (so the
marker falls anywhere in the images), both eyes render (with the scene's realism, i.e. the
cameras as built), and the marker is detected by the body schema's OpenCV detector. What a
babbling run over ROS records, without the minutes of simulated motion.

- :func:`rendered_marker_observations`: one arm, the eyes jittered around the marker (the
  eye calibration's views, decision 0057);
- :func:`rendered_gaze_samples`: babbled postures of both arms and the trunk, the gaze
  following the hand with a lag (the eye-hand map's protocol of decision 0070), the samples
  as eq 12 of the force paper takes them (decision 0071).
"""

from __future__ import annotations

import time
from typing import Mapping, NamedTuple, Sequence

import numpy as np

from icub_pmp.body_schema.eye_hand_samples import StereoSamples, gaze_lag_offset
from icub_pmp.body_schema.marker_detector import MarkerDetector
from icub_pmp.vision.eye_calibration import MarkerObservations

__all__ = ["rendered_marker_observations", "rendered_gaze_samples", "RenderedGazeSamples",
           "OUT_OF_VIEW"]

#: where the scene's objects wait while the robot babbles (behind it, out of view) [m]
OUT_OF_VIEW = (0.5, 0.0, -0.3)

_NECK = ("neck_pitch", "neck_roll", "neck_yaw")
_EYES = ("eyes_tilt", "eyes_version", "eyes_vergence")


def rendered_marker_observations(scene, n: int, seed: int = 0, arm: str = "right",
                                 max_tries: int | None = None) -> MarkerObservations:
    """``n`` marker observations of ``scene`` (a :class:`~.table_scene.TableScene`): the marker
    from the nominal forward kinematics and the scene's ``hand_marker_offset``, nominal camera
    frames, detected pixels. Postures whose marker is not seen by both eyes are skipped."""
    from icub_pmp.errors import IcubPmpError
    from icub_pmp.gaze.gaze_controller import GazeController

    model = scene.head.model
    gaze = GazeController()
    detector = MarkerDetector()
    spec = scene.sim.spec
    joints = spec.arm_joints(arm)
    idx = model.indices(joints)
    lo, hi = model.lower[idx], model.upper[idx]
    frame = spec.hand_frame(arm)
    offset = np.asarray(scene.sim.config.hand_marker_offset, dtype=float)
    rest = dict(spec.posture("rest"))
    rng = np.random.default_rng(seed)
    rows: list[tuple] = []
    tries = 0
    while len(rows) < n and tries < (max_tries or 20 * n):
        tries += 1
        q = dict(rest)
        q.update(zip(joints, rng.uniform(lo + 0.05 * (hi - lo), hi - 0.05 * (hi - lo))))
        pose = model.frame_pose(model.q_from_dict(q), frame)
        p = pose.translation + pose.rotation @ offset
        if p[0] > -0.15:  # beside or behind the body: the eyes cannot look there
            continue
        try:
            sol = gaze.solve(p, q)
        except IcubPmpError:
            continue
        q.update(zip(_NECK, map(float, sol.neck)))
        q.update(zip(_EYES, map(float, sol.eyes)))
        q["eyes_version"] += rng.uniform(-0.12, 0.12)
        q["eyes_tilt"] += rng.uniform(-0.1, 0.1)
        scene.pose(q, {})
        f = scene.render()
        dl, dr = detector.detect(f.left), detector.detect(f.right)
        if dl.found and dr.found:
            rows.append((p, f.poses.T_root_left, f.poses.T_root_right,
                         (dl.u, dl.v, dr.u, dr.v)))
    if not rows:
        return MarkerObservations(np.zeros((0, 3)), np.zeros((0, 4, 4)), np.zeros((0, 4, 4)),
                                  np.zeros((0, 4)))
    return MarkerObservations(*(np.array([r[i] for r in rows], dtype=float) for i in range(4)))


class RenderedGazeSamples(NamedTuple):
    """What :func:`rendered_gaze_samples` gives.

    Attributes:
        samples: the kept samples; ``inputs`` (n, 7) detected pixels [px] and encoder eye
            angles [rad], ``hands`` the marker (n, 3) [m] in root_link by the nominal forward
            kinematics of the encoder joints, ``poses`` the nominal camera poses (n, 2, 4, 4)
            and ``heads`` the head frames (n, 4, 4) of those joints.
        truth: (n, 3) [m] the marker's true position in the physics (for evaluation only).
        renders: stereo pairs rendered (kept or not).
        seconds: wall time spent [s].
    """

    samples: StereoSamples
    truth: np.ndarray
    renders: int
    seconds: float


def rendered_gaze_samples(scene, n: int, seed: int, postures: Sequence[Mapping[str, float]],
                          arms: Sequence[str], lag: float = 0.2, gate_px: float = 40.0,
                          min_fill: float = 0.5, max_tries: int | None = None,
                          table: bool = False) -> RenderedGazeSamples:
    """``n`` eye-hand samples of ``scene`` (a :class:`~.table_scene.TableScene`, its realism's
    cameras) while the gaze follows the babbling hands: a posture of ``postures`` (dicts
    {joint: rad}, e.g. :func:`~icub_pmp.body_schema.babbled_hands`, the hand of ``arms[i]``
    babbling) drawn at random, the gaze controller fixating a point within ``lag`` [m] of its
    marker (:func:`gaze_lag_offset`), both eyes rendered with the objects out of view, the
    marker detected in both images. Without ``table`` the table is taken away while the robot
    babbles (as a robot babbles before the table is put in front of it): the hand is then seen
    below the table top too, where the table's own points are at use.

    What the robot knows, not the simulator's truth: the eye angles, the marker (forward
    kinematics + ``hand_marker_offset``) and the head frame come from the encoders' joint
    state and the nominal body model. The marker's blob is the one within ``gate_px`` [px] of
    where the nominal cameras put it (the other hand's marker may be in view too) and covering
    at least ``min_fill`` of the disc the nominal cameras predict (a marker half hidden by the
    hand biases its centroid): the nominal model only picks the blob, the pixels are the
    detected ones. Fewer than ``n`` samples when ``max_tries`` (default 4 n) postures run
    out."""
    from icub_pmp.errors import IcubPmpError
    from icub_pmp.gaze.gaze_controller import GazeController
    from icub_pmp.kinematics.eye_kinematics import project_point

    t0 = time.perf_counter()
    model = scene.head.model
    gaze = GazeController(model=model)
    detector = MarkerDetector()
    spec = scene.sim.spec
    sim = scene.sim
    nominal = scene.camera  # camera_info's intrinsics (the preset renders with others)
    offset = np.asarray(sim.config.hand_marker_offset, dtype=float)
    radius = float(sim.config.hand_marker_radius)
    if len(postures) != len(arms) or len(postures) == 0:
        raise IcubPmpError(f"rendered_gaze_samples: need one arm per posture, got "
                           f"{len(postures)} postures and {len(arms)} arms")
    mj_ids = {a: sim.model.geom(f"{spec.hand_frame(a)[:2]}hand_marker").id for a in set(arms)}
    rng = np.random.default_rng(seed)
    far = {o: OUT_OF_VIEW for o in sim.object_names}
    rows: list[tuple] = []
    tries = renders = 0
    scene.table_away(not table)
    try:
        while len(rows) < n and tries < (max_tries or 4 * n):
            tries += 1
            i = int(rng.integers(len(postures)))
            arm, q = arms[i], dict(postures[i])
            frame = spec.hand_frame(arm)
            p_cmd = _marker(model, q, frame, offset)
            try:
                sol = gaze.solve(p_cmd + gaze_lag_offset(rng, lag), q)
            except IcubPmpError:  # behind the head or too near the eyes
                continue
            q.update(zip(_NECK, map(float, sol.neck)))
            q.update(zip(_EYES, map(float, sol.eyes)))
            scene.pose(q, far)
            images = scene.render_eyes()
            renders += 1
            js = dict(zip(sim.joint_names, sim.joint_state().position.tolist()))  # the encoders
            p = _marker(model, js, frame, offset)
            poses = scene.head.poses(js)
            uv = []
            for side, T in (("left", poses.T_root_left), ("right", poses.T_root_right)):
                depth = float((T[:3, :3].T @ (p - T[:3, 3]))[2])
                if depth <= 0.05:
                    break
                d = detector.detect_near(images[side], tuple(project_point(T, p, nominal)), gate_px)
                if not d.found or d.area < min_fill * np.pi * (nominal.fx * radius / depth) ** 2:
                    break
                uv += [d.u, d.v]
            if len(uv) < 4:
                continue
            eyes = [js[j] for j in _EYES]
            rows.append((np.r_[uv, eyes], p, np.stack([poses.T_root_left, poses.T_root_right]),
                         scene.head.head_pose(js), sim.data.geom_xpos[mj_ids[arm]].copy()))
    finally:
        scene.table_away(False)
    cols = [np.array([r[k] for r in rows], dtype=float).reshape((len(rows),) + shape)
            for k, shape in enumerate(((7,), (3,), (2, 4, 4), (4, 4), (3,)))]
    return RenderedGazeSamples(StereoSamples(*cols[:4]), cols[4], renders,
                               time.perf_counter() - t0)


def _marker(model, joints: Mapping[str, float], frame: str, offset: np.ndarray) -> np.ndarray:
    """The hand marker (3,) [m] in root_link by forward kinematics of ``joints``."""
    pose = model.frame_pose(model.q_from_dict({k: float(v) for k, v in joints.items()}), frame)
    return pose.translation + pose.rotation @ offset

