"""TrajectoryGoal: an accepted trajectory-execution goal on the controller, from start to an
outcome (the core of the FollowJointTrajectory action of ``impedance_controller``).

The goal owns its joints in the :class:`SetpointGenerator` from the moment it is accepted
(each joint follows its most recent source). Every control step, :meth:`update` compares the
measured joints with the set-points and decides, in this order:

* ``SAFE_HOLD``: the controller latched a safe hold (joint states or estimates lost);
* ``PREEMPTED``: another trajectory, a velocity command or a hold took one of its joints;
* ``PATH_TOLERANCE_VIOLATED``: before the end, |q - q_d| > path tolerance on a joint;
* ``SUCCESSFUL``: at or after the end, every joint within its goal tolerance;
* ``GOAL_TOLERANCE_VIOLATED``: ``goal_time_tolerance`` after the end, still outside it.

The codes are those of ``control_msgs/action/FollowJointTrajectory`` (and of
``icub_interfaces/action/FollowJointTrajectory``, which adds the last three).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["TrajectoryGoal", "GoalOutcome", "GoalFeedback", "GoalCode"]


class GoalCode:
    """Result codes (control_msgs FollowJointTrajectory + the reasons an accepted goal stops)."""

    SUCCESSFUL = 0
    INVALID_GOAL = -1
    INVALID_JOINTS = -2
    OLD_HEADER_TIMESTAMP = -3
    PATH_TOLERANCE_VIOLATED = -4
    GOAL_TOLERANCE_VIOLATED = -5
    PREEMPTED = -10
    SAFE_HOLD = -11
    CANCELED = -12


class GoalOutcome(NamedTuple):
    """How a goal ended: ``code`` (:class:`GoalCode`), a one-line ``message`` (empty on
    success), the measured error q - q_d of its joints at that moment (k,) [rad] and the time
    since its start [s]."""

    code: int
    message: str
    final_error: np.ndarray
    execution_time: float

    @property
    def succeeded(self) -> bool:
        return self.code == GoalCode.SUCCESSFUL


class GoalFeedback(NamedTuple):
    """Desired and measured positions of the goal's joints (k,) [rad], time since the start
    and until the last point [s]."""

    desired: np.ndarray
    actual: np.ndarray
    time_from_start: float
    time_to_go: float

    @property
    def error(self) -> np.ndarray:
        return self.actual - self.desired


class TrajectoryGoal:
    """A goal over controller joints ``idx`` (k,), running from ``start`` to ``end`` [s].

    ``path_tolerance`` / ``goal_tolerance``: (k,) [rad] (0 = no check on that joint);
    ``goal_time_tolerance`` [s]. ``owner``: the token this goal holds in the set-point
    generator (:meth:`SetpointGenerator.owner_of`).
    """

    def __init__(self, goal_id: int, joint_names: tuple[str, ...], idx: np.ndarray,
                 start: float, end: float, path_tolerance: np.ndarray,
                 goal_tolerance: np.ndarray, goal_time_tolerance: float):
        self.goal_id = int(goal_id)
        self.joint_names = tuple(joint_names)
        self.idx = np.asarray(idx, dtype=int)
        self.start = float(start)
        self.end = float(end)
        self.path_tolerance = np.asarray(path_tolerance, dtype=float)
        self.goal_tolerance = np.asarray(goal_tolerance, dtype=float)
        self.goal_time_tolerance = float(goal_time_tolerance)
        self.outcome: GoalOutcome | None = None
        self.feedback: GoalFeedback | None = None

    @property
    def done(self) -> bool:
        return self.outcome is not None

    def finish(self, code: int, message: str, q: np.ndarray, q_d: np.ndarray,
               t: float) -> GoalOutcome:
        """End the goal now with ``code`` (no-op if it already ended)."""
        if self.outcome is None:
            err = (np.asarray(q)[self.idx] - np.asarray(q_d)[self.idx]).copy()
            self.outcome = GoalOutcome(code, message, err, max(0.0, t - self.start))
        return self.outcome

    def update(self, t: float, q: np.ndarray, q_d: np.ndarray, owned: bool,
               safe_hold: str | None) -> GoalOutcome | None:
        """One control step at time ``t`` [s] with measured ``q`` and set-point ``q_d`` over
        all controller joints (n,); ``owned``: the goal still owns all its joints;
        ``safe_hold``: the reason of a latched safe hold, else None. Returns the outcome when
        the goal ends on this step."""
        if self.outcome is not None:
            return None
        qi, qdi = q[self.idx], q_d[self.idx]
        self.feedback = GoalFeedback(qdi.copy(), qi.copy(), max(0.0, t - self.start),
                                     max(0.0, self.end - t))
        if safe_hold is not None:
            return self.finish(GoalCode.SAFE_HOLD, f"safe hold: {safe_hold}", q, q_d, t)
        if not owned:
            return self.finish(GoalCode.PREEMPTED,
                               "preempted: a newer trajectory, velocity command or hold took "
                               "over some of its joints", q, q_d, t)
        err = np.abs(qi - qdi)
        if t < self.end:
            bad = (self.path_tolerance > 0) & (err > self.path_tolerance)
            if bad.any():
                k = int(np.argmax(np.where(bad, err - self.path_tolerance, -np.inf)))
                return self.finish(
                    GoalCode.PATH_TOLERANCE_VIOLATED,
                    f"path tolerance violated: joint {self.joint_names[k]!r} is "
                    f"{math.degrees(err[k]):.1f} deg from its set-point (tolerance "
                    f"{math.degrees(self.path_tolerance[k]):.1f} deg)", q, q_d, t)
            return None
        out = (self.goal_tolerance > 0) & (err > self.goal_tolerance)
        if not out.any():
            return self.finish(GoalCode.SUCCESSFUL, "", q, q_d, t)
        if t > self.end + self.goal_time_tolerance:
            k = int(np.argmax(np.where(out, err - self.goal_tolerance, -np.inf)))
            return self.finish(
                GoalCode.GOAL_TOLERANCE_VIOLATED,
                f"goal tolerance violated: joint {self.joint_names[k]!r} is "
                f"{math.degrees(err[k]):.1f} deg from its goal {self.goal_time_tolerance} s "
                f"after the end (tolerance {math.degrees(self.goal_tolerance[k]):.1f} deg)",
                q, q_d, t)
        return None
