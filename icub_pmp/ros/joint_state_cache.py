"""JointStateCache: the latest /joint_states of the robot, kept as bytes and read on demand.

Nodes that only look at the robot's posture now and then (planners, the gaze controller, goal
monitors) should not pay rclpy's per-field deserialisation at 1 kHz: the subscription takes
the serialised bytes (``raw=True``) and :meth:`JointStateCache.latest` reads the most recent
one only when asked.
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import JointState

from icub_pmp.errors import IcubPmpError
from icub_pmp.ros.raw_messages import RawJointStateReader, read_joint_state

__all__ = ["JointStateCache", "MeasuredState"]


class MeasuredState(NamedTuple):
    """A measured joint state: ``t`` [s] (the message stamp: simulated time in the
    simulator), ``positions`` {joint: rad}, ``wall`` (time.monotonic() at reception)."""

    t: float
    positions: dict[str, float]
    wall: float


class JointStateCache:
    """Subscribes ``topic`` (raw) on ``node``; :meth:`latest` reads the newest sample.

    Malformed samples are skipped with a throttled warning (the previous good one stays).
    """

    def __init__(self, node: Node, topic: str = "/joint_states", callback_group=None):
        self._node = node
        self._reader = RawJointStateReader()
        self._data: bytes | None = None
        self._wall = 0.0
        self._cached: MeasuredState | None = None
        self.count = 0
        node.create_subscription(JointState, topic, self._on_data, qos_profile_sensor_data,
                                 raw=True, callback_group=callback_group)

    def _on_data(self, data: bytes) -> None:
        self._data = data
        self._wall = time.monotonic()
        self.count += 1

    def latest(self) -> MeasuredState | None:
        """The newest good sample, or None before the first."""
        data = self._data
        if data is None:
            return self._cached
        if self._cached is not None and self._cached.wall == self._wall:
            return self._cached
        try:
            m = read_joint_state(self._reader, data)
            if len(m.position) != len(m.name) or not np.all(np.isfinite(m.position)):
                raise IcubPmpError(f"{len(m.position)} finite positions expected for "
                                   f"{len(m.name)} names")
        except IcubPmpError as exc:
            self._node.get_logger().warning(f"/joint_states sample skipped: {exc}",
                                            throttle_duration_sec=5.0)
            return self._cached
        self._cached = MeasuredState(m.stamp_ns * 1e-9, dict(zip(m.name, m.position.tolist())),
                                     self._wall)
        return self._cached

    def wall_age(self) -> float:
        """Wall time since the last sample arrived [s] (inf before the first)."""
        return time.monotonic() - self._wall if self._data is not None else float("inf")
