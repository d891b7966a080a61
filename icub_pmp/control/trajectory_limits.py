"""JointRateLimits: the joints' velocity and acceleration limits, and what a trajectory asks.

A trajectory that asks a joint for more than its limits is either refused (the impedance
controller: :meth:`JointRateLimits.check` raises) or slowed down to them (the planners:
:meth:`RateReport.time_scale` is the factor by which its time axis must be stretched: velocities
scale with 1/s and accelerations with 1/s^2, so ``s = max(1, v_peak / v_max,
sqrt(a_peak / a_max))`` over all joints brings every joint within both limits).

The limits come from ``config/robot.yaml`` (``velocity_limits``, ``acceleration_limits``; their
sources are cited there) through :class:`~icub_pmp.kinematics.robot_spec.RobotSpec`.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np

from icub_pmp.control.joint_trajectory import JointTrajectory
from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_spec import RobotSpec

__all__ = ["JointRateLimits", "RateReport", "scale_trajectory_time"]


class RateReport(NamedTuple):
    """What a trajectory asks of its joints: per joint (n,) peaks and their ratio to the
    limits; ``worst_joint`` / ``worst_kind`` ('velocity' or 'acceleration') name the joint that
    sets ``time_scale``."""

    joint_names: tuple[str, ...]
    peak_velocity: np.ndarray
    peak_acceleration: np.ndarray
    velocity_limit: np.ndarray
    acceleration_limit: np.ndarray

    @property
    def velocity_ratio(self) -> np.ndarray:
        """peak |v| / limit per joint (n,)."""
        return self.peak_velocity / self.velocity_limit

    @property
    def acceleration_ratio(self) -> np.ndarray:
        """peak |a| / limit per joint (n,)."""
        return self.peak_acceleration / self.acceleration_limit

    @property
    def time_scale(self) -> float:
        """Factor >= 1 that stretches the time axis so every joint is within both limits."""
        if not len(self.joint_names):
            return 1.0
        return max(1.0, float(self.velocity_ratio.max()),
                   math.sqrt(float(self.acceleration_ratio.max())))

    @property
    def worst(self) -> tuple[str, str]:
        """(joint, 'velocity' | 'acceleration') that sets :attr:`time_scale`."""
        kv = int(np.argmax(self.velocity_ratio))
        ka = int(np.argmax(self.acceleration_ratio))
        if self.velocity_ratio[kv] >= math.sqrt(self.acceleration_ratio[ka]):
            return self.joint_names[kv], "velocity"
        return self.joint_names[ka], "acceleration"

    def within(self, tolerance: float = 0.0) -> bool:
        """Whether every joint is within both limits (times 1 + ``tolerance``)."""
        return self.time_scale <= 1.0 + tolerance

    def describe(self) -> str:
        """One line naming the worst joint, what it asks and its limit (SI and degrees)."""
        joint, kind = self.worst
        k = self.joint_names.index(joint)
        if kind == "velocity":
            peak, lim, unit = self.peak_velocity[k], self.velocity_limit[k], "/s"
        else:
            peak, lim, unit = self.peak_acceleration[k], self.acceleration_limit[k], "/s^2"
        return (f"joint {joint!r} would reach {peak:.3g} rad{unit} ({math.degrees(peak):.0f} "
                f"deg{unit}), above its {kind} limit {lim:.3g} rad{unit} "
                f"({math.degrees(lim):.0f} deg{unit})")


class JointRateLimits:
    """Velocity [rad/s] and acceleration [rad/s^2] limits of named joints."""

    def __init__(self, joint_names: Sequence[str], velocity: Sequence[float],
                 acceleration: Sequence[float]):
        self.joint_names = tuple(joint_names)
        n = len(self.joint_names)
        self.velocity = np.array(velocity, dtype=float).reshape(-1)
        self.acceleration = np.array(acceleration, dtype=float).reshape(-1)
        for label, arr in (("velocity", self.velocity), ("acceleration", self.acceleration)):
            if arr.shape != (n,) or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
                raise InvalidInput(f"{label} limits: expected {n} finite values > 0, got {arr}")
            arr.setflags(write=False)
        self._index = {j: k for k, j in enumerate(self.joint_names)}

    @classmethod
    def from_spec(cls, spec: RobotSpec | None = None,
                  joint_names: Sequence[str] | None = None) -> "JointRateLimits":
        """The limits of ``config/robot.yaml`` for ``joint_names`` (default: every actuated
        joint)."""
        spec = spec or RobotSpec.load()
        names = tuple(joint_names) if joint_names is not None else spec.actuated_joints
        return cls(names, [spec.velocity_limit(j) for j in names],
                   [spec.acceleration_limit(j) for j in names])

    def report(self, traj: JointTrajectory) -> RateReport:
        """Peaks of ``traj`` against the limits of its joints (joints unknown here raise)."""
        idx = [self._index[j] if j in self._index else self._unknown(j)
               for j in traj.joint_names]
        v, a = traj.peak_rates()
        return RateReport(tuple(traj.joint_names), v, a, self.velocity[idx],
                          self.acceleration[idx])

    def check(self, traj: JointTrajectory, tolerance: float = 0.05) -> RateReport:
        """:meth:`report`, raising :class:`InvalidInput` when a joint exceeds a limit by more
        than ``tolerance`` (relative)."""
        rep = self.report(traj)
        if not rep.within(tolerance):
            raise InvalidInput(
                f"trajectory too fast: {rep.describe()} (limits: config/robot.yaml; a "
                f"{rep.time_scale:.2f}x longer trajectory would be within them)")
        return rep

    def _unknown(self, joint: str) -> int:
        raise UnknownName("joint", joint, self.joint_names)


def scale_trajectory_time(
    times: np.ndarray, velocities: np.ndarray | None, accelerations: np.ndarray | None,
    factor: float,
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Stretch a trajectory's time axis by ``factor`` >= 1: the same path, times * s,
    velocities / s, accelerations / s^2."""
    if not math.isfinite(factor) or factor < 1.0:
        raise InvalidInput(f"time scale: expected a finite factor >= 1, got {factor}")
    t = np.asarray(times, dtype=float) * factor
    v = None if velocities is None else np.asarray(velocities, dtype=float) / factor
    a = None if accelerations is None else np.asarray(accelerations, dtype=float) / factor**2
    return t, v, a
