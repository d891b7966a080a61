"""BagPlayer: replay a bag on the ROS graph (what ``ros2 bag play`` does), on rclpy.

Messages are published in the order they were recorded, as the CDR bytes stored in the bag
(``Publisher.publish`` takes serialised bytes; nothing is decoded or re-encoded), each at
``start + (log_time - first_log_time) / rate`` on the monotonic clock. Each topic gets a
publisher with the QoS its recorded publishers offered (reliable only if all were, transient
local only if all were). With ``clock_hz`` the player publishes ``/clock`` with the bag time
at that rate (and before every message that is due), so ``use_sim_time`` nodes run on the
replayed time; the recorded ``/clock`` topic is then not replayed. SIGINT/SIGTERM stop it.
"""

from __future__ import annotations

import signal
import statistics
import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import rclpy
from rclpy.context import Context
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from rosbags.interfaces import Qos, QosDurability, QosReliability
from rosgraph_msgs.msg import Clock

from icub_pmp.bags import BagReader, BagStatus, BagTopic
from icub_pmp.errors import BagError, IcubPmpError, UnknownName
from icub_pmp.ros.msg_types import get_interface

__all__ = ["PlayResult", "play", "qos_for_replay"]

_SLEEP_MARGIN = 50e-6  # [s] wake this much early; the rest is a short busy wait


@dataclass(frozen=True)
class PlayResult:
    """What a replay published and how late it was against the bag's timing."""

    published: dict[str, int]
    wall_s: float  # first to last publication [s]
    bag_s: float  # first to last log time of the replayed messages [s]
    late_median_ms: float  # median of (publish time - scheduled time) [ms]
    late_p99_ms: float
    late_max_ms: float
    clock_published: int

    @property
    def total(self) -> int:
        """Messages replayed on all topics."""
        return sum(self.published.values())


def qos_for_replay(profiles: Sequence[Qos]) -> QoSProfile:
    """The publisher QoS for a topic recorded with publishers that offered ``profiles``."""
    reliable = bool(profiles) and all(p.reliability == QosReliability.RELIABLE for p in profiles)
    latched = bool(profiles) and all(
        p.durability == QosDurability.TRANSIENT_LOCAL for p in profiles
    )
    depth = max([int(p.depth) for p in profiles if int(p.depth) > 0] + [10])
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=min(depth, 1000),
        reliability=ReliabilityPolicy.RELIABLE if (reliable or not profiles)
        else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE,
    )


def play(
    path: str,
    *,
    rate: float = 1.0,
    clock_hz: float | None = None,
    topics: Sequence[str] | None = None,
    wait_for_subscribers: float = 0.0,
    delay: float = 0.0,
    salvage: bool = False,
    domain_id: int | None = None,
    log: Callable[[str], None] | None = None,
) -> PlayResult:
    """Replay the bag at ``path``; returns the counts and timing. Raises BagError."""
    log = log or (lambda s: print(s, flush=True))
    if not rate > 0:
        raise BagError(f"--rate must be > 0, got {rate}")
    if clock_hz is not None and not clock_hz > 0:
        raise BagError(f"--clock rate must be > 0 Hz, got {clock_hz}")
    reader = BagReader(path)
    info = reader.info()
    if info.status == BagStatus.TRUNCATED and not salvage:
        raise BagError(f"{path}: {info.notes[0]}")
    for note in info.notes:
        log(f"warning: {note}")
    by_name = {t.name: t for t in info.topics}
    if topics:
        names = [t if t.startswith("/") else "/" + t for t in topics]
        for n in names:
            if n not in by_name:
                raise UnknownName("topic", n, by_name)
    else:
        names = list(by_name)
    if clock_hz is not None and "/clock" in names:
        names.remove("/clock")
        log("note: --clock publishes the bag time on /clock; the recorded /clock is not replayed")

    ctx = Context()
    rclpy.init(context=ctx, domain_id=domain_id, signal_handler_options=SignalHandlerOptions.NO)
    stop = {"why": ""}

    def on_signal(signum: int, _frame: Any) -> None:
        stop["why"] = signal.Signals(signum).name

    previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    node = Node("icub_bag_player", context=ctx, start_parameter_services=False)
    try:
        pubs = _publishers(node, [by_name[n] for n in names], log)
        clock_pub = (
            node.create_publisher(Clock, "/clock", QoSProfile(depth=10)) if clock_hz else None
        )
        _wait(pubs, wait_for_subscribers, stop, log)
        if delay > 0:
            time.sleep(delay)
        return _replay(reader, pubs, clock_pub, rate, clock_hz, stop, log)
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=ctx)
        for s, h in previous.items():
            signal.signal(s, h)


def _publishers(node: Node, topics: Sequence[BagTopic], log: Callable[[str], None]) -> dict:
    pubs = {}
    for t in topics:
        try:
            cls = get_interface(t.msgtype)
        except IcubPmpError as exc:
            log(f"warning: not replaying {t.name}: {exc}")
            continue
        pubs[t.name] = node.create_publisher(cls, t.name, qos_for_replay(t.qos_profiles))
    if not pubs:
        raise BagError("nothing to replay: no topic of the bag has an installed message type")
    return pubs


def _wait(pubs: dict, timeout: float, stop: dict, log: Callable[[str], None]) -> None:
    if timeout <= 0:
        return
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not stop["why"]:
        if all(p.get_subscription_count() > 0 for p in pubs.values()):
            time.sleep(0.3)  # the subscribers' side of the match settles too
            return
        time.sleep(0.02)
    lonely = [t for t, p in pubs.items() if p.get_subscription_count() == 0]
    if lonely:
        log(f"warning: no subscriber after {timeout} s on {', '.join(lonely)}")


def _replay(
    reader: BagReader,
    pubs: dict,
    clock_pub: Any,
    rate: float,
    clock_hz: float | None,
    stop: dict,
    log: Callable[[str], None],
) -> PlayResult:
    counts = {t: 0 for t in pubs}
    late: list[float] = []
    clock_count = 0
    first_log = last_log = None
    t0 = first_pub = last_pub = 0.0
    next_clock = float("inf")
    clock_period = 1.0 / clock_hz if clock_hz else float("inf")

    def publish_clock(wall: float, limit: int | None = None) -> None:
        nonlocal clock_count
        ns = first_log + int((wall - t0) * rate * 1e9)
        if limit is not None:
            ns = min(ns, limit)
        msg = Clock()
        msg.clock.sec, msg.clock.nanosec = divmod(ns, 1_000_000_000)
        clock_pub.publish(msg)
        clock_count += 1

    for m in reader.messages(list(pubs)):
        if stop["why"]:
            break
        if first_log is None:
            first_log = m.log_time
            t0 = time.perf_counter()
            if clock_pub is not None:
                publish_clock(t0)
                next_clock = t0 + clock_period
        target = t0 + (m.log_time - first_log) / rate * 1e-9
        while not stop["why"]:
            now = time.perf_counter()
            if next_clock <= min(target, now):
                publish_clock(next_clock)
                next_clock += clock_period
                continue
            wake = min(target, next_clock)
            if wake - now > _SLEEP_MARGIN:
                time.sleep(min(wake - now - _SLEEP_MARGIN, 0.1))
                continue
            if now >= target:
                break
        if stop["why"]:
            break
        pub_t = time.perf_counter()
        pubs[m.topic].publish(m.data)
        late.append(pub_t - target)
        counts[m.topic] += 1
        last_log = m.log_time
        last_pub = pub_t
        if not first_pub:
            first_pub = pub_t
    if clock_pub is not None and first_log is not None and not stop["why"]:
        publish_clock(time.perf_counter(), limit=last_log)  # the bag's last time
    for p in pubs.values():
        if p.qos_profile.reliability == ReliabilityPolicy.RELIABLE:
            p.wait_for_all_acked(Duration(seconds=2))
    if stop["why"]:
        log(f"stopped by {stop['why']}")
    ms = sorted(x * 1e3 for x in late) or [0.0]
    return PlayResult(
        published={t: n for t, n in counts.items()},
        wall_s=max(0.0, last_pub - first_pub),
        bag_s=((last_log or 0) - (first_log or 0)) * 1e-9,
        late_median_ms=statistics.median(ms),
        late_p99_ms=ms[min(len(ms) - 1, int(0.99 * len(ms)))],
        late_max_ms=ms[-1],
        clock_published=clock_count,
    )
