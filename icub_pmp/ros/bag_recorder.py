"""BagRecorder: record topics of the ROS graph into a :class:`~icub_pmp.bags.BagWriter`.

What ``ros2 bag record`` does, on rclpy: topics are discovered on the graph (every
``discovery_period`` s, so late publishers are picked up), each is subscribed with a *raw*
subscription of the type the graph reports (messages stay CDR bytes, nothing is deserialised)
and a QoS matching its publishers (reliable only if all are; transient local only if all are,
so latched topics such as ``/robot_description`` are recorded), with a deep history
(``qos_depth``) so bursts are buffered instead of dropped. Each message is written with its
receive time (wall clock, or the ROS clock with ``use_sim_time``). What is recorded is a
:class:`~icub_pmp.bags.RecordSelection` (``ros2 bag record``'s topic, service, hidden-topic and
action options): service calls come from the introspection topics ``<service>/_service_event``,
actions from ``<action>/_action/{status,feedback}``, and neither is in the default bag (the
official MCAP ROS 2 decoder cannot decode them). Run it with :func:`record` (EventsExecutor;
SIGINT and SIGTERM finalise the bag).
"""

from __future__ import annotations

import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable

import rclpy
from rclpy.clock import Clock, ClockType
from rclpy.context import Context
from rclpy.duration import Duration
from rclpy.event_handler import QoSMessageLostInfo, SubscriptionEventCallbacks
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future
from rosbags.interfaces import (
    Qos,
    QosDurability,
    QosHistory,
    QosLiveliness,
    QosReliability,
    QosTime,
)

from icub_pmp.bags import BagWriter, RecordSelection, TopicHandle
from icub_pmp.errors import BagError, IcubPmpError
from icub_pmp.ros.msg_types import get_interface
from icub_pmp.ros.qos import matching_qos

__all__ = ["BagRecorder", "RecordResult", "record", "qos_to_rosbags"]

_INFINITE = QosTime(2147483647, 4294967295)  # how rosbag2 writes an infinite duration


def qos_to_rosbags(p: QoSProfile) -> Qos:
    """An rclpy QoS profile as the rosbags ``Qos`` stored in the bag's metadata."""
    return Qos(
        QosHistory(int(p.history)),
        int(p.depth),
        QosReliability(int(p.reliability)),
        QosDurability(int(p.durability)),
        _qos_time(p.deadline),
        _qos_time(p.lifespan),
        QosLiveliness(int(p.liveliness)),
        _qos_time(p.liveliness_lease_duration),
        bool(p.avoid_ros_namespace_conventions),
    )


def _qos_time(d: Duration) -> QosTime:
    ns = int(d.nanoseconds)
    if ns >= 2**63 - 1 or ns // 1_000_000_000 >= 2147483647:
        return _INFINITE
    return QosTime(ns // 1_000_000_000, ns % 1_000_000_000)


@dataclass(frozen=True)
class RecordResult:
    """What a recording wrote: messages received/written and DDS-reported losses per topic."""

    path: str
    received: dict[str, int]
    written: dict[str, int]
    lost: dict[str, int]
    duration_s: float  # wall time from the first subscription to the end [s]
    size_bytes: int
    cpu_s: float = 0.0  # CPU time of the recording process (user + system) [s]
    error: str = ""  # why the recording stopped early (a write refused: disk full), else ""

    @property
    def total(self) -> int:
        """Messages written on all topics."""
        return sum(self.written.values())


class BagRecorder(Node):
    """Subscribe to the topics ``selection`` keeps, as they appear, and write to ``writer``.

    ``qos_depth``: history depth of each subscription. ``log``: where progress lines go
    (default: stdout).
    """

    def __init__(
        self,
        writer: BagWriter,
        selection: RecordSelection,
        *,
        qos_depth: int = 1000,
        discovery_period: float = 0.2,
        use_sim_time: bool = False,
        context: Context | None = None,
        name: str = "icub_bag_recorder",
        log: Callable[[str], None] | None = None,
    ):
        super().__init__(
            name,
            context=context,
            parameter_overrides=[Parameter("use_sim_time", value=use_sim_time)],
            start_parameter_services=False,
        )
        if qos_depth < 1:
            raise BagError(f"qos depth must be >= 1, got {qos_depth}")
        self.writer = writer
        self.selection = selection
        self.qos_depth = int(qos_depth)
        self.use_sim_time = use_sim_time
        self.received: dict[str, int] = {}
        self.lost: dict[str, int] = {}
        self.error = ""  # the write error that stopped the recording, "" while none
        self._subs: dict[str, Any] = {}
        self._skipped: set[str] = set()
        self._log = log or (lambda s: print(s, flush=True))
        self.started = time.monotonic()
        # Wall-clock (steady) timers: with use_sim_time, ROS-time timers would not fire before
        # the first /clock message, and topics would be subscribed late.
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._discovery = self.create_timer(discovery_period, self.discover, clock=steady)
        self._flusher = self.create_timer(
            min(0.25, writer.flush_interval / 2), self._flush, clock=steady
        )
        self.discover()

    # ------------------------------------------------------------------ discovery
    def discover(self) -> None:
        """Subscribe to every wanted topic that has a publisher and is not yet recorded."""
        for topic, types in self.get_topic_names_and_types():
            if topic in self._subs or topic in self._skipped or not self.selection.wants(topic):
                continue
            infos = self.get_publishers_info_by_topic(topic)
            if not infos or not types:
                continue
            msgtype = types[0]
            if len(set(types)) > 1:
                self._log(f"warning: {topic} has several types {types}; recording {msgtype}")
            try:
                cls = get_interface(msgtype)
                handle = self.writer.add_topic(
                    topic,
                    msgtype,
                    qos_profiles=[qos_to_rosbags(i.qos_profile) for i in infos],
                    type_hash=_hash_text(infos[0]),
                )
            except IcubPmpError as exc:
                self._skipped.add(topic)
                self._log(f"warning: not recording {topic}: {exc}")
                continue
            self.received[topic] = 0
            self.lost[topic] = 0
            self._subs[topic] = self.create_subscription(
                cls,
                topic,
                self._guarded(self._make_callback(handle)),
                matching_qos(self, topic, depth=self.qos_depth),
                raw=True,
                event_callbacks=SubscriptionEventCallbacks(
                    message_lost=self._make_lost_callback(topic)
                ),
            )
            self._log(f"recording {topic} [{msgtype}]")

    def missing(self) -> list[str]:
        """Channels asked for by name not yet subscribed (no publisher seen yet)."""
        return [t for t in self.selection.named_topics() if t not in self._subs]

    @property
    def subscribed(self) -> list[str]:
        """Topics being recorded."""
        return list(self._subs)

    # ------------------------------------------------------------------ callbacks
    def _make_callback(self, handle: TopicHandle) -> Callable[[bytes], None]:
        topic = handle.topic
        write = self.writer.write
        received = self.received
        if self.use_sim_time:
            clock = self.get_clock()

            def cb_sim(data: bytes) -> None:
                received[topic] += 1
                write(handle, clock.now().nanoseconds, data)

            return cb_sim

        def cb(data: bytes) -> None:
            # The EventsExecutor of the Jazzy wheel cannot pass MessageInfo: receive time here.
            received[topic] += 1
            write(handle, time.time_ns(), data)

        return cb

    def _guarded(self, cb: Callable[[bytes], None]) -> Callable[[bytes], None]:
        """``cb`` that stops writing at the first write the file system refuses (disk full,
        size limit): the error is kept in :attr:`error` and logged once, the recording loop
        ends on it, and no callback raises into the executor."""

        def guarded(data: bytes) -> None:
            if self.error:
                return
            try:
                cb(data)
            except BagError as exc:
                self.error = str(exc)
                self._log(f"recording stopped: {exc}")

        return guarded

    def _make_lost_callback(self, topic: str) -> Callable[[QoSMessageLostInfo], None]:
        def cb(info: QoSMessageLostInfo) -> None:
            self.lost[topic] = int(info.total_count)

        return cb

    def _flush(self) -> None:
        if self.error:
            return
        try:
            self.writer.flush_if_due()
        except BagError as exc:
            self.error = str(exc)
            self._log(f"recording stopped: {exc}")

    def stop(self) -> None:
        """Destroy the subscriptions (no callback runs afterwards)."""
        self._discovery.cancel()
        self._flusher.cancel()
        for sub in self._subs.values():
            self.destroy_subscription(sub)


def _hash_text(info: Any) -> str:
    h = getattr(info, "topic_type_hash", None)
    if h is None:
        return ""
    text = str(h)
    return text if text.startswith("RIHS01_") else ""


def record(
    path: str,
    selection: RecordSelection,
    *,
    compression: str = "none",
    qos_depth: int = 1000,
    use_sim_time: bool = False,
    duration: float = 0.0,
    max_wait: float = 0.0,
    flush_interval: float = 0.5,
    drain: float = 1.0,
    domain_id: int | None = None,
    log: Callable[[str], None] | None = None,
    custom_data: dict[str, str] | None = None,
) -> RecordResult:
    """Record until SIGINT/SIGTERM (or ``duration`` s), then finalise the bag at ``path``.

    ``max_wait`` > 0: fail if a channel named in ``selection`` has no publisher after that
    many seconds.
    ``drain``: after the stop, keep writing what already arrived for at most this long [s].
    """
    from rclpy.experimental import EventsExecutor

    log = log or (lambda s: print(s, flush=True))
    cpu0 = _cpu_seconds()
    writer = BagWriter(
        path,
        compression=compression,
        flush_interval=flush_interval,
        custom_data={"recorder": "icub_pmp icub bag record", **(custom_data or {})},
    )
    ctx = Context()
    rclpy.init(context=ctx, domain_id=domain_id, signal_handler_options=SignalHandlerOptions.NO)
    stop = {"why": ""}

    def on_signal(signum: int, _frame: Any) -> None:
        stop["why"] = signal.Signals(signum).name  # the spin loop returns within 0.1 s

    previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    recorder: BagRecorder | None = None
    try:
        recorder = BagRecorder(
            writer, selection, qos_depth=qos_depth, use_sim_time=use_sim_time,
            context=ctx, log=log,
        )
        executor = EventsExecutor(context=ctx)
        executor.add_node(recorder)
        log(f"recording to {path} (Ctrl-C to stop)")
        t_end = time.monotonic() + duration if duration > 0 else float("inf")
        waited = time.monotonic()
        never = Future()  # spin in C++ for 0.1 s slices (many messages per Python call)
        while (not stop["why"] and not recorder.error and ctx.ok()
               and time.monotonic() < t_end):
            executor.spin_until_future_complete(never, timeout_sec=0.1)
            if max_wait > 0 and recorder.missing() and time.monotonic() - waited > max_wait:
                raise BagError(
                    f"no publisher for {', '.join(recorder.missing())} after {max_wait} s"
                )
        # Drain what DDS already delivered: stop after a 50 ms slice without messages
        # (at most `drain` s, so live traffic cannot keep the recording going).
        t_drain = time.monotonic() + drain
        before = -1
        while ctx.ok() and not recorder.error and time.monotonic() < t_drain:
            now_total = sum(recorder.received.values())
            if now_total == before:
                break
            before = now_total
            executor.spin_until_future_complete(never, timeout_sec=0.05)
        recorder.stop()
    finally:
        # Finalise whatever happens: a second Ctrl-C must not interrupt the footer.
        for s in previous:
            signal.signal(s, signal.SIG_IGN)
        received = dict(recorder.received) if recorder else {}
        lost = dict(recorder.lost) if recorder else {}
        started = recorder.started if recorder else time.monotonic()
        error = recorder.error if recorder else ""
        try:
            stats = writer.close()
        except BagError as exc:
            if not error:
                raise
            # the write refused mid-recording: the footer cannot be written either
            log(f"the bag could not be finalised ({exc}); free space, then "
                f"`icub bag repair {path}`")
            stats = None
        finally:
            if recorder is not None:
                recorder.destroy_node()
            rclpy.try_shutdown(context=ctx)
            for s, h in previous.items():
                signal.signal(s, h)
    if stats is None:
        files = list(Path(path).glob("*.mcap"))
        written, size = dict(writer.counts), sum(f.stat().st_size for f in files)
    else:
        written, size = dict(stats.counts), stats.bytes_written
    return RecordResult(
        path=str(path if stats is None else stats.path),
        received=received,
        written=written,
        lost=lost,
        duration_s=time.monotonic() - started,
        size_bytes=size,
        cpu_s=_cpu_seconds() - cpu0,
        error=error,
    )


def _cpu_seconds() -> float:
    import resource

    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def format_result(result: RecordResult, topics: Iterable[str] | None = None) -> str:
    """Per-topic lines 'topic: received N, written N, lost N' and a total line."""
    lines = []
    for t in sorted(topics or result.written):
        lines.append(
            f"  {t}: received {result.received.get(t, 0)}, written {result.written.get(t, 0)}"
            + (f", lost (DDS) {result.lost[t]}" if result.lost.get(t) else "")
        )
    lines.append(
        f"wrote {result.total} messages on {len(result.written)} topics in "
        f"{result.duration_s:.1f} s to {result.path} ({result.size_bytes / 1e6:.1f} MB)"
    )
    return "\n".join(lines)


if __name__ == "__main__":  # pragma: no cover - use `icub bag record`
    sys.exit("use: icub bag record -o DIR [TOPICS...|--all] [--all-services] [--all-actions]")
