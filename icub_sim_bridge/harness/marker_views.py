"""Rendered views of the hand marker for eye-calibration tests and benchmarks.

The arm is posed kinematically at random postures (no stepping), the head fixates the marker's
kinematic position with the gaze controller's solution plus a random offset of the eyes (so the
marker falls anywhere in the images), both eyes render (with the scene's realism, i.e. the
cameras as built), and the marker is detected by the body schema's OpenCV detector. What a
babbling run over ROS records, without the minutes of simulated motion.
"""

from __future__ import annotations

import numpy as np

from icub_pmp.body_schema.marker_detector import MarkerDetector
from icub_pmp.vision.eye_calibration import MarkerObservations

__all__ = ["rendered_marker_observations"]

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
