"""``icub bag record|play|info|convert|repair``: MCAP bags in the rosbag2 layout (``ros2 bag``).

    icub bag record -o DIR [TOPICS...|--all] [--all-services|--services S ...]
                    [--all-actions|--actions A ...] [--exclude RE] [--compression zstd]
    icub bag play DIR [--rate R] [--clock [HZ]] [--topics T ...] [--wait-for-subscribers]
    icub bag info DIR [--check]
    icub bag convert DIR -o NEW [the record options; default: every topic]
    icub bag repair DIR [-o NEW] [--force]

Ctrl-C (or SIGTERM) ends a recording and finalises the bag. A bag whose recording was killed
is still readable up to its last flushed chunk; ``info`` says it was not closed cleanly and
``play`` replays what is readable. ``info`` names every channel a common reader (rosbags, the
official MCAP ROS 2 decoder) cannot decode; ``convert`` writes a copy of an older bag that they
all read. ``repair`` finalises a bag whose recording was killed or whose file was cut (index,
summary, footer and ``metadata.yaml``; in place the original is kept as ``DIR.damaged``), so
that ``ros2 bag play`` and rosbags' Reader open it. A damaged bag gives one ``icub: error:``
line. A recording that cannot write (disk full, file size limit) stops, says so and exits 1.
"""

from __future__ import annotations

import argparse
import datetime
import json
import sys

from icub_pmp.bags import (
    COMPRESSIONS,
    MCAP_ROS2,
    ROSBAGS,
    BagInfo,
    BagReader,
    BagStatus,
    ReaderCheck,
    RecordSelection,
    UnreadableChannel,
)

__all__ = ["register", "run_record", "run_play", "run_info", "run_convert", "run_repair",
           "format_info", "format_unreadable"]

RECORD_EPILOG = """\
What is recorded: the topics named, or with --all every topic (hidden ones, whose names have a
part starting with "_", only with --include-hidden-topics). Service calls (from
<service>/_service_event, the server must enable introspection) need --all-services or
--services; actions (<action>/_action/status and /feedback) need --all-actions or --actions.
Unlike `ros2 bag record -a`, --all records no service events: the official MCAP ROS 2
decoder (mcap-ros2-support, what many tools use) cannot decode service-event types
(pkg/srv/Name_Event) nor action feedback (pkg/action/Name_FeedbackMessage), and stops at the
first such message, so the default bag holds none; rosbags reads them. `icub bag info` warns
about such channels."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``bag`` subcommand with ``record``, ``play``, ``info``, ``convert`` and
    ``repair``."""
    p = sub.add_parser("bag", help="record, replay, inspect and convert MCAP bags (rosbag2 "
                                   "layout)")
    bag = p.add_subparsers(dest="bag_command", metavar="{record,play,info,convert,repair}")
    p.set_defaults(func=lambda _a: (p.print_help(), 2)[1])

    r = bag.add_parser("record", help="record topics into a new bag directory",
                       epilog=RECORD_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    r.add_argument("-o", "--output", help="bag directory to create (default: bags/<time>)")
    _add_selection(r)
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

    c = bag.add_parser("convert", help="rewrite a bag with today's schemas (fixes older bags)",
                       epilog="Every topic is kept unless topics are named; service events "
                              "and action topics only with --all-services / --services, "
                              "--all-actions / --actions (see `icub bag record --help`).",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    c.add_argument("bag", help="bag directory (or .mcap file) to read")
    c.add_argument("-o", "--output", required=True, help="bag directory to create")
    _add_selection(c)
    c.add_argument("--compression", choices=COMPRESSIONS, default="none",
                   help="MCAP chunk compression (default: none)")
    c.set_defaults(func=run_convert)

    rp = bag.add_parser(
        "repair", help="finalise a bag whose recording was interrupted (index, summary, "
                       "metadata.yaml)",
        epilog="Every message of the complete chunks is kept, on every channel; the record cut "
               "by the end of the file is left out and named. In place (no -o) the damaged "
               "original stays beside the repaired bag as DIR.damaged. A bag closed cleanly "
               "is left alone unless --force.")
    rp.add_argument("bag", help="bag directory (or .mcap file) to repair")
    rp.add_argument("-o", "--output", default=None,
                    help="write the repaired bag here instead of in place")
    rp.add_argument("--force", action="store_true",
                    help="rewrite a bag that was closed cleanly too")
    rp.set_defaults(func=run_repair)


def _add_selection(p: argparse.ArgumentParser) -> None:
    """The channel options of ``ros2 bag record`` (see RECORD_EPILOG)."""
    g = p.add_argument_group("what to record")
    g.add_argument("topics", nargs="*", help="topics to record (or --all)")
    g.add_argument("--topics", dest="topic_list", nargs="+", default=[], metavar="TOPIC",
                   help="topics to record (the same as naming them)")
    g.add_argument("-a", "--all", "--all-topics", dest="all", action="store_true",
                   help="every topic (no service events: see below)")
    g.add_argument("--all-services", action="store_true",
                   help="every service with introspection, from <service>/_service_event")
    g.add_argument("--services", nargs="+", default=[], metavar="SERVICE",
                   help="these services (their <service>/_service_event topics)")
    g.add_argument("--all-actions", action="store_true",
                   help="every action's <action>/_action/status and /feedback")
    g.add_argument("--actions", nargs="+", default=[], metavar="ACTION",
                   help="these actions' status and feedback topics")
    g.add_argument("--include-hidden-topics", action="store_true",
                   help="with --all, also hidden topics (a name part starting with '_')")
    g.add_argument("-e", "--exclude", "--exclude-regex", dest="exclude", default="",
                   help="regular expression of topics not to record")


def _selection(args: argparse.Namespace, default_all: bool = False) -> RecordSelection:
    topics = list(args.topics) + list(args.topic_list)
    if args.all and topics:
        raise ValueError("give either topics or --all, not both")
    everything = args.all or (default_all and not topics)
    return RecordSelection(
        topics=tuple(topics), all_topics=everything, services=tuple(args.services),
        all_services=args.all_services, actions=tuple(args.actions),
        all_actions=args.all_actions, include_hidden_topics=args.include_hidden_topics,
        exclude=args.exclude)


# ---------------------------------------------------------------------- record
def run_record(args: argparse.Namespace) -> int:
    """Record until Ctrl-C / SIGTERM / --duration; print per-topic counts."""
    from icub_pmp.ros.bag_recorder import format_result, record

    selection = _selection(args)
    out = args.output or f"bags/{datetime.datetime.now():%Y-%m-%d_%H-%M-%S}"
    result = record(
        out,
        selection,
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
                          "duration_s": round(result.duration_s, 3),
                          "error": result.error}), flush=True)
    if result.error:
        print(f"icub: error: the recording stopped early: {result.error}", file=sys.stderr,
              flush=True)
        return 1
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
    unreadable = ReaderCheck(info.topics).unreadable()
    if unreadable:
        print(format_unreadable(unreadable, args.bag), flush=True)
    return 1 if info.status == BagStatus.TRUNCATED else 0


def format_unreadable(unreadable: tuple[UnreadableChannel, ...], bag: str) -> str:
    """One ``Warning:`` line per channel a common reader cannot decode, and what to do."""
    by_topic: dict[str, list[UnreadableChannel]] = {}
    for u in unreadable:
        by_topic.setdefault(u.topic, []).append(u)
    lines = [f"Warning: {topic} [{us[0].msgtype}]: "
             + "; ".join(f"{u.reader} cannot decode it ({u.reason})" for u in us)
             for topic, us in by_topic.items()]
    readers = {u.reader for u in unreadable}
    what = []
    if MCAP_ROS2 in readers:
        what.append("the MCAP ROS 2 decoder raises at the first message of such a channel "
                    "(name the other topics to read them)")
    if ROSBAGS in readers:
        what.append("rosbags' AnyReader refuses the whole bag")
    lines.append(f"Note: {' and '.join(what)}; `icub bag convert {bag} -o NEW` writes a copy "
                 "without these channels")
    return "\n".join(lines)


def run_convert(args: argparse.Namespace) -> int:
    """Rewrite the bag; print what was kept, dropped and left with its recorded schema."""
    from icub_pmp.bags import BagConverter

    result = BagConverter(args.bag, args.output, _selection(args, default_all=True),
                          compression=args.compression).run()
    st = result.stats
    for topic, n in sorted(st.counts.items()):
        print(f"  {topic}: {n}", flush=True)
    for topic, why in sorted(result.kept_recorded_schema.items()):
        print(f"note: {topic} keeps its recorded schema: {why}", flush=True)
    if result.dropped:
        print(f"left out (not selected): {', '.join(result.dropped)}", flush=True)
    print(f"wrote {st.total} messages on {len(st.counts)} topics to {st.path} "
          f"({st.bytes_written / 1e6:.1f} MB)", flush=True)
    return 0


def run_repair(args: argparse.Namespace) -> int:
    """Repair the bag; print what was recovered and where the original went."""
    from icub_pmp.bags import BagRepair

    result = BagRepair(args.bag, args.output, force=args.force).run()
    if not result.repaired:
        print(f"{args.bag} was closed cleanly: nothing to repair (--force rewrites it)",
              flush=True)
        return 0
    st = result.stats
    for topic, n in sorted(st.counts.items()):
        print(f"  {topic}: {n}", flush=True)
    for cut in result.cut:
        print(f"left out: the incomplete record of {cut}", flush=True)
    for topic in result.kept_recorded_schema:
        print(f"note: {topic} keeps its recorded schema (the installed type differs)",
              flush=True)
    print(f"repaired ({result.status_before}): {st.total} messages on {len(st.counts)} "
          f"topics in {result.path}", flush=True)
    if result.damaged_kept_at is not None:
        print(f"the damaged original is kept at {result.damaged_kept_at}", flush=True)
    return 0


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
