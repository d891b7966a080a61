"""JointStateCache: the latest /joint_states of the robot, received on a thread of its own and
read on demand.

Nodes that only look at the robot's posture now and then (planners, the gaze controller, goal
monitors) should not pay for 1 kHz joint states on their own executor, nor stop seeing them
while a callback of theirs waits. The cache receives them on a small helper node
(``<node>_joint_states``, no parameters, no ``use_sim_time`` and thus no ``/clock``) spun by an
``EventsExecutor`` on a background thread (about 6 % of a core at 1 kHz, against about 26 %
with rclpy's default executor), keeps the serialised bytes of the newest sample, and reads them
(:mod:`icub_pmp.ros.raw_messages`) only when :meth:`JointStateCache.latest` is called.
"""

from __future__ import annotations

import bisect
import threading
import time
from collections import deque
from typing import Callable, NamedTuple

import numpy as np
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import JointState

from icub_pmp.errors import IcubPmpError, InvalidInput
from icub_pmp.ros.node_runner import guard_parameter_services
from icub_pmp.ros.raw_messages import RawJointStateReader, raw_header_stamp_ns, read_joint_state

__all__ = ["JointStateCache", "MeasuredState"]


class MeasuredState(NamedTuple):
    """A measured joint state: ``t`` [s] (the message stamp: simulated time in the
    simulator), ``positions`` {joint: rad}, ``wall`` (time.monotonic() at reception)."""

    t: float
    positions: dict[str, float]
    wall: float


class JointStateCache:
    """The newest good sample of ``topic`` for ``node`` (module doc).

    Malformed samples are skipped (the previous good one stays) and reported through
    ``on_error`` (default: a throttled warning of ``node``). With ``history`` > 0 the last
    ``history`` seconds of samples (by stamp) are kept too, for :meth:`at`: the posture at the
    time of another sensor's data (a camera image). ``suffix`` names the helper node
    (``<node>_<suffix>``): a node with two caches gives each its own.
    """

    def __init__(self, node: Node, topic: str = "/joint_states",
                 on_error: Callable[[str], None] | None = None, history: float = 0.0,
                 suffix: str = "joint_states"):
        self._on_error = on_error or (lambda text: node.get_logger().warning(
            text, throttle_duration_sec=5.0))
        self._reader = RawJointStateReader()
        self._lock = threading.Lock()
        self._data: bytes | None = None
        self._wall = 0.0
        self._cached: MeasuredState | None = None
        self._bad_wall = -1.0
        self.count = 0
        self._history_ns = int(history * 1e9)
        self._stamps: deque[int] = deque()
        self._samples: deque[bytes] = deque()
        self.node = Node(f"{node.get_name()}_{suffix}", namespace=node.get_namespace(),
                         context=node.context, use_global_arguments=False)
        self.node.create_subscription(JointState, topic, self._on_data,
                                      qos_profile_sensor_data, raw=True)
        guard_parameter_services(self.node)
        self._executor = EventsExecutor(context=node.context)
        self._executor.add_node(self.node)
        self._stop = False
        self._thread = threading.Thread(target=self._spin, name=self.node.get_name(),
                                        daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        try:
            while not self._stop and rclpy.ok(context=self.node.context):
                self._executor.spin_once(timeout_sec=0.1)
        except (ExternalShutdownException, KeyboardInterrupt):
            pass
        except Exception:
            if rclpy.ok(context=self.node.context) and not self._stop:
                raise

    def _on_data(self, data: bytes) -> None:
        self._data = data
        self._wall = time.monotonic()
        self.count += 1
        if self._history_ns > 0:
            try:
                ns = raw_header_stamp_ns(data)
            except IcubPmpError:
                return
            with self._lock:
                if self._stamps and ns < self._stamps[-1]:  # time went back: start afresh
                    self._stamps.clear()
                    self._samples.clear()
                self._stamps.append(ns)
                self._samples.append(data)
                while self._stamps and self._stamps[0] < ns - self._history_ns:
                    self._stamps.popleft()
                    self._samples.popleft()

    def at(self, t: float) -> MeasuredState | None:
        """The kept sample whose stamp is nearest to ``t`` [s] (None without history or
        samples; a malformed one is reported and None returned). Check ``abs(s.t - t)``."""
        ns = int(round(t * 1e9))
        with self._lock:
            if not self._stamps:
                return None
            stamps = list(self._stamps)
            k = bisect.bisect_left(stamps, ns)
            k = min((i for i in (k - 1, k) if 0 <= i < len(stamps)),
                    key=lambda i: abs(stamps[i] - ns))
            try:
                m = read_joint_state(self._reader, self._samples[k])
            except IcubPmpError as exc:
                self._on_error(f"/joint_states sample skipped: {exc}")
                return None
        return MeasuredState(m.stamp_ns * 1e-9, dict(zip(m.name, m.position.tolist())),
                             time.monotonic())

    def latest(self, wait: float = 0.0) -> MeasuredState | None:
        """The newest good sample, or None before the first. ``wait`` > 0: before the first
        sample, wait up to that many seconds of wall time for it (a request right after
        start-up, while DDS is still matching the subscription)."""
        if wait > 0.0 and self._data is None:
            self.wait_for_first(wait)
        with self._lock:
            data, wall = self._data, self._wall
            if data is None or (self._cached is not None and self._cached.wall == wall):
                return self._cached
            if wall == self._bad_wall:
                return self._cached
            try:
                m = read_joint_state(self._reader, data)
                if m.position.shape != (len(m.name),) or not np.all(np.isfinite(m.position)):
                    raise InvalidInput(f"{len(m.name)} finite positions expected, got "
                                       f"{m.position.size}")
            except IcubPmpError as exc:
                self._bad_wall = wall
                self._on_error(f"/joint_states sample skipped: {exc}")
                return self._cached
            self._cached = MeasuredState(m.stamp_ns * 1e-9,
                                         dict(zip(m.name, m.position.tolist())), wall)
            return self._cached

    def wait_for_first(self, timeout: float) -> bool:
        """Wait up to ``timeout`` s of wall time for the first sample (a request right after
        start-up, while DDS is still matching the subscription); True once one arrived."""
        deadline = time.monotonic() + timeout
        while self._data is None and time.monotonic() < deadline:
            time.sleep(0.02)
        return self._data is not None

    def wall_age(self) -> float:
        """Wall time since the last sample arrived [s] (inf before the first)."""
        return time.monotonic() - self._wall if self._data is not None else float("inf")

    def close(self) -> None:
        """Stop the thread and destroy the helper node."""
        self._stop = True
        self._thread.join(timeout=2.0)
        self._executor.shutdown()
        self.node.destroy_node()
