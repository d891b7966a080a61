"""JointTrajectory: a validated joint trajectory over a subset of joints, interpolated with
quintic Hermite polynomials (continuous position, velocity and acceleration).

Given through points ``(t_k, q_k[, v_k, a_k, effort_k])``, each segment is the quintic that
matches position, velocity and acceleration at both ends. Missing velocities are filled with
a shape-preserving estimate (harmonic mean of the adjacent chord slopes, 0 at a local
extremum and at the last point); missing accelerations are central differences of the given
velocities (0 at the ends), or 0 at the knots when velocities are missing too. A single point
reached from rest is therefore the minimum-jerk profile. Efforts (used as torque feed-forward
in the pure torque mode) are interpolated linearly. After the last point the trajectory holds it.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName

__all__ = ["JointTrajectory", "TrajectorySample"]


class TrajectorySample(NamedTuple):
    """Desired state (n,) each: position [rad], velocity [rad/s], acceleration [rad/s^2],
    effort [N m] (zeros when the trajectory has none)."""

    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    effort: np.ndarray


class JointTrajectory:
    """Trajectory of joints ``names`` starting at absolute time ``start`` [s].

    ``times`` (N,) [s] from ``start``, strictly increasing, >= 0; ``positions`` (N, n) [rad];
    optional ``velocities``, ``accelerations``, ``efforts`` (N, n). ``valid_names`` lists the
    joints that exist; ``lower`` / ``upper`` {name: limit} [rad] reject points outside the
    limits (by more than ``limit_tolerance``). Raises :class:`InvalidInput` /
    :class:`UnknownName` with a one-line reason.
    """

    def __init__(
        self,
        names: Sequence[str],
        times: Sequence[float],
        positions: np.ndarray,
        velocities: np.ndarray | None = None,
        accelerations: np.ndarray | None = None,
        efforts: np.ndarray | None = None,
        *,
        start: float = 0.0,
        valid_names: Sequence[str] | None = None,
        lower: dict[str, float] | None = None,
        upper: dict[str, float] | None = None,
        limit_tolerance: float = 1e-3,
    ):
        names = [str(n) for n in names]
        n = len(names)
        if n == 0:
            raise InvalidInput("trajectory has no joint names")
        if len(set(names)) != n:
            dup = sorted({x for x in names if names.count(x) > 1})
            raise InvalidInput(f"trajectory names joints more than once: {dup}")
        if valid_names is not None:
            valid = set(valid_names)
            for name in names:
                if name not in valid:
                    raise UnknownName("joint", name, valid)
        times = np.asarray(times, dtype=float).reshape(-1)
        npts = len(times)
        if npts == 0:
            raise InvalidInput("trajectory has no points")
        if not np.all(np.isfinite(times)):
            raise InvalidInput("trajectory times contain NaN or infinite values")
        if times[0] < 0:
            raise InvalidInput(f"trajectory time_from_start is negative ({times[0]} s)")
        if np.any(np.diff(times) <= 0):
            k = int(np.argmax(np.diff(times) <= 0)) + 1
            raise InvalidInput(
                f"trajectory times are not strictly increasing: point {k} at {times[k]} s "
                f"after point {k - 1} at {times[k - 1]} s"
            )
        if not np.isfinite(start):
            raise InvalidInput(f"trajectory start time is not finite ({start})")
        arrays = {}
        for label, arr in (("positions", positions), ("velocities", velocities),
                           ("accelerations", accelerations), ("efforts", efforts)):
            if arr is None:
                arrays[label] = None
                continue
            a = np.asarray(arr, dtype=float)
            if a.shape != (npts, n):
                raise InvalidInput(
                    f"trajectory {label}: expected shape ({npts}, {n}) for {npts} points and "
                    f"{n} joints, got {a.shape}"
                )
            if not np.all(np.isfinite(a)):
                k, j = np.argwhere(~np.isfinite(a))[0]
                raise InvalidInput(
                    f"trajectory {label} contain NaN or infinite values (point {k}, "
                    f"joint {names[j]!r})"
                )
            arrays[label] = a.copy()
        pos = arrays["positions"]
        if pos is None:
            raise InvalidInput("trajectory has no positions")
        for j, name in enumerate(names):
            lo = None if lower is None else lower.get(name)
            hi = None if upper is None else upper.get(name)
            if lo is not None and np.min(pos[:, j]) < lo - limit_tolerance:
                raise InvalidInput(
                    f"trajectory joint {name!r} goes to {np.min(pos[:, j]):.4f} rad, below "
                    f"its lower limit {lo:.4f} rad"
                )
            if hi is not None and np.max(pos[:, j]) > hi + limit_tolerance:
                raise InvalidInput(
                    f"trajectory joint {name!r} goes to {np.max(pos[:, j]):.4f} rad, above "
                    f"its upper limit {hi:.4f} rad"
                )
        self.joint_names: tuple[str, ...] = tuple(names)
        self.start = float(start)
        self.times = times
        self.positions = pos
        self.velocities = arrays["velocities"]
        self.accelerations = arrays["accelerations"]
        self.efforts = arrays["efforts"]
        for a in (self.times, self.positions, self.velocities, self.accelerations, self.efforts):
            if a is not None:
                a.setflags(write=False)
        self._coeffs: np.ndarray | None = None
        self._knots: np.ndarray | None = None

    @property
    def end(self) -> float:
        """Absolute time of the last point [s]."""
        return self.start + float(self.times[-1])

    # ------------------------------------------------------------------ anchoring
    def anchored(
        self, q0: np.ndarray, v0: np.ndarray, a0: np.ndarray, start: float | None = None
    ) -> "JointTrajectory":
        """This trajectory preceded by the state (q0, v0, a0) (n,) at its start time, starting
        at ``start`` [s] (default: its own start).

        Used by the controller to join a new trajectory smoothly from the current set-point.
        A trajectory whose first point is at time 0 is not joined (it starts there).
        """
        start = self.start if start is None else float(start)
        if self.times[0] == 0.0:
            return JointTrajectory(
                self.joint_names, self.times, self.positions, self.velocities,
                self.accelerations, self.efforts, start=start, limit_tolerance=np.inf,
            )
        times = np.concatenate([[0.0], self.times])
        pos = np.vstack([q0, self.positions])
        if self.velocities is not None:
            vel = np.vstack([v0, self.velocities])
        else:
            vel = _shape_preserving_velocities(times, pos)
            vel[0] = v0
        if self.accelerations is not None:
            acc = np.vstack([a0, self.accelerations])
        else:
            acc = _accelerations_from_velocities(times, vel) if self.velocities is not None \
                else np.zeros_like(pos)
            acc[0] = a0
        eff = None if self.efforts is None else np.vstack([self.efforts[0], self.efforts])
        return JointTrajectory(
            self.joint_names, times, pos, vel, acc, eff, start=start, limit_tolerance=np.inf
        )

    # ------------------------------------------------------------------ sampling
    def _build(self) -> None:
        p, t = self.positions, self.times
        vel = (self.velocities if self.velocities is not None
               else _shape_preserving_velocities(t, p))
        if self.accelerations is not None:
            acc = self.accelerations
        elif self.velocities is not None:
            acc = _accelerations_from_velocities(t, vel)
        else:
            acc = np.zeros_like(p)
        self._vel, self._acc = vel, acc
        dt = np.diff(t)[:, None]
        p0, p1, v0, v1, a0, a1 = p[:-1], p[1:], vel[:-1], vel[1:], acc[:-1], acc[1:]
        d = p1 - p0
        c = np.empty((len(dt), 6, p.shape[1]))
        c[:, 0] = p0
        c[:, 1] = v0
        c[:, 2] = a0 / 2
        c[:, 3] = (20 * d - (8 * v1 + 12 * v0) * dt - (3 * a0 - a1) * dt**2) / (2 * dt**3)
        c[:, 4] = (-30 * d + (14 * v1 + 16 * v0) * dt + (3 * a0 - 2 * a1) * dt**2) / (2 * dt**4)
        c[:, 5] = (12 * d - 6 * (v1 + v0) * dt + (a1 - a0) * dt**2) / (2 * dt**5)
        self._coeffs = c

    def peak_rates(self, samples_per_segment: int = 16) -> tuple[np.ndarray, np.ndarray]:
        """Largest |velocity| [rad/s] and |acceleration| [rad/s^2] of each joint (n,) over the
        interpolated trajectory, sampled ``samples_per_segment`` times per segment (both ends
        included)."""
        n = len(self.joint_names)
        if len(self.times) < 2:
            return np.zeros(n), np.zeros(n)
        if self._coeffs is None:
            self._build()
        c = self._coeffs
        dt = np.diff(self.times)
        s = np.linspace(0.0, 1.0, samples_per_segment)[None, :] * dt[:, None]  # (nseg, m)
        s = s[:, :, None]
        c1, c2, c3, c4, c5 = (c[:, k][:, None, :] for k in range(1, 6))
        v = c1 + s * (2 * c2 + s * (3 * c3 + s * (4 * c4 + s * 5 * c5)))
        a = 2 * c2 + s * (6 * c3 + s * (12 * c4 + s * 20 * c5))
        return np.abs(v).max(axis=(0, 1)), np.abs(a).max(axis=(0, 1))

    def sample(self, t: float) -> TrajectorySample:
        """Desired state at absolute time ``t`` [s]: the first point (at rest) before the first
        time, the last point (at rest) after the last one."""
        if self._coeffs is None:
            self._build()
        n = len(self.joint_names)
        tau = t - self.start
        times = self.times
        if tau < times[0] or len(times) == 1 or tau >= times[-1]:
            k = 0 if tau < times[-1] else len(times) - 1
            eff = np.zeros(n) if self.efforts is None else self.efforts[k].copy()
            return TrajectorySample(self.positions[k].copy(), np.zeros(n), np.zeros(n), eff)
        k = int(np.searchsorted(times, tau, side="right")) - 1
        s = tau - times[k]
        c = self._coeffs[k]
        q = c[0] + s * (c[1] + s * (c[2] + s * (c[3] + s * (c[4] + s * c[5]))))
        v = c[1] + s * (2 * c[2] + s * (3 * c[3] + s * (4 * c[4] + s * 5 * c[5])))
        a = 2 * c[2] + s * (6 * c[3] + s * (12 * c[4] + s * 20 * c[5]))
        if self.efforts is None:
            eff = np.zeros(n)
        else:
            w = s / (times[k + 1] - times[k])
            eff = (1 - w) * self.efforts[k] + w * self.efforts[k + 1]
        return TrajectorySample(q, v, a, eff)


def _shape_preserving_velocities(times: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """Velocities at the points: harmonic mean of the adjacent chord slopes (0 at an
    extremum), 0 at the first and last point. The harmonic mean is at most twice the smaller
    slope, which keeps a quintic with zero knot accelerations monotone on monotone data."""
    vel = np.zeros_like(pos)
    if len(times) < 3:
        return vel
    slopes = np.diff(pos, axis=0) / np.diff(times)[:, None]
    left, right = slopes[:-1], slopes[1:]
    same = left * right > 0
    safe = np.where(same, left + right, 1.0)
    vel[1:-1] = np.where(same, 2.0 * left * right / safe, 0.0)
    return vel


def _accelerations_from_velocities(times: np.ndarray, vel: np.ndarray) -> np.ndarray:
    """Accelerations at the points from given velocities: central differences inside, 0 at
    the first and last point (a dense sampled trajectory keeps its acceleration profile
    instead of being forced through zero at every knot)."""
    acc = np.zeros_like(vel)
    if len(times) >= 3:
        acc[1:-1] = (vel[2:] - vel[:-2]) / (times[2:] - times[:-2])[:, None]
    return acc
