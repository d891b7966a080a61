"""``icub send-goal ACTION [TYPE] [VALUES]``: send an action goal and wait for its result
(what ``ros2 action send_goal`` does).

    icub send-goal /pmp/reach_action icub_interfaces/action/Reach \\
        "{hands: [right], right_target: {pose: {position: {x: -0.3, y: 0.15, z: 0.05}}}}" -f
    icub send-goal /cartesian/go_to_pose_action \\
        "{chain: right_arm, target: {pose: {position: {x: -0.3, y: 0.15, z: 0.05}}}}"
    icub send-goal /impedance_controller/follow_joint_trajectory "{trajectory: {joint_names: \\
        [r_elbow], points: [{positions: [1.2], time_from_start: {sec: 2}}]}}"

VALUES is the goal in ros2cli's YAML syntax (fields not named keep their defaults); the type is
read from the graph when it is not given. ``--feedback`` prints every feedback message. Ctrl-C
cancels the goal. Exit status: 0 when the goal SUCCEEDED, 1 when it was rejected, aborted or
canceled (the status and the result are printed in every case).
"""

from __future__ import annotations

import argparse
import sys

import yaml

from icub_pmp.cli.defaults import DISCOVERY_TIMEOUT

__all__ = ["register", "run", "STATUS_NAMES"]

#: action_msgs/GoalStatus codes
STATUS_NAMES = {0: "UNKNOWN", 1: "ACCEPTED", 2: "EXECUTING", 3: "CANCELING", 4: "SUCCEEDED",
                5: "CANCELED", 6: "ABORTED"}


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``send-goal`` subcommand."""
    p = sub.add_parser(
        "send-goal", help="send an action goal and wait for the result (ros2 action send_goal)",
        description=__doc__.split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("action", help="action name, e.g. /pmp/reach_action")
    p.add_argument("args", nargs="*", metavar="[TYPE] [VALUES]",
                   help="action type (pkg/action/Type; default: from the graph) and the goal "
                        "in YAML (default: {})")
    p.add_argument("-f", "--feedback", action="store_true", help="print the feedback")
    p.add_argument("--timeout", type=float, default=DISCOVERY_TIMEOUT,
                   help=f"wait this long for the server [s] (default {DISCOVERY_TIMEOUT:g})")
    p.add_argument("--result-timeout", type=float, default=0.0,
                   help="give up waiting for the result after this long [s] (default: wait)")
    p.set_defaults(func=run, extra_positionals="args")


def _dump(msg: object) -> str:
    from icub_pmp.ros.msg_types import message_to_dict

    text = yaml.safe_dump(message_to_dict(msg), sort_keys=False, width=100)
    return "".join(f"    {line}\n" for line in text.splitlines())


def run(args: argparse.Namespace) -> int:
    """Validate the goal, wait for the server, send, print feedback and the result."""
    from rclpy.action import ActionClient

    from icub_pmp.cli.session import cli_node, connect_typed, spin_until, typed_values

    typed = typed_values(args.action, args.args, "action")
    action = typed.name
    with cli_node("icub_send_goal") as (node, executor):
        print("Waiting for an action server to become available...", flush=True)
        client = connect_typed(node, executor, typed,
                               lambda act: ActionClient(node, act, action), args.timeout)
        goal = typed.message
        print(f"Sending goal:\n{_dump(goal)}", flush=True)

        def on_feedback(msg) -> None:
            print(f"Feedback:\n{_dump(msg.feedback)}", flush=True)

        sent = client.send_goal_async(goal, feedback_callback=on_feedback if args.feedback
                                      else None)
        if not spin_until(executor, sent.done, args.timeout):
            raise TimeoutError(f"action {action}: the goal was not acknowledged within "
                               f"{args.timeout:g} s")
        handle = sent.result()
        if not handle.accepted:
            print("Goal was rejected.", flush=True)
            return 1
        print(f"Goal accepted with ID: {bytes(handle.goal_id.uuid).hex()}\n", flush=True)
        result = handle.get_result_async()
        try:
            if not spin_until(executor, result.done, args.result_timeout):
                handle.cancel_goal_async()
                spin_until(executor, result.done, 10.0)
                raise TimeoutError(f"action {action}: no result within "
                                   f"{args.result_timeout:g} s (goal canceled)")
        except KeyboardInterrupt:
            print("Canceling the goal...", file=sys.stderr, flush=True)
            handle.cancel_goal_async()
            spin_until(executor, result.done, 10.0)
            if not result.done():
                return 130
        res = result.result()
    status = STATUS_NAMES.get(res.status, str(res.status))
    print(f"Result:\n{_dump(res.result)}", flush=True)
    print(f"Goal finished with status: {status}", flush=True)
    return 0 if status == "SUCCEEDED" else 1
