"""``icub bag record|play|info``: MCAP bags in the rosbag2 layout (what ``ros2 bag`` does).

    icub bag record -o DIR [TOPICS...|--all] [--exclude RE] [--compression zstd]
    icub bag play DIR [--rate R] [--clock [HZ]] [--topics T ...] [--wait-for-subscribers]
    icub bag info DIR [--check]

Ctrl-C (or SIGTERM) ends a recording and finalises the bag. A bag whose recording was killed
is still readable up to its last flushed chunk; ``info`` says it was not closed cleanly and
``play`` replays what is readable. A damaged bag gives one ``icub: error:`` line.
"""

from __future__ import annotations

import argparse
import datetime
import json
import sys

from icub_pmp.bags import COMPRESSIONS, BagInfo, BagReader, BagStatus

__all__ = ["register", "run_record", "run_play", "run_info", "format_info"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``bag`` subcommand with ``record``, ``play`` and ``info``."""
    p = sub.add_parser("bag", help="record, replay and inspect MCAP bags (rosbag2 layout)")
    bag = p.add_subparsers(dest="bag_command", metavar="{record,play,info}")
    p.set_defaults(func=lambda _a: (p.print_help(), 2)[1])

    r = bag.add_parser("record", help="record topics into a new bag directory")
    r.add_argument("topics", nargs="*", help="topics to record (or --all)")
    r.add_argument("-o", "--output", help="bag directory to create (default: bags/<time>)")
    r.add_argument("-a", "--all", action="store_true",
                   help="record every topic, including service request events")
    r.add_argument("-e", "--exclude", help="regular expression of topics not to record")
    r.add_argument("--compression", choices=COMPRESSIONS, default="none",
                   help="MCAP chunk compression (default: none)")
    r.add_argument("--qos-depth", type=int, default=1000,
                   help="history depth of each subscription (buffers bursts)")
    r.add_argument("--use-sim-time", action="store_true",
                   help="stamp messages with /clock time instead of the wall clock")
    r.add_argument("--duration", type=float, default=0.0,
                   help="stop after this many seconds (default: until Ctrl-C)")
    r.add_argument("--max-wait", type=float, default=0.0,
                   help="fail if a named topic has no publisher after this many seconds")
    r.add_argument("--json", action="store_true", help="end with a JSON line of counts")
    r.set_defaults(func=run_record)

    pl = bag.add_parser("play", help="replay a bag on the graph")
    pl.add_argument("bag", help="bag directory (or .mcap file)")
    pl.add_argument("-r", "--rate", type=float, default=1.0, help="playback rate factor")
    pl.add_argument("--clock", type=float, nargs="?", const=100.0, default=None, metavar="HZ",
                    help="publish /clock with the bag time at HZ (default 100) for "
                         "use_sim_time nodes; the recorded /clock is then not replayed")
    pl.add_argument("--topics", nargs="+", help="replay only these topics")
    pl.add_argument("--wait-for-subscribers", type=float, nargs="?", const=10.0, default=0.0,
                    metavar="S", help="wait up to S s (default 10) until every replayed topic "
                                      "has a subscriber")
    pl.add_argument("--delay", type=float, default=0.0,
                    help="wait this long [s] after creating the publishers")
    pl.add_argument("--salvage", action="store_true",
                    help="replay the readable part of a truncated bag instead of failing")
    pl.add_argument("--json", action="store_true", help="end with a JSON line of counts")
    pl.set_defaults(func=run_play)

    i = bag.add_parser("info", help="summarise a bag and check its integrity")
    i.add_argument("bag", help="bag directory (or .mcap file)")
    i.add_argument("--check", action="store_true",
                   help="read every chunk (default: a finalised bag is read from its index)")
    i.set_defaults(func=run_info)


# ---------------------------------------------------------------------- record
def run_record(args: argparse.Namespace) -> int:
    """Record until Ctrl-C / SIGTERM / --duration; print per-topic counts."""
    from icub_pmp.ros.bag_recorder import format_result, record

    if not args.all and not args.topics:
        raise ValueError("name the topics to record, or use --all")
    if args.all and args.topics:
        raise ValueError("give either topics or --all, not both")
    out = args.output or f"bags/{datetime.datetime.now():%Y-%m-%d_%H-%M-%S}"
    result = record(
        out,
        None if args.all else args.topics,
        exclude=args.exclude,
        compression=args.compression,
        qos_depth=args.qos_depth,
        use_sim_time=args.use_sim_time,
        duration=args.duration,
        max_wait=args.max_wait,
    )
    print(format_result(result), flush=True)
    if args.json:
        print(json.dumps({"bag": result.path, "received": result.received,
                          "written": result.written, "lost": result.lost,
                          "size_bytes": result.size_bytes, "cpu_s": round(result.cpu_s, 3),
                          "duration_s": round(result.duration_s, 3)}), flush=True)
    return 0


# ---------------------------------------------------------------------- play
def run_play(args: argparse.Namespace) -> int:
    """Replay the bag; print what was published."""
    from icub_pmp.ros.bag_player import play

    result = play(
        args.bag,
        rate=args.rate,
        clock_hz=args.clock,
        topics=args.topics,
        wait_for_subscribers=args.wait_for_subscribers,
        delay=args.delay,
        salvage=args.salvage,
    )
    print(
        f"replayed {result.total} messages on {len(result.published)} topics in "
        f"{result.wall_s:.2f} s (bag time {result.bag_s:.2f} s, rate {args.rate}); "
        f"lateness median {result.late_median_ms:.3f} ms, max {result.late_max_ms:.3f} ms",
        flush=True,
    )
    if args.json:
        print(json.dumps({"published": result.published, "wall_s": result.wall_s,
                          "bag_s": result.bag_s, "late_median_ms": result.late_median_ms,
                          "late_p99_ms": result.late_p99_ms, "late_max_ms": result.late_max_ms,
                          "clock_published": result.clock_published}), flush=True)
    return 0


# ---------------------------------------------------------------------- info
def run_info(args: argparse.Namespace) -> int:
    """Print the summary; exit 1 if the bag is truncated (0 if finalised or only unclosed)."""
    info = BagReader(args.bag).info(check=args.check)
    print(format_info(info), flush=True)
    return 1 if info.status == BagStatus.TRUNCATED else 0


def format_info(info: BagInfo) -> str:
    """The ``ros2 bag info``-like text of a bag."""

    def when(ns: int) -> str:
        if not ns:
            return "-"
        sec, nsec = divmod(ns, 1_000_000_000)
        t = datetime.datetime.fromtimestamp(sec)
        return f"{t:%b %d %Y %H:%M:%S}.{nsec:09d} ({sec}.{nsec:09d})"

    state = {
        BagStatus.CLOSED: "closed cleanly",
        BagStatus.UNCLOSED: "NOT closed cleanly (recording interrupted)",
        BagStatus.TRUNCATED: "TRUNCATED",
    }[info.status]
    lines = [
        f"Files:             {', '.join(f.name for f in info.files)}",
        f"Bag size:          {_size(info.size_bytes)}",
        "Storage id:        mcap",
        f"Status:            {state}",
        f"Duration:          {info.duration_s:.9f}s",
        f"Start:             {when(info.start_ns)}",
        f"End:               {when(info.end_ns)}",
        f"Messages:          {info.message_count}",
        f"Compression:       {info.compression}",
        "Topic information: " + ("(none)" if not info.topics else ""),
    ]
    width = max((len(t.name) for t in info.topics), default=0)
    for t in info.topics:
        qos = ""
        if t.qos_profiles:
            q = t.qos_profiles[0]
            qos = f" | QoS: {q.reliability.name.lower()}, {q.durability.name.lower()}"
        lines.append(f"  Topic: {t.name:<{width}} | Type: {t.msgtype} | Count: {t.count} | "
                     f"Serialization Format: {t.serialization_format}{qos}")
    for note in info.notes:
        lines.append(f"Note: {note}")
    return "\n".join(lines)


def _size(n: int) -> str:
    for unit in ("B", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return f"{n:.1f} {unit}" if unit != "B" else f"{n} B"
        n /= 1024
    return f"{n} B"  # pragma: no cover


if __name__ == "__main__":  # pragma: no cover
    from icub_pmp.cli.main import main

    sys.exit(main(["bag", *sys.argv[1:]]))
