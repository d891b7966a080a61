"""The ``icub`` command line: the everyday ros2cli jobs this machine lacks (rclpy only).

    icub graph                     nodes, topics with types, services with types
    icub echo TOPIC [--count N]    print messages
    icub hz TOPIC                  measure a topic's rate
    icub pub TOPIC TYPE [VALUES]   publish a message (ros2 topic pub)
    icub call SERVICE [TYPE] [VALUES]       call a service (ros2 service call)
    icub send-goal ACTION [TYPE] [VALUES]   send an action goal (ros2 action send_goal)
    icub param list|get|set|dump   node parameters (ros2 param)
    icub reach right=X,Y,Z ...     send a PMP reach goal to /pmp/reach_action
    icub peri check|allocate|empty|plan-pair ...   peripersonal space queries
    icub bag record|play|info|convert|repair   MCAP bags (rosbag2 layout)
    icub babble --arm right --samples N   motor babbling for the learned body schema
    icub calibrate-eyes DATASET    fit the eye cameras to the hand marker seen while babbling

VALUES use ros2cli's YAML syntax, e.g. ``"{target: box, wrench: {force: {z: 1.0}}}"``.

Each subcommand lives in its own module (``send-goal`` in ``send_goal``) exposing
``register(subparsers)``; its parser sets
``func(args) -> int``. Errors print one line ``icub: error: ...`` and exit non-zero.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from typing import Sequence

from icub_pmp.errors import IcubPmpError

__all__ = ["main", "build_parser"]

#: subcommand modules of icub_pmp.cli, in the order of ``icub --help``
SUBCOMMANDS = ("graph", "echo", "hz", "pub", "call", "send_goal", "param", "reach", "peri",
               "bag", "babble", "calibrate_eyes", "posture")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every installed subcommand registered."""
    parser = argparse.ArgumentParser(
        prog="icub", description="Command line of the icub_pmp ROS 2 node graph."
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMANDS:
        try:
            module = importlib.import_module(f"icub_pmp.cli.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"icub_pmp.cli.{name}":
                continue  # subcommand not installed in this tree
            raise
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``icub`` console script."""
    parser = build_parser()
    # positionals after an option (`icub send-goal ACTION -f VALUES`): argparse stops its
    # list at the option; verbs that allow it name the list in `extra_positionals`
    args, extra = parser.parse_known_args(argv)
    if extra:
        dest = getattr(args, "extra_positionals", None)
        if dest is None or any(e.startswith("-") and not _is_number(e) for e in extra):
            parser.error(f"unrecognized arguments: {' '.join(extra)}")
        setattr(args, dest, [*getattr(args, dest), *extra])
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:  # the reader went away (icub ... | head): not an error
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - nothing more reaches the pipe
        return 0
    except (IcubPmpError, TimeoutError, ValueError, OSError) as exc:
        print(f"icub: error: {exc}", file=sys.stderr)
        return 1
    except RuntimeError as exc:  # rclpy's RCLError: the ROS middleware refused to start
        if type(exc).__name__ != "RCLError":
            raise
        text = " ".join(str(exc).split())
        print(f"icub: error: ROS could not start a node: {text}", file=sys.stderr)
        return 1


def _is_number(text: str) -> bool:
    """A number, or comma-separated numbers (a point ``-0.3,0.1,0``), not an option."""
    try:
        for part in text.split(","):
            float(part)
    except ValueError:
        return False
    return True


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
