"""Time series from a recorded bag (icub_pmp.bags reader + rosbags CDR decoding): joint
states, wrenches, trajectories.

No ROS import: messages are decoded by rosbags from the definitions stored in the bag.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from icub_pmp.errors import BagError

WRENCH = "geometry_msgs/msg/WrenchStamped"
TRAJECTORY = "trajectory_msgs/msg/JointTrajectory"

__all__ = ["JointSeries", "WrenchSeries", "BagSeries", "read_bag_series"]


@dataclass
class JointSeries:
    """Joint states: t (N,) [s], names, position/velocity/effort (N, n)."""

    t: np.ndarray
    names: list[str]
    position: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray


@dataclass
class WrenchSeries:
    """WrenchStamped stream: t (N,) [s], wrench (N, 6) force then torque, frame id."""

    t: np.ndarray
    wrench: np.ndarray
    frame_id: str


@dataclass
class BagSeries:
    """What the report needs from a demo bag."""

    joints: JointSeries | None = None
    wrenches: dict[str, WrenchSeries] = field(default_factory=dict)
    # each trajectory: (receive time [s], names, times (K,), positions (K, n))
    trajectories: list[tuple[float, list[str], np.ndarray, np.ndarray]] = field(
        default_factory=list
    )
    counts: dict[str, int] = field(default_factory=dict)


def _stamp(header) -> float:
    return header.stamp.sec + header.stamp.nanosec * 1e-9


def read_bag_series(path: str | Path, joint_stride: int = 10) -> BagSeries:
    """Read joint states (every ``joint_stride``-th), all WrenchStamped topics and trajectories.

    Times are message header stamps (sim time). Raises :class:`BagError` on an unreadable bag.
    """
    from rosbags.typesys import Stores, get_typestore

    from icub_pmp.bags import BagReader

    store = get_typestore(Stores.ROS2_JAZZY)  # the standard types this report decodes
    out = BagSeries()
    js_t, js_p, js_v, js_e = [], [], [], []
    names: list[str] | None = None
    w: dict[str, tuple[list[float], list[np.ndarray], str]] = {}
    try:
        reader = BagReader(path)
        info = reader.info()
        out.counts = {t.name: t.count for t in info.topics}
        wanted = [t.name for t in info.topics
                  if t.name == "/joint_states" or t.msgtype in (WRENCH, TRAJECTORY)]
        k = 0
        for bm in reader.messages(wanted):
            if bm.topic == "/joint_states":
                k += 1
                if k % joint_stride:
                    continue
            msg = store.deserialize_cdr(bm.data, bm.msgtype)
            if bm.topic == "/joint_states":
                if names is None:
                    names = list(msg.name)
                if list(msg.name) != names or len(msg.position) != len(names):
                    continue
                n = len(names)
                js_t.append(_stamp(msg.header))
                js_p.append(np.asarray(msg.position, dtype=float))
                js_v.append(np.asarray(msg.velocity, dtype=float) if len(msg.velocity) == n
                            else np.zeros(n))
                js_e.append(np.asarray(msg.effort, dtype=float) if len(msg.effort) == n
                            else np.zeros(n))
            elif bm.msgtype == WRENCH:
                f, tq = msg.wrench.force, msg.wrench.torque
                entry = w.setdefault(bm.topic, ([], [], msg.header.frame_id))
                entry[0].append(_stamp(msg.header))
                entry[1].append(np.array([f.x, f.y, f.z, tq.x, tq.y, tq.z]))
            elif msg.points:
                pts = msg.points
                times = np.array([p.time_from_start.sec + p.time_from_start.nanosec * 1e-9
                                  for p in pts])
                pos = np.array([np.asarray(p.positions, dtype=float) for p in pts])
                stamp = _stamp(msg.header)
                out.trajectories.append((stamp if stamp > 0 else bm.log_time * 1e-9,
                                         list(msg.joint_names), times, pos))
    except Exception as exc:  # BagError and the decoder's own error types
        raise BagError(f"cannot read bag {path}: {exc}") from exc
    if names is not None and js_t:
        out.joints = JointSeries(
            np.array(js_t), names, np.array(js_p), np.array(js_v), np.array(js_e)
        )
    for topic, (t, ws, frame) in w.items():
        out.wrenches[topic] = WrenchSeries(np.array(t), np.array(ws), frame)
    return out
