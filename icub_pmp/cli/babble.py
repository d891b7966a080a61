"""``icub babble``: start motor babbling on the body_schema node and follow it to the end.

    icub babble --arm right --samples 10000          # progress bar until the budget is reached
    icub babble --arm left --samples 200 --torso --name left_torso
    icub babble --stop                               # stop a run (the dataset is saved)

Calls /body_schema/start_babbling, then shows /body_schema/progress (samples, visible
fraction, rates) until the run ends; Ctrl-C stops the run (the samples so far are saved).
Prints the dataset path; exits 1 if the run did not reach its budget.
"""

from __future__ import annotations

import argparse
import sys

from icub_pmp.cli.defaults import DISCOVERY_TIMEOUT
from icub_pmp.errors import InvalidInput

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``babble`` subcommand."""
    p = sub.add_parser("babble", help="motor babbling for the learned body schema "
                                      "(/body_schema/start_babbling)",
                       description="Babble an arm, the hand's marker seen by both cameras; "
                                   "the dataset is saved by the body_schema node.")
    p.add_argument("--arm", default="", help="left | right (default: the node's parameter)")
    p.add_argument("--samples", type=int, default=0,
                   help="sample budget (default: the node's parameter)")
    p.add_argument("--torso", action="store_true", help="babble torso + arm (10 joints)")
    p.add_argument("--name", default="", help="dataset file name (in the node's data_dir)")
    p.add_argument("--stop", action="store_true", help="stop the running babbling")
    p.add_argument("--timeout", type=float, default=DISCOVERY_TIMEOUT,
                   help="wait this long for the body_schema node [s]")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Start (or stop) babbling and show its progress until it ends."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_srvs.srv import Trigger

    from icub_interfaces.msg import BabblingProgress
    from icub_interfaces.srv import StartBabbling
    from icub_pmp.cli.progress import ProgressLine
    from icub_pmp.cli.session import cli_node, spin_until, spin_until_ready

    if args.samples < 0:
        raise InvalidInput(f"--samples: expected a budget >= 0, got {args.samples}")
    with cli_node("icub_babble") as (node, executor):
        stop = node.create_client(Trigger, "/body_schema/stop_babbling")
        if args.stop:
            spin_until_ready(node, executor, stop.service_is_ready, args.timeout,
                             "/body_schema/stop_babbling", "service", "body_schema")
            future = stop.call_async(Trigger.Request())
            spin_until(executor, future.done, 30.0)
            print(future.result().message)
            return 0 if future.result().success else 1
        start = node.create_client(StartBabbling, "/body_schema/start_babbling")
        spin_until_ready(node, executor, start.service_is_ready, args.timeout,
                         "/body_schema/start_babbling", "service", "body_schema")
        latest: list = []
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
        node.create_subscription(BabblingProgress, "/body_schema/progress", latest.append, qos)
        future = start.call_async(StartBabbling.Request(
            arm=args.arm, samples=args.samples, use_torso=args.torso, dataset_name=args.name))
        if not spin_until(executor, future.done, 60.0):
            raise TimeoutError("/body_schema/start_babbling gave no answer")
        res = future.result()
        if not res.success:
            print(f"icub: error: {res.message}", file=sys.stderr)
            return 1
        print(res.message, file=sys.stderr)
        bar = ProgressLine(sys.stderr)
        started = [False]

        def ended() -> bool:
            if not latest:
                return False
            m = latest[-1]
            if m.dataset_path != res.dataset_path:
                return False
            started[0] = started[0] or m.active
            bar.show(m.samples / max(m.budget, 1),
                     f"{m.samples}/{m.budget} samples, {m.dropped} dropped, visible "
                     f"{m.visible_fraction * 100:.0f} %, {m.rate_wall:.2f}/s wall, "
                     f"{m.rate_sim:.2f}/s sim")
            return started[0] and not m.active
        try:
            spin_until(executor, ended, 0.0)
        except KeyboardInterrupt:
            bar.done()
            print("icub: stopping the babbling (the samples so far are saved)", file=sys.stderr)
            f = stop.call_async(Trigger.Request())
            spin_until(executor, f.done, 10.0)
            spin_until(executor, lambda: bool(latest) and not latest[-1].active, 30.0)
        bar.done()
        last = latest[-1]
    print(f"message: {last.message}")
    print(f"samples: {last.samples} of {last.budget} ({last.dropped} dropped, visible "
          f"{last.visible_fraction * 100:.0f} %)")
    print(f"rate: {last.rate_sim:.3f} samples per simulated s, {last.rate_wall:.3f} per wall s")
    print(f"dataset: {last.dataset_path}")
    return 0 if last.samples >= last.budget else 1
