"""Closed-loop scenarios on :class:`SimLoop` shared by the tests and the benchmarks: the 2 s
minimum-jerk tracking move, the contact-free periodic arm motion of the Table 1 experiment and
the hand pressing on the table. Angles in the arguments are [deg], results in [deg] / SI."""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np

from icub_pmp.kinematics.robot_spec import RobotSpec
from icub_sim_bridge.harness.sim_loop import LoopStep, SimLoop

__all__ = [
    "min_jerk",
    "raised_posture",
    "TrackingResult",
    "track_min_jerk",
    "start_periodic_motion",
    "press_left_hand_on_table",
    "TRACKING_JOINTS",
    "TRACKING_DELTA_DEG",
]

#: the tracking move: torso yaw, right arm 6 joints, left elbow, by these amounts [deg]
TRACKING_JOINTS = ("torso_yaw", "r_shoulder_pitch", "r_shoulder_roll", "r_shoulder_yaw",
                   "r_elbow", "r_wrist_prosup", "l_elbow")
TRACKING_DELTA_DEG = (20.0, -30.0, 20.0, 25.0, 35.0, 30.0, 20.0)


def min_jerk(q0: np.ndarray, q1: np.ndarray, duration: float, t: float
             ) -> tuple[np.ndarray, np.ndarray]:
    """Minimum-jerk position and velocity from ``q0`` to ``q1`` in ``duration`` [s] at ``t``."""
    s = min(max(t / duration, 0.0), 1.0)
    d = q1 - q0
    return (q0 + d * (10 * s**3 - 15 * s**4 + 6 * s**5),
            d * (30 * s**2 - 60 * s**3 + 30 * s**4) / duration)


def raised_posture(spec: RobotSpec) -> dict[str, float]:
    """The rest posture with both forearms raised clear of the table and objects [rad]."""
    q = dict(spec.posture("rest"))
    for s in "lr":
        q.update({f"{s}_shoulder_pitch": math.radians(-60), f"{s}_shoulder_roll":
                  math.radians(35), f"{s}_elbow": math.radians(80)})
    return q


class TrackingResult(NamedTuple):
    """Tracking of a min-jerk move: RMS and max error during it, final error ``settle`` s
    after [deg] (over all joints), number of steps with a saturated command, the steps."""

    rms_deg: float
    max_deg: float
    final_deg: float
    saturated_steps: int
    steps: list[LoopStep]


def track_min_jerk(
    loop: SimLoop,
    names: Sequence[str] = TRACKING_JOINTS,
    delta_deg: Sequence[float] = TRACKING_DELTA_DEG,
    duration: float = 2.0,
    points: int = 40,
    settle: float = 0.3,
) -> TrackingResult:
    """Send a min-jerk move of ``names`` by ``delta_deg`` as ``points`` trajectory points with
    velocities (as a planner does) and run it; errors vs the analytic profile."""
    c = loop.controller
    idx = c.indices(names)
    q0 = loop.sim.joint_state().position[idx].copy()
    q1 = q0 + np.radians(delta_deg)
    ts = np.arange(1, points + 1) * duration / points
    pos = np.array([min_jerk(q0, q1, duration, t)[0] for t in ts])
    vel = np.array([min_jerk(q0, q1, duration, t)[1] for t in ts])
    t0 = loop.t
    c.set_trajectory(c.make_trajectory(names, ts, pos, vel, start=t0), t0)
    steps = loop.run(duration + settle)
    err = np.array([s.q[idx] - min_jerk(q0, q1, duration, s.t - t0)[0] for s in steps])
    moving = err[: int(round(duration / loop.sim.config.timestep))]
    return TrackingResult(
        float(np.degrees(np.sqrt(np.mean(moving**2)))),
        float(np.degrees(np.abs(moving).max())),
        float(np.degrees(np.abs(err[-1]).max())),
        int(sum(s.control.saturated.any() for s in steps)),
        steps,
    )


def start_periodic_motion(loop: SimLoop, duration: float) -> float:
    """Start a contact-free periodic motion of both arms from the raised posture: 10 joints
    (shoulder pitch/roll/yaw, elbow, prosup), 10-20 deg at 0.37-0.71 Hz, faded in over 1 s
    (minimum-jerk envelope), sent as points every 20 ms. Returns its start time [s]."""
    c = loop.controller
    names = [f"{s}_{j}" for s in "lr" for j in
             ("shoulder_pitch", "shoulder_roll", "shoulder_yaw", "elbow", "wrist_prosup")]
    idx = c.indices(names)
    # about the held set-point (on the imperfect robot the measured posture sags from it: a
    # trajectory from there would start with a jump)
    q0 = c.setpoints.q[idx].copy()
    amp = np.radians([15, 10, 15, 20, 20] * 2)  # peak speeds up to 84 deg/s (limit 100)
    freq = np.array([0.5, 0.37, 0.61, 0.53, 0.71, 0.47, 0.41, 0.59, 0.51, 0.67])
    ts = np.arange(1, int(round(duration / 0.02)) + 1) * 0.02
    r = np.clip(ts / 1.0, 0.0, 1.0)
    fade = (10 * r**3 - 15 * r**4 + 6 * r**5)[:, None]
    pos = q0 + fade * amp * np.sin(2 * np.pi * freq * ts[:, None])
    vel = np.gradient(pos, ts, axis=0)
    t0 = loop.t
    c.set_trajectory(c.make_trajectory(names, ts, pos, vel, start=t0), t0)
    return t0


def press_left_hand_on_table(loop: SimLoop) -> None:
    """Drive the left hand down onto the table from rest (shoulder pitch +12 deg, elbow
    -25 deg in 1 s): in impedance mode it then presses with a steady force."""
    c = loop.controller
    names = ["l_shoulder_pitch", "l_elbow"]
    q = loop.sim.joint_state().position[c.indices(names)]
    c.set_trajectory(c.make_trajectory(names, [1.0], [q + np.radians([12.0, -25.0])]), loop.t)
