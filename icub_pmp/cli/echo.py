"""``icub echo TOPIC``: print the messages of a topic as YAML documents."""

from __future__ import annotations

import argparse
import sys

import yaml

from icub_pmp.cli.defaults import DISCOVERY_TIMEOUT
from icub_pmp.cli.session import cli_node, not_ready_reason, spin_until, wait_for_topic_type
from icub_pmp.ros.msg_types import get_interface, message_to_dict
from icub_pmp.ros.qos import matching_qos

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``echo`` subcommand."""
    p = sub.add_parser("echo", help="print messages of a topic")
    p.add_argument("topic")
    p.add_argument("type", nargs="?", help="message type (default: from the graph)")
    p.add_argument("--count", "-n", type=int, default=0, help="stop after N messages")
    p.add_argument("--timeout", type=float, default=DISCOVERY_TIMEOUT,
                   help="give up if the topic has no publisher / no message for this long [s] "
                        f"(default {DISCOVERY_TIMEOUT:g})")
    p.add_argument("--full-arrays", action="store_true", help="do not cut long arrays")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Subscribe and print until ``--count`` messages (or Ctrl-C)."""
    if args.count < 0:
        raise ValueError(f"--count must be >= 0, got {args.count}")
    topic = args.topic if args.topic.startswith("/") else "/" + args.topic
    with cli_node("icub_echo") as (node, executor):
        tname = args.type or wait_for_topic_type(node, executor, topic, args.timeout)
        if tname is None:
            raise TimeoutError(not_ready_reason(node, topic, "topic", args.timeout,
                                                "its publisher"))
        msg_type = get_interface(tname)
        received = [0]
        cut = None if args.full_arrays else 32

        def cb(msg: object) -> None:
            if args.count and received[0] >= args.count:
                return
            received[0] += 1
            sys.stdout.write(yaml.safe_dump(message_to_dict(msg, cut), sort_keys=False))
            sys.stdout.write("---\n")
            sys.stdout.flush()

        node.create_subscription(msg_type, topic, cb, matching_qos(node, topic))
        if args.count:
            ok = spin_until(executor, lambda: received[0] >= args.count, args.timeout)
            if not ok and received[0] == 0:
                raise TimeoutError(not_ready_reason(node, topic, "topic", args.timeout,
                                                    "its publisher"))
            if not ok:
                raise TimeoutError(
                    f"got {received[0]} of {args.count} messages on {topic} in {args.timeout} s"
                )
        else:
            spin_until(executor, lambda: False, 0)
    return 0
