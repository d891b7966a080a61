"""ObjectTracker: follow one object in root_link from its stereo measurements.

A constant-velocity Kalman filter (Bar-Shalom, Li, Kirubarajan, "Estimation with Applications
to Tracking and Navigation", 2001, sect. 6.3.2: the discrete white-noise acceleration model,
acceleration sigma ``position_noise``) on the object's centre. Every estimate is about the time
of the images it was measured in (``stamp``), and a constant-velocity model follows a moving
object without the lag of an exponential smoother.

The motion segmenter sees an object only while it moves; the node then measures it in its own
image region (still measurements, ``moving=False``), which here also sets its velocity to zero;
a still measurement inconsistent with the prediction (beyond :data:`JUMP_CHI2`, within
``track_gate``) restarts the target there: the object was moved without being seen moving, and
averaging its old and new places would leave the target between them for many frames.
Without any measurement the target is held where it was last measured (an object that nobody
sees moving stays where it is) for ``hold_time``. A measurement farther than ``track_gate``
from the target is another object: it takes over only after ``switch_frames`` measurements in a
row near each other, or at once when the target itself has not been measured for
``switch_frames`` frames (a stale target, e.g. of an object taken away, must not hide the next).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.vision.object_locator import ObjectEstimate
from icub_pmp.vision.stereo_target_config import StereoTargetConfig

__all__ = ["ObjectTracker", "TrackedObject", "TRACK_STATES", "JUMP_CHI2"]

#: a still measurement this far from the prediction (squared Mahalanobis distance; the chi-square
#: quantile 0.999 of 3 degrees of freedom) restarts the target there: the object was moved
#: without being seen moving (a jump, a stop that the prediction overshot)
JUMP_CHI2 = 16.27

#: ``moving`` (measured, seen moving), ``still`` (measured, not moving), ``held`` (not measured
#: this frame), ``none`` (no target).
TRACK_STATES = ("moving", "still", "held", "none")


@dataclasses.dataclass(frozen=True)
class TrackedObject:
    """The tracked object at one image stamp.

    Attributes:
        valid: a target exists.
        state: one of :data:`TRACK_STATES`.
        stamp: time of the images this is about [s].
        position: (3,) object centre in root_link [m] (NaN when not valid).
        velocity: (3,) [m/s].
        covariance: (3, 3) of the position [m^2].
        top: (3,) centre of the top face [m] (the last measurement's, moved with the centre).
        radius: horizontal extent about the axis [m] (last measurement).
        height: top face above the support [m] (last measurement).
        last_measured: stamp of the last measurement [s].
        measurements: number of measurements since the target was acquired.
    """

    valid: bool
    state: str
    stamp: float
    position: np.ndarray
    velocity: np.ndarray
    covariance: np.ndarray
    top: np.ndarray
    radius: float
    height: float
    last_measured: float
    measurements: int

    def __post_init__(self) -> None:
        for name in ("position", "velocity", "covariance", "top"):
            a = np.array(getattr(self, name), dtype=float, copy=True)
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    @property
    def speed(self) -> float:
        """Norm of the velocity [m/s]."""
        return float(np.linalg.norm(self.velocity))


def _none(stamp: float) -> TrackedObject:
    nan3 = np.full(3, np.nan)
    return TrackedObject(False, "none", stamp, nan3, np.zeros(3), np.full((3, 3), np.nan), nan3,
                         math.nan, math.nan, math.nan, 0)


class ObjectTracker:
    """Constant-velocity tracking of one object (module doc)."""

    def __init__(self, config: StereoTargetConfig | None = None):
        self.config = config or StereoTargetConfig()
        self.reset()

    def reset(self) -> None:
        """Drop the target."""
        self._x = np.zeros(6)
        self._P = np.eye(6)
        self._t = -math.inf
        self._target = _none(math.nan)
        self._shape: ObjectEstimate | None = None
        self._candidate: np.ndarray | None = None
        self._candidate_frames = 0
        self._misses = 0
        self._count = 0
        self._last = math.nan

    @property
    def target(self) -> TrackedObject:
        """The current target."""
        return self._target

    def update(self, stamp: float, measurement: ObjectEstimate | None,
               moving: bool = True, other: ObjectEstimate | None = None) -> TrackedObject:
        """Advance to ``stamp`` [s] with this frame's measurement (None: not measured).

        Args:
            stamp: time of the images [s]; older than the last update by more than 0.5 s
                resets the tracker (simulation reset, bag loop), otherwise older ones are
                ignored.
            measurement: the object measured in this frame's images.
            moving: the measurement comes from motion blobs (False: the object was measured in
                its own region without motion, so it is still).
            other: another object seen moving this frame, beyond ``track_gate`` of the target
                (while ``measurement`` is the target's own): it takes over once seen moving
                ``switch_frames`` frames in a row, even from a target measured at rest (the
                robot attends to what moves; a still object taken for the target, or one that
                was the target and stopped, must not hide a new motion).

        Raises:
            InvalidInput: ``stamp`` is not finite.
        """
        if not math.isfinite(stamp):
            raise InvalidInput(f"stamp: expected a finite time [s], got {stamp}")
        c = self.config
        if self._target.valid and stamp < self._t - 0.5:
            self.reset()
        if self._target.valid and stamp < self._t:
            return self._target
        if not self._target.valid:
            if measurement is None:
                self._target = _none(stamp)
                return self._target
            self._start(stamp, measurement, moving)
            return self._target
        self._predict(stamp)
        if measurement is None:
            if stamp - self._target.last_measured > c.hold_time:
                self.reset()
                self._target = _none(stamp)
                return self._target
            self._miss()
            self._publish(stamp, "held")
            return self._target
        z = np.asarray(measurement.position, float)
        if np.linalg.norm(z - self._x[:3]) > c.track_gate:
            # another object (or a jump): take over only if it persists
            self._count_candidate(z)
            # a target that has not been measured for switch_frames frames (its region shows
            # nothing: the object was taken away) gives way at once
            if self._candidate_frames >= c.switch_frames or self._misses >= c.switch_frames:
                self._start(stamp, measurement, moving)
            else:
                self._miss()
                self._publish(stamp, "held")
            return self._target
        self._misses = 0
        if other is not None and not moving:
            self._count_candidate(np.asarray(other.position, float))
            if self._candidate_frames >= c.switch_frames:
                self._start(stamp, other, True)
                return self._target
        else:
            self._candidate, self._candidate_frames = None, 0
        if not moving and self._jumped(z, measurement.covariance):
            # measured at rest where the target cannot be: moved without being seen moving
            self._start(stamp, measurement, moving)
            return self._target
        if not moving:
            self._x[3:] = 0.0
            self._P[3:, 3:] = np.eye(3) * 1e-6
            self._P[:3, 3:] = self._P[3:, :3] = 0.0
        H = np.hstack([np.eye(3), np.zeros((3, 3))])
        S = H @ self._P @ H.T + measurement.covariance
        K = self._P @ H.T @ np.linalg.inv(S)
        self._x = self._x + K @ (z - self._x[:3])
        self._P = (np.eye(6) - K @ H) @ self._P
        self._on_support(measurement.support_normal)
        self._shape = measurement
        self._count += 1
        self._last = stamp
        speed = float(np.linalg.norm(self._x[3:]))
        self._publish(stamp, "moving" if moving and speed > c.still_speed else "still")
        return self._target

    def _miss(self) -> None:
        """The target was not measured this frame: after ``still_frames`` such frames its
        velocity is zeroed (nobody sees it move: it stays where it is, rather than drifting
        away along a velocity that is no longer measured)."""
        self._misses += 1
        if self._misses >= self.config.still_frames:
            self._x[3:] = 0.0

    def _on_support(self, normal: np.ndarray) -> None:
        """Keep the velocity in the support's plane (``normal`` (3,), upwards): an object
        resting on a support slides along it. Without this, a few measurements of a part of
        the object (its top cut by the image's border, the hand over it) give it a vertical
        velocity, and the held target sinks through the table within a few frames (seen in
        the vision bench: 12 cm in 0.2 s)."""
        n = np.asarray(normal, float)
        norm = float(np.linalg.norm(n))
        if not np.isfinite(norm) or norm < 1e-9:
            return
        n = n / norm
        T = np.eye(6)
        T[3:, 3:] -= np.outer(n, n)
        self._x = T @ self._x
        self._P = T @ self._P @ T.T
        self._P[3:, 3:] += np.outer(n, n) * 1e-6

    def _count_candidate(self, position: np.ndarray) -> None:
        """Count another object measured at ``position`` (3,) [m]: one more frame in a row if
        it is within ``track_gate`` of the last candidate, else a new candidate."""
        if self._candidate is not None and \
                np.linalg.norm(position - self._candidate) <= self.config.track_gate:
            self._candidate_frames += 1
        else:
            self._candidate_frames = 1
        self._candidate = position

    # ------------------------------------------------------------------ filter
    def _start(self, stamp: float, m: ObjectEstimate, moving: bool) -> None:
        self._x = np.concatenate([np.asarray(m.position, float), np.zeros(3)])
        self._P = np.zeros((6, 6))
        self._P[:3, :3] = m.covariance
        self._P[3:, 3:] = np.eye(3) * (0.5**2 if moving else 1e-6)
        self._shape = m
        self._count = 1
        self._last = stamp
        self._t = stamp
        self._candidate, self._candidate_frames, self._misses = None, 0, 0
        self._publish(stamp, "moving" if moving else "still")

    def _jumped(self, z: np.ndarray, R: np.ndarray) -> bool:
        """The still measurement ``z`` (3,) [m] with covariance ``R`` is inconsistent with the
        predicted position (squared Mahalanobis distance beyond :data:`JUMP_CHI2`)."""
        S = self._P[:3, :3] + np.asarray(R, float)
        e = z - self._x[:3]
        try:
            d2 = float(e @ np.linalg.solve(S, e))
        except np.linalg.LinAlgError:
            return False
        return d2 > JUMP_CHI2

    def _predict(self, stamp: float) -> None:
        dt = stamp - self._t
        self._t = stamp
        if dt <= 0.0:
            return
        F = np.eye(6)
        F[:3, 3:] = np.eye(3) * dt
        q = self.config.position_noise**2
        G = np.array([[dt**4 / 4, dt**3 / 2], [dt**3 / 2, dt**2]]) * q
        Q = np.kron(G, np.eye(3))
        self._x = F @ self._x
        self._P = F @ self._P @ F.T + Q

    def _publish(self, stamp: float, state: str) -> None:
        s = self._shape
        assert s is not None  # noqa: S101 - a target always has its first measurement
        offset = self._x[:3] - s.position
        self._target = TrackedObject(
            valid=True, state=state, stamp=stamp, position=self._x[:3].copy(),
            velocity=self._x[3:].copy(), covariance=0.5 * (self._P[:3, :3] + self._P[:3, :3].T),
            top=s.top + offset, radius=s.radius, height=s.height, last_measured=self._last,
            measurements=self._count,
        )
