"""trajectory_msgs/JointTrajectory and nav_msgs/Path <-> numpy arrays."""

from __future__ import annotations

from typing import Iterable, Sequence

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.ros.conversions.geometry import arrays_to_pose
from icub_pmp.ros.conversions.stamps import (
    duration_to_sec,
    sec_to_duration,
    sec_to_time,
    time_to_sec,
)

__all__ = ["trajectory_to_arrays", "trajectory_extras", "arrays_to_trajectory", "positions_to_path"]


def trajectory_to_arrays(
    msg: JointTrajectory, valid_names: Iterable[str] | None = None
) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray | None]:
    """JointTrajectory -> (names, times (N,) [s], positions (N, n) [rad], velocities or None).

    Rejects: no points or names, duplicate or unknown names, a point whose positions (or
    non-empty velocities) do not match the names, NaN/inf, times not strictly increasing.
    """
    names = list(msg.joint_names)
    n = len(names)
    if n == 0:
        raise InvalidInput("JointTrajectory has no joint names")
    if len(set(names)) != n:
        raise InvalidInput("JointTrajectory has duplicate joint names")
    if valid_names is not None:
        valid = set(valid_names)
        for name in names:
            if name not in valid:
                raise UnknownName("joint", name, valid)
    if len(msg.points) == 0:
        raise InvalidInput("JointTrajectory has no points")
    times = np.empty(len(msg.points))
    pos = np.empty((len(msg.points), n))
    have_vel = all(len(p.velocities) == n for p in msg.points)
    vel = np.empty((len(msg.points), n)) if have_vel else None
    for k, p in enumerate(msg.points):
        if len(p.positions) != n:
            raise InvalidInput(f"point {k} has {len(p.positions)} positions for {n} joints")
        if len(p.velocities) not in (0, n):
            raise InvalidInput(f"point {k} has {len(p.velocities)} velocities for {n} joints")
        times[k] = duration_to_sec(p.time_from_start)
        pos[k] = p.positions
        if vel is not None:
            vel[k] = p.velocities
    if not np.all(np.isfinite(pos)) or (vel is not None and not np.all(np.isfinite(vel))):
        raise InvalidInput("JointTrajectory contains NaN or infinite values")
    if np.any(np.diff(times) <= 0):
        raise InvalidInput("JointTrajectory time_from_start is not strictly increasing")
    if times[0] < 0:
        raise InvalidInput("JointTrajectory time_from_start is negative")
    return names, times, pos, vel


def trajectory_extras(msg: JointTrajectory) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(accelerations (N, n) [rad/s^2] or None, efforts (N, n) [N m] or None) of a
    JointTrajectory: a field is returned only when every point has it for every joint; a
    point with a partial field raises InvalidInput. Complements :func:`trajectory_to_arrays`.
    """
    n = len(msg.joint_names)
    out = []
    for field in ("accelerations", "effort"):
        lengths = {len(getattr(p, field)) for p in msg.points}
        if lengths - {0, n}:
            raise InvalidInput(f"JointTrajectory point {field} must be empty or have {n} values")
        if lengths == {n}:
            a = np.array([list(getattr(p, field)) for p in msg.points], dtype=float)
            if not np.all(np.isfinite(a)):
                raise InvalidInput(f"JointTrajectory {field} contain NaN or infinite values")
            out.append(a)
        else:
            out.append(None)
    return out[0], out[1]


def arrays_to_trajectory(
    names: Sequence[str],
    times: Sequence[float],
    positions: np.ndarray,
    velocities: np.ndarray | None = None,
    stamp: Time | None = None,
    frame_id: str = "",
) -> JointTrajectory:
    """(names, times (N,), positions (N, n), velocities (N, n) or None) -> JointTrajectory."""
    positions = np.asarray(positions, dtype=float)
    msg = JointTrajectory()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.joint_names = list(names)
    for k, t in enumerate(times):
        pt = JointTrajectoryPoint()
        pt.positions = positions[k].tolist()
        if velocities is not None:
            pt.velocities = np.asarray(velocities[k], dtype=float).tolist()
        pt.time_from_start = sec_to_duration(float(t))
        msg.points.append(pt)
    return msg


def positions_to_path(
    positions: np.ndarray,
    frame_id: str,
    stamp: Time | None = None,
    times: Sequence[float] | None = None,
) -> Path:
    """(N, 3) positions [m] -> nav_msgs/Path in ``frame_id`` (identity orientations); each
    pose is stamped ``stamp + times[k]`` when ``times`` [s] are given, else ``stamp``."""
    positions = np.asarray(positions, dtype=float)
    msg = Path()
    msg.header.frame_id = frame_id
    base = time_to_sec(stamp) if stamp is not None else 0.0
    if stamp is not None:
        msg.header.stamp = stamp
    for k, p in enumerate(positions):
        ps = PoseStamped()
        ps.header.frame_id = frame_id
        if times is not None:
            ps.header.stamp = sec_to_time(base + float(times[k]))
        elif stamp is not None:
            ps.header.stamp = stamp
        ps.pose = arrays_to_pose(p)
        msg.poses.append(ps)
    return msg
