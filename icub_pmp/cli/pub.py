"""``icub pub TOPIC TYPE [VALUES]``: publish a message (what ``ros2 topic pub`` does).

    icub pub /effort_command sensor_msgs/msg/JointState "{name: [r_elbow], effort: [1.0]}" -1
    icub pub /impedance_controller/velocity_command sensor_msgs/msg/JointState \\
        "{name: [r_elbow], velocity: [0.1]}" --rate 10
    icub pub /joint_trajectory trajectory_msgs/msg/JointTrajectory \\
        "{joint_names: [r_elbow], points: [{positions: [1.2], time_from_start: {sec: 2}}]}" --once

VALUES is the message in ros2cli's YAML syntax (fields not named keep their defaults). Without
``--once``/``--times`` it publishes at ``--rate`` (1 Hz) until Ctrl-C. ``--once`` and
``--times`` first wait for ``--wait-matching-subscriptions`` subscribers (default 1) and exit
non-zero, saying why, if none was matched within ``--timeout``. QoS: reliable, volatile,
depth 1 (compatible with best-effort subscribers); ``--qos-durability transient_local`` for a
latched topic.
"""

from __future__ import annotations

import argparse
import math

from icub_pmp.cli.defaults import DISCOVERY_TIMEOUT

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``pub`` subcommand."""
    p = sub.add_parser(
        "pub", help="publish a message on a topic (ros2 topic pub)",
        description=__doc__.split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("topic", help="topic name, e.g. /effort_command")
    p.add_argument("type", help="message type, e.g. sensor_msgs/msg/JointState")
    p.add_argument("values", nargs="*", metavar="VALUES",
                   help="the message in YAML (default: {})")
    p.add_argument("-r", "--rate", type=float, default=1.0,
                   help="publishing rate [Hz] (default 1)")
    p.add_argument("-1", "--once", action="store_true", help="publish one message and exit")
    p.add_argument("-t", "--times", type=int, default=0,
                   help="publish this many messages and exit")
    p.add_argument("-w", "--wait-matching-subscriptions", type=int, default=None,
                   metavar="N", help="wait for N matched subscribers before publishing "
                                     "(default 1 with --once/--times, else 0)")
    p.add_argument("--timeout", type=float, default=DISCOVERY_TIMEOUT,
                   help="how long to wait for the subscribers [s] "
                        f"(default {DISCOVERY_TIMEOUT:g})")
    p.add_argument("--qos-reliability", choices=("reliable", "best_effort"),
                   default="reliable")
    p.add_argument("--qos-durability", choices=("volatile", "transient_local"),
                   default="volatile")
    p.add_argument("--qos-depth", type=int, default=1)
    p.add_argument("-p", "--print", type=int, default=1, metavar="N", dest="print_every",
                   help="print every N-th published message (0: none)")
    p.set_defaults(func=run, extra_positionals="values")


def run(args: argparse.Namespace) -> int:
    """Validate the message, wait for subscribers if asked, publish."""
    from rclpy.duration import Duration
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    from icub_pmp.cli.session import cli_node, spin_until
    from icub_pmp.cli.yaml_values import full_name, interface_name, parse_values
    from icub_pmp.ros.msg_types import get_interface, set_message_fields

    if not (math.isfinite(args.rate) and args.rate > 0):
        raise ValueError(f"--rate must be a finite rate > 0 Hz, got {args.rate}")
    if args.times < 0:
        raise ValueError(f"--times must be >= 0, got {args.times}")
    if args.qos_depth < 1:
        raise ValueError(f"--qos-depth must be >= 1, got {args.qos_depth}")
    count = 1 if args.once else args.times
    wait_n = args.wait_matching_subscriptions
    if wait_n is None:
        wait_n = 1 if count else 0
    if wait_n < 0:
        raise ValueError(f"--wait-matching-subscriptions must be >= 0, got {wait_n}")
    topic = full_name(args.topic)
    msg_type = get_interface(interface_name(args.type, "msg"))
    if len(args.values) > 1:
        raise ValueError(f"expected one VALUES argument, got {len(args.values)}: "
                         f"{args.values} (quote the YAML)")
    msg = set_message_fields(msg_type(), parse_values(args.values[0] if args.values else "{}"))
    qos = QoSProfile(
        depth=args.qos_depth,
        reliability=ReliabilityPolicy.RELIABLE if args.qos_reliability == "reliable"
        else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if args.qos_durability == "transient_local"
        else DurabilityPolicy.VOLATILE)
    with cli_node("icub_pub") as (node, executor):
        pub = node.create_publisher(msg_type, topic, qos)
        if wait_n and not spin_until(executor, lambda: pub.get_subscription_count() >= wait_n,
                                     args.timeout):
            raise TimeoutError(_not_matched(node, topic, wait_n, pub.get_subscription_count(),
                                            args.timeout))
        sent = 0
        period = 1.0 / args.rate
        try:
            while not count or sent < count:
                pub.publish(msg)
                sent += 1
                if args.print_every and (sent - 1) % args.print_every == 0:
                    print(f"publishing #{sent}: {msg!r}", flush=True)
                if count and sent >= count:
                    break
                spin_until(executor, lambda: False, period)
        finally:
            if qos.reliability == ReliabilityPolicy.RELIABLE and sent:
                pub.wait_for_all_acked(Duration(seconds=5.0))  # delivered before we go
            spin_until(executor, lambda: False, 0.1)
    return 0


def _not_matched(node, topic: str, wanted: int, matched: int, timeout: float) -> str:
    """Why ``wanted`` subscribers of ``topic`` were not matched (in the graph or not)."""
    known = node.count_subscribers(topic) - matched
    if known > 0:
        return (f"topic {topic}: {known} subscriber(s) exist in the graph but {matched} of "
                f"{wanted} were matched after {timeout:g} s (DDS discovery is slow on a "
                "loaded machine, or the QoS is incompatible: retry, give a longer --timeout "
                "or check --qos-reliability/--qos-durability)")
    return (f"topic {topic}: {matched} of {wanted} subscriber(s) after {timeout:g} s: no node "
            "subscribes to it (give -w 0 to publish anyway)")
