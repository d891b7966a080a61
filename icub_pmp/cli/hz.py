"""``icub hz TOPIC``: the receive rate of a topic (messages are not deserialised)."""

from __future__ import annotations

import argparse
import time

import numpy as np

from icub_pmp.cli.defaults import DISCOVERY_TIMEOUT
from icub_pmp.cli.session import cli_node, not_ready_reason, spin_until, wait_for_topic_type
from icub_pmp.ros.msg_types import get_interface
from icub_pmp.ros.qos import matching_qos

__all__ = ["register", "run", "rate_statistics"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``hz`` subcommand."""
    p = sub.add_parser("hz", help="measure the rate of a topic")
    p.add_argument("topic")
    p.add_argument("--window", "-w", type=int, default=10000, help="last N intervals")
    p.add_argument("--duration", type=float, default=0.0,
                   help="measure this long [s], print once and exit (default: until Ctrl-C)")
    p.add_argument("--timeout", type=float, default=DISCOVERY_TIMEOUT,
                   help=f"wait for a publisher [s] (default {DISCOVERY_TIMEOUT:g})")
    p.set_defaults(func=run)


def rate_statistics(stamps: list[float]) -> dict[str, float]:
    """Rate [Hz] and interval statistics [s] of receive times ``stamps`` (seconds)."""
    dt = np.diff(np.asarray(stamps, dtype=float))
    if dt.size == 0:
        return {"rate": 0.0, "min": 0.0, "max": 0.0, "std": 0.0, "n": 0}
    return {
        "rate": float(1.0 / dt.mean()),
        "min": float(dt.min()),
        "max": float(dt.max()),
        "std": float(dt.std()),
        "n": int(dt.size),
    }


def _report(topic: str, s: dict[str, float]) -> None:
    print(
        f"{topic}: average rate: {s['rate']:.3f} Hz\n"
        f"  min: {s['min']:.6f}s max: {s['max']:.6f}s std dev: {s['std']:.6f}s window: {s['n']}",
        flush=True,
    )


def run(args: argparse.Namespace) -> int:
    """Measure and print the rate (once after ``--duration``, or every second)."""
    if args.window < 2:
        raise ValueError(f"--window must be >= 2, got {args.window}")
    if args.duration < 0:
        raise ValueError(f"--duration must be >= 0, got {args.duration}")
    topic = args.topic if args.topic.startswith("/") else "/" + args.topic
    with cli_node("icub_hz") as (node, executor):
        tname = wait_for_topic_type(node, executor, topic, args.timeout)
        if tname is None:
            raise TimeoutError(not_ready_reason(node, topic, "topic", args.timeout,
                                                "its publisher"))
        stamps: list[float] = []

        def cb(_raw: bytes) -> None:
            stamps.append(time.monotonic())
            if len(stamps) > args.window + 1:
                del stamps[0]

        node.create_subscription(
            get_interface(tname), topic, cb, matching_qos(node, topic, depth=1000), raw=True
        )
        if args.duration > 0:
            spin_until(executor, lambda: False, args.duration)
            s = rate_statistics(stamps)
            if s["n"] == 0:
                raise TimeoutError(f"no messages on {topic} in {args.duration} s")
            _report(topic, s)
            return 0
        while True:
            spin_until(executor, lambda: False, 1.0)
            if len(stamps) > 1:
                _report(topic, rate_statistics(stamps))
