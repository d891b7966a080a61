"""SetpointGenerator: the desired joint state (q_d, q_dot_d, q_ddot_d, effort) the impedance law
tracks, from trajectories, velocity commands (eq 7) or a hold.

Each joint follows its most recent source: a new trajectory takes over the joints it names
(preempting an older trajectory or a velocity command on those joints only; the other joints
keep what they were doing) and starts from the joints' current set-point, so the switch is
smooth. When a trajectory ends its joints hold its last point. A velocity command integrates
eq 7, ``q_d(t) = q_d(t - dt) + q_dot_d(t) dt``, and lapses to a hold after ``timeout``.
Set-points are clipped into the joint limits shrunk by ``margin``.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import numpy as np

from icub_pmp.control.joint_trajectory import JointTrajectory
from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.name_index import name_indices

__all__ = ["SetpointGenerator", "Setpoint"]


class Setpoint(NamedTuple):
    """Desired state over all joints (n,): position [rad], velocity [rad/s], acceleration
    [rad/s^2], effort feed-forward [N m]; ``moving``: a trajectory or velocity command is
    active on some joint."""

    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    effort: np.ndarray
    moving: bool


class SetpointGenerator:
    """Per-joint set-point sources for joints ``names`` with limits ``lower``/``upper`` (n,)."""

    def __init__(
        self, names: Sequence[str], lower: np.ndarray, upper: np.ndarray, margin: float = 0.0
    ):
        self.joint_names = tuple(names)
        self.n = len(self.joint_names)
        self._index = {n: i for i, n in enumerate(self.joint_names)}
        self.lower = np.asarray(lower, dtype=float) + margin
        self.upper = np.asarray(upper, dtype=float) - margin
        if np.any(self.lower > self.upper):
            raise InvalidInput("SetpointGenerator: margin larger than half a joint range")
        self.q = np.zeros(self.n)
        self.v = np.zeros(self.n)
        self.a = np.zeros(self.n)
        self.effort = np.zeros(self.n)
        self._trajs: list[tuple[JointTrajectory, np.ndarray]] = []  # (traj, joint indices)
        self._vel_cmd = np.zeros(self.n)
        self._vel_mask = np.zeros(self.n, dtype=bool)
        self._vel_deadline = -np.inf
        self._t: float | None = None
        self.initialised = False
        #: per joint, the token of the source that owns it (0 = a hold, a velocity command or
        #: an anonymous trajectory; > 0 = a trajectory goal, see TrajectoryGoal)
        self.owner = np.zeros(self.n, dtype=np.int64)

    def indices(self, names: Sequence[str]) -> np.ndarray:
        """Positions of ``names`` in the joint vector (raises UnknownName)."""
        return name_indices(names, self._index, self.joint_names)

    # ------------------------------------------------------------------ sources
    def hold(self, q: np.ndarray | None = None, t: float | None = None) -> None:
        """Stop every trajectory and velocity command; hold ``q`` (n,) [rad] (default: the
        current set-point) at rest."""
        if q is not None:
            q = np.asarray(q, dtype=float)
            if q.shape != (self.n,) or not np.all(np.isfinite(q)):
                raise InvalidInput(f"hold: expected {self.n} finite positions")
            self.q = np.clip(q, self.lower, self.upper)
            self.initialised = True
        self.v = np.zeros(self.n)
        self.a = np.zeros(self.n)
        self.effort = np.zeros(self.n)
        self._trajs.clear()
        self._vel_mask[:] = False
        self.owner[:] = 0
        if t is not None:
            self._t = float(t)

    def hold_joints(self, idx: np.ndarray, q: np.ndarray) -> None:
        """Stop every source on joints ``idx`` and hold them at ``q`` (len(idx),) [rad] at
        rest; the other joints keep what they are doing."""
        idx = np.asarray(idx, dtype=int)
        self._release(idx)
        self.q[idx] = np.clip(np.asarray(q, dtype=float), self.lower[idx], self.upper[idx])
        self.v[idx] = 0.0
        self.a[idx] = 0.0
        self.effort[idx] = 0.0
        self.owner[idx] = 0

    def _release(self, idx: np.ndarray) -> None:
        """Remove joints ``idx`` from older sources (trajectories, velocity command)."""
        kept = []
        for traj, tidx in self._trajs:
            keep = ~np.isin(tidx, idx)
            if keep.all():
                kept.append((traj, tidx))
            elif keep.any():
                kept.append((_TrajView(traj, np.flatnonzero(keep)), tidx[keep]))
        self._trajs = kept
        self._vel_mask[idx] = False

    def anchor(self, traj: JointTrajectory, t_now: float) -> JointTrajectory:
        """``traj`` as it would be followed from ``t_now`` [s]: joined from its joints'
        current set-point, starting at its own start or now, whichever is later."""
        if not self.initialised:
            raise InvalidInput("no joint state received yet: cannot start a trajectory")
        idx = self.indices(traj.joint_names)
        return traj.anchored(
            self.q[idx], self.v[idx], self.a[idx], start=max(traj.start, float(t_now))
        )

    def follow(self, anchored: JointTrajectory, owner: int = 0) -> np.ndarray:
        """Follow an :meth:`anchor` ed trajectory on its joints (token ``owner``); returns the
        joint indices."""
        idx = self.indices(anchored.joint_names)
        self._release(idx)
        self._trajs.append((anchored, idx))
        self.owner[idx] = owner
        return idx

    def set_trajectory(self, traj: JointTrajectory, t_now: float, owner: int = 0) -> None:
        """Follow ``traj`` (its ``start`` is absolute time; a start in the past means 'now')
        on its joints, joined from their current set-point."""
        self.follow(self.anchor(traj, t_now), owner)

    def set_velocity(self, names: Sequence[str], velocities: np.ndarray, t_now: float,
                     timeout: float) -> None:
        """Velocity command (eq 7) for joints ``names`` [rad/s], valid for ``timeout`` [s]."""
        if not self.initialised:
            raise InvalidInput("no joint state received yet: cannot follow a velocity command")
        idx = self.indices(names)
        vel = np.asarray(velocities, dtype=float)
        if vel.shape != (len(idx),) or not np.all(np.isfinite(vel)):
            raise InvalidInput(
                f"velocity command: expected {len(idx)} finite velocities, got {vel!r}"
            )
        self._release(idx)
        self.owner[idx] = 0
        self._vel_mask[idx] = True
        self._vel_cmd[idx] = vel
        self._vel_deadline = t_now + timeout

    # ------------------------------------------------------------------ sampling
    def update(self, t: float) -> Setpoint:
        """The set-point at time ``t`` [s] (advance the velocity integration to ``t``)."""
        dt = 0.0 if self._t is None else max(0.0, t - self._t)
        self._t = float(t)
        moving = False
        # velocity mode, eq 7
        if self._vel_mask.any():
            if t > self._vel_deadline:
                self.v[self._vel_mask] = 0.0
                self.a[self._vel_mask] = 0.0
                self._vel_mask[:] = False
            else:
                m = self._vel_mask
                self.q[m] += self._vel_cmd[m] * dt
                self.v[m] = self._vel_cmd[m]
                self.a[m] = 0.0
                self.effort[m] = 0.0
                moving = True
        # trajectories
        finished = []
        for k, (traj, idx) in enumerate(self._trajs):
            s = traj.sample(t)
            self.q[idx] = s.q
            self.v[idx] = s.v
            self.a[idx] = s.a
            self.effort[idx] = s.effort
            if t >= traj.end:
                finished.append(k)
            else:
                moving = True
        for k in reversed(finished):
            del self._trajs[k]
        # limits: clip and stop at a limit
        low, high = self.q < self.lower, self.q > self.upper
        if low.any() or high.any():
            hit = low | high
            self.q = np.clip(self.q, self.lower, self.upper)
            self.v[hit] = 0.0
            self.a[hit] = 0.0
        return Setpoint(self.q.copy(), self.v.copy(), self.a.copy(), self.effort.copy(), moving)

    @property
    def active_trajectories(self) -> int:
        """Number of trajectories still running."""
        return len(self._trajs)


class _TrajView:
    """A trajectory restricted to some of its joints (after partial preemption)."""

    def __init__(self, traj: JointTrajectory | "_TrajView", cols: np.ndarray):
        self._traj = traj
        self._cols = cols
        self.joint_names = tuple(traj.joint_names[c] for c in cols)

    @property
    def end(self) -> float:
        return self._traj.end

    def sample(self, t: float):
        s = self._traj.sample(t)
        c = self._cols
        return type(s)(s.q[c], s.v[c], s.a[c], s.effort[c])
