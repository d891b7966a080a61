"""Message <-> numpy conversions: pure functions, one place for the whole project.

Validation lives here too, so every node rejects a malformed message the same way: the
functions raise :class:`~icub_pmp.errors.InvalidInput` (or ``UnknownName``) with a one-line
message that the node logs (throttled) before dropping the message.
"""

from __future__ import annotations

import math
import struct
from typing import Iterable, Sequence

import numpy as np
from builtin_interfaces.msg import Duration, Time
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion, Vector3, Wrench
from nav_msgs.msg import Path
from sensor_msgs.msg import Image, JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from icub_pmp.errors import InvalidInput, UnknownName

__all__ = [
    "time_to_sec",
    "sec_to_time",
    "sec_to_duration",
    "duration_to_sec",
    "make_joint_state",
    "joint_state_field",
    "validate_joint_state",
    "joint_state_arrays",
    "set_wrench",
    "trajectory_extras",
    "raw_header_stamp_ns",
    "wrench_to_array",
    "array_to_wrench",
    "point_to_array",
    "pose_to_arrays",
    "arrays_to_pose",
    "quat_wxyz_to_matrix",
    "matrix_to_quat_wxyz",
    "trajectory_to_arrays",
    "arrays_to_trajectory",
    "positions_to_path",
    "image_to_array",
    "array_to_image",
    "IMAGE_ENCODINGS",
]


# ---------------------------------------------------------------------------- time
def time_to_sec(t: Time) -> float:
    """builtin_interfaces/Time -> seconds."""
    return t.sec + t.nanosec * 1e-9


def sec_to_time(s: float) -> Time:
    """Seconds -> builtin_interfaces/Time (rounded to the nanosecond)."""
    ns = int(round(s * 1e9))
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def sec_to_duration(s: float) -> Duration:
    """Seconds -> builtin_interfaces/Duration."""
    ns = int(round(s * 1e9))
    return Duration(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def duration_to_sec(d: Duration) -> float:
    """builtin_interfaces/Duration -> seconds."""
    return d.sec + d.nanosec * 1e-9


# ---------------------------------------------------------------------------- joint states
def make_joint_state(
    names: Sequence[str],
    position: Iterable[float] | None = None,
    velocity: Iterable[float] | None = None,
    effort: Iterable[float] | None = None,
    stamp: Time | None = None,
    frame_id: str = "",
) -> JointState:
    """Build a JointState; absent fields stay empty (as ROS allows)."""
    msg = JointState()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.name = list(names)
    if position is not None:
        msg.position = np.asarray(position, dtype=float).tolist()
    if velocity is not None:
        msg.velocity = np.asarray(velocity, dtype=float).tolist()
    if effort is not None:
        msg.effort = np.asarray(effort, dtype=float).tolist()
    return msg


def validate_joint_state(
    msg: JointState,
    required: Sequence[str] = ("position",),
    valid_names: Iterable[str] | None = None,
) -> None:
    """Check a JointState: unique names, each ``required`` field as long as ``name`` and
    finite, optional fields empty or as long as ``name``, names among ``valid_names``."""
    n = len(msg.name)
    if n == 0:
        raise InvalidInput("JointState has no joint names")
    if len(set(msg.name)) != n:
        raise InvalidInput("JointState has duplicate joint names")
    for field in ("position", "velocity", "effort"):
        values = getattr(msg, field)
        if field in required and len(values) != n:
            raise InvalidInput(f"JointState.{field} has {len(values)} values for {n} names")
        if len(values) not in (0, n):
            raise InvalidInput(f"JointState.{field} has {len(values)} values for {n} names")
        if len(values) and not np.all(np.isfinite(np.asarray(values, dtype=float))):
            raise InvalidInput(f"JointState.{field} contains NaN or infinite values")
    if valid_names is not None:
        valid = set(valid_names)
        for name in msg.name:
            if name not in valid:
                raise UnknownName("joint", name, valid)


def joint_state_field(msg: JointState, field: str = "position") -> dict[str, float]:
    """{joint: value} for one field of a JointState (empty if the field is empty)."""
    values = getattr(msg, field)
    if len(values) == 0:
        return {}
    return dict(zip(msg.name, (float(v) for v in values)))


def joint_state_arrays(
    msg: JointState, names: Sequence[str], index: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """(positions (n,) [rad], velocities (n,) [rad/s] or None when the message has none,
    index) of joints ``names``, in that order, from a JointState (joints the message has
    beyond ``names`` are ignored).

    ``index`` = the positions of ``names`` in ``msg.name`` returned by a previous call for
    the same name list (skips the name lookup: the 1 kHz path). Raises InvalidInput when a
    joint is missing, a field has the wrong length or a value is NaN/inf.
    """
    n = len(msg.name)
    if index is None:
        lookup = {name: i for i, name in enumerate(msg.name)}
        missing = [name for name in names if name not in lookup]
        if missing:
            raise InvalidInput(f"JointState lacks joints {missing}")
        index = np.array([lookup[name] for name in names], dtype=int)
    pos = np.asarray(msg.position, dtype=float)
    if pos.shape != (n,):
        raise InvalidInput(f"JointState.position has {pos.size} values for {n} names")
    q = pos[index]
    v = None
    if len(msg.velocity):
        vel = np.asarray(msg.velocity, dtype=float)
        if vel.shape != (n,):
            raise InvalidInput(f"JointState.velocity has {vel.size} values for {n} names")
        v = vel[index]
        if not math.isfinite(float(v.sum())):
            raise InvalidInput("JointState.velocity contains NaN or infinite values")
    if not math.isfinite(float(q.sum())):
        raise InvalidInput("JointState.position contains NaN or infinite values")
    return q, v, index


def raw_header_stamp_ns(data: bytes) -> int:
    """``header.stamp`` [ns] of a serialised (CDR) message whose first field is a
    std_msgs/Header (JointState, WrenchStamped, ...), read without deserialising it: a
    subscriber with ``raw=True`` can drop the samples it does not need for free."""
    if len(data) < 12:
        raise InvalidInput(f"serialised message too short ({len(data)} bytes) for a header")
    fmt = "<iI" if data[1] & 1 else ">iI"  # CDR encapsulation: odd id = little endian
    sec, nanosec = struct.unpack_from(fmt, data, 4)
    return sec * 1_000_000_000 + nanosec


# ---------------------------------------------------------------------------- geometry
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


def quat_wxyz_to_matrix(q: Sequence[float]) -> np.ndarray:
    """Unit quaternion (w, x, y, z) -> rotation matrix (3, 3)."""
    w, x, y, z = (float(v) for v in q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_to_quat_wxyz(R: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) -> unit quaternion (w, x, y, z) with w >= 0."""
    R = np.asarray(R, dtype=float)
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2]) * 2
        q = [(R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s]
    elif R[1, 1] > R[2, 2]:
        s = math.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2]) * 2
        q = [(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s]
    else:
        s = math.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1]) * 2
        q = [(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s]
    qa = np.array(q)
    qa /= np.linalg.norm(qa)
    return -qa if qa[0] < 0 else qa


# ---------------------------------------------------------------------------- trajectories
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


# ---------------------------------------------------------------------------- images
#: encodings image_to_array accepts -> channels (bgr8 is returned as RGB).
IMAGE_ENCODINGS = {"rgb8": 3, "bgr8": 3, "mono8": 1}


def image_to_array(
    msg: Image, width: int | None = None, height: int | None = None
) -> np.ndarray:
    """sensor_msgs/Image (rgb8, bgr8, mono8) -> (H, W, 3) RGB or (H, W) grey uint8 array.

    Checks the encoding, the optional expected size [px], ``step`` and the data length;
    raises :class:`InvalidInput` naming what is wrong. The array is a copy.
    """
    enc = msg.encoding.lower()
    if enc not in IMAGE_ENCODINGS:
        raise UnknownName("image encoding", msg.encoding, IMAGE_ENCODINGS)
    h, w, ch = int(msg.height), int(msg.width), IMAGE_ENCODINGS[enc]
    if (width is not None and w != width) or (height is not None and h != height):
        raise InvalidInput(f"image size {w}x{h} (W x H); expected {width}x{height}")
    if h <= 0 or w <= 0:
        raise InvalidInput(f"image size {w}x{h} is empty")
    step = int(msg.step)
    if step < w * ch:
        raise InvalidInput(f"image step {step} < width * channels = {w * ch}")
    data = np.frombuffer(bytes(msg.data), dtype=np.uint8)
    if data.size != step * h:
        raise InvalidInput(f"image data has {data.size} bytes; step * height = {step * h}")
    rows = data.reshape(h, step)[:, : w * ch]
    if ch == 1:
        return rows.copy()
    a = rows.reshape(h, w, 3)
    return (a[:, :, ::-1] if enc == "bgr8" else a).copy()


def array_to_image(
    a: np.ndarray, encoding: str = "mono8", stamp: Time | None = None, frame_id: str = ""
) -> Image:
    """(H, W) uint8 -> mono8 or (H, W, 3) uint8 RGB -> rgb8 sensor_msgs/Image (data as bytes)."""
    a = np.ascontiguousarray(a)
    ch = IMAGE_ENCODINGS.get(encoding)
    if ch is None or encoding == "bgr8":
        raise UnknownName("image encoding", encoding, ("mono8", "rgb8"))
    if a.dtype != np.uint8 or a.ndim != (2 if ch == 1 else 3) or (ch == 3 and a.shape[2] != 3):
        shape = "(H, W)" if ch == 1 else "(H, W, 3)"
        raise InvalidInput(f"{encoding} image: expected uint8 {shape}, got {a.dtype} {a.shape}")
    msg = Image()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.height, msg.width = int(a.shape[0]), int(a.shape[1])
    msg.encoding = encoding
    msg.is_bigendian = 0
    msg.step = int(a.shape[1] * ch)
    msg.data = a.tobytes()
    return msg
