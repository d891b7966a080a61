"""geometry_msgs (Wrench, Point, Pose) <-> numpy arrays [N, N m, m]."""

from __future__ import annotations

from typing import Sequence

import numpy as np
from geometry_msgs.msg import Point, Pose, Quaternion, Vector3, Wrench

from icub_pmp.errors import InvalidInput

__all__ = [
    "set_wrench",
    "wrench_to_array",
    "array_to_wrench",
    "point_to_array",
    "pose_to_arrays",
    "arrays_to_pose",
]


def set_wrench(w: Wrench, a: Sequence[float]) -> None:
    """Fill a Wrench in place from (6,) force then torque [N, N m] (no allocation)."""
    f, t = w.force, w.torque
    f.x, f.y, f.z = float(a[0]), float(a[1]), float(a[2])
    t.x, t.y, t.z = float(a[3]), float(a[4]), float(a[5])


def wrench_to_array(w: Wrench) -> np.ndarray:
    """Wrench -> (6,) [fx, fy, fz, tx, ty, tz] in N and N m."""
    return np.array([w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z])


def array_to_wrench(a: Sequence[float]) -> Wrench:
    """(6,) force then torque -> Wrench."""
    a = [float(x) for x in a]
    if len(a) != 6:
        raise InvalidInput(f"wrench: expected 6 values, got {len(a)}")
    return Wrench(force=Vector3(x=a[0], y=a[1], z=a[2]), torque=Vector3(x=a[3], y=a[4], z=a[5]))


def point_to_array(p: Point | Vector3) -> np.ndarray:
    """Point/Vector3 -> (3,) with a finiteness check."""
    a = np.array([p.x, p.y, p.z], dtype=float)
    if not np.all(np.isfinite(a)):
        raise InvalidInput(f"point ({p.x}, {p.y}, {p.z}) contains NaN or infinite values")
    return a


def pose_to_arrays(pose: Pose) -> tuple[np.ndarray, np.ndarray]:
    """Pose -> (position (3,) [m], quaternion (4,) w, x, y, z normalised).

    Raises on NaN and on a zero quaternion.
    """
    pos = point_to_array(pose.position)
    o = pose.orientation
    q = np.array([o.w, o.x, o.y, o.z], dtype=float)
    if not np.all(np.isfinite(q)):
        raise InvalidInput("pose orientation contains NaN or infinite values")
    norm = float(np.linalg.norm(q))
    if norm < 1e-9:
        raise InvalidInput("pose orientation is a zero quaternion")
    return pos, q / norm


def arrays_to_pose(position: Sequence[float], quat_wxyz: Sequence[float] = (1, 0, 0, 0)) -> Pose:
    """(position, quaternion w, x, y, z) -> Pose."""
    p = [float(x) for x in position]
    q = [float(x) for x in quat_wxyz]
    return Pose(
        position=Point(x=p[0], y=p[1], z=p[2]),
        orientation=Quaternion(w=q[0], x=q[1], y=q[2], z=q[3]),
    )
