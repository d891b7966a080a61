"""``icub reach``: send a PMP reach goal and print the answer.

    icub reach right=-0.30,0.15,0.05                       # executes, waits, prints the error
    icub reach left=-0.3,-0.1,0.1 right=-0.3,0.1,0.1 --torso --tau 1.5
    icub reach right=-0.3,0.15,0.05,1,0,0,0 --simulate     # with orientation (qw,qx,qy,qz)
    icub reach right=-0.30,0.15,0.05 --no-wait             # send and return (not monitored)

By default the goal goes to the ``/pmp/reach_action`` action: a progress bar shows the phase
and the hands' measured distance to their targets, and the answer is the arrival error
measured on the robot (exit 0 only when every hand arrived within the tolerance). Ctrl-C
cancels the goal (the arms hold where they are). ``--simulate`` (mental simulation) and
``--no-wait`` call the ``/pmp/reach`` service instead. Arguments are checked before anything
is sent: a NaN, an unknown hand or a negative tau exits with a one-line error and no request.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass, field

from icub_pmp.cli.defaults import DISCOVERY_TIMEOUT
from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS

__all__ = ["register", "run", "ReachArgs", "parse_reach_args"]


@dataclass(frozen=True)
class ReachArgs:
    """The parsed `icub reach` arguments: per hand (x, y, z) [m] and optional quaternion
    (w, x, y, z)."""

    positions: dict[str, tuple[float, float, float]]
    orientations: dict[str, tuple[float, float, float, float]] = field(default_factory=dict)
    frame: str = "root_link"
    use_torso: bool = False
    tau: float = 0.0
    simulate_only: bool = False


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``reach`` subcommand."""
    p = sub.add_parser(
        "reach",
        help="send a PMP reach goal (/pmp/reach_action) and wait for the arrival",
        description="HAND=X,Y,Z[,QW,QX,QY,QZ] per hand (left, right); positions in metres.",
    )
    p.add_argument("targets", nargs="+", metavar="HAND=X,Y,Z[,QW,QX,QY,QZ]")
    p.add_argument("--frame", default="root_link", help="frame of the targets")
    p.add_argument("--torso", action="store_true", help="let the torso take part")
    p.add_argument("--tau", type=float, default=0.0,
                   help="time-base-generator duration [s] (0 = planner default)")
    p.add_argument("--simulate", action="store_true",
                   help="mental simulation: plan only, do not execute (service)")
    p.add_argument("--no-wait", action="store_true",
                   help="send the plan and return without watching the execution (service)")
    p.add_argument("--tolerance", type=float, default=0.0,
                   help="arrival tolerance [m] measured on the robot (0 = planner default, "
                        "1 cm)")
    p.add_argument("--service", default="/pmp/reach")
    p.add_argument("--action", default="/pmp/reach_action")
    p.add_argument("--timeout", type=float, default=DISCOVERY_TIMEOUT,
                   help="wait this long for the planner to be discovered [s] (default "
                        f"{DISCOVERY_TIMEOUT:g})")
    p.set_defaults(func=run)


def parse_reach_args(
    targets: list[str], frame: str = "root_link", use_torso: bool = False,
    tau: float = 0.0, simulate_only: bool = False,
) -> ReachArgs:
    """Validate the command-line goal (raises InvalidInput / UnknownName)."""
    if not math.isfinite(tau) or tau < 0:
        raise InvalidInput(f"--tau must be a finite duration >= 0 s, got {tau}")
    positions: dict[str, tuple[float, float, float]] = {}
    orientations: dict[str, tuple[float, float, float, float]] = {}
    for t in targets:
        hand, sep, values = t.partition("=")
        if not sep:
            raise InvalidInput(f"target {t!r}: expected HAND=X,Y,Z[,QW,QX,QY,QZ]")
        if hand not in HANDS:
            raise UnknownName("hand", hand, HANDS)
        if hand in positions:
            raise InvalidInput(f"hand {hand!r} given twice")
        try:
            nums = [float(v) for v in values.split(",")]
        except ValueError:
            raise InvalidInput(f"target {t!r}: values must be numbers") from None
        if len(nums) not in (3, 7):
            raise InvalidInput(f"target {t!r}: expected 3 (position) or 7 values, got {len(nums)}")
        if not all(math.isfinite(v) for v in nums):
            raise InvalidInput(f"target {t!r}: contains NaN or infinite values")
        positions[hand] = (nums[0], nums[1], nums[2])
        if len(nums) == 7:
            q = nums[3:]
            n = math.sqrt(sum(v * v for v in q))
            if n < 1e-9:
                raise InvalidInput(f"target {t!r}: zero quaternion")
            orientations[hand] = (q[0] / n, q[1] / n, q[2] / n, q[3] / n)
    if orientations and set(orientations) != set(positions):
        raise InvalidInput("give an orientation for every hand or for none")
    return ReachArgs(positions, orientations, frame, use_torso, tau, simulate_only)


def build_request(goal: ReachArgs):  # noqa: ANN201 - ROS type imported lazily
    """The icub_interfaces/srv/Reach request for ``goal``."""
    from icub_interfaces.srv import Reach

    req = Reach.Request()
    req.hands = [h for h in HANDS if h in goal.positions]
    req.use_orientation = bool(goal.orientations)
    req.use_torso = goal.use_torso
    req.tau = goal.tau
    req.simulate_only = goal.simulate_only
    for hand, pos in goal.positions.items():
        target = req.left_target if hand == "left" else req.right_target
        target.header.frame_id = goal.frame
        target.pose.position.x, target.pose.position.y, target.pose.position.z = pos
        if hand in goal.orientations:
            w, x, y, z = goal.orientations[hand]
            o = target.pose.orientation
            o.w, o.x, o.y, o.z = w, x, y, z
    return req


def build_action_goal(goal: ReachArgs, tolerance: float = 0.0):  # noqa: ANN201
    """The icub_interfaces/action/Reach goal for ``goal``."""
    from icub_interfaces.action import Reach as ReachAction

    req = build_request(goal)
    g = ReachAction.Goal()
    for f in ("hands", "left_target", "right_target", "use_orientation", "use_torso", "tau"):
        setattr(g, f, getattr(req, f))
    g.arrival_tolerance = float(tolerance)
    return g


def run(args: argparse.Namespace) -> int:
    """Validate, send the goal, print the answer; exit 1 unless it succeeded."""
    goal = parse_reach_args(args.targets, args.frame, args.torso, args.tau, args.simulate)
    if not math.isfinite(args.tolerance) or args.tolerance < 0:
        raise InvalidInput(f"--tolerance must be a finite distance >= 0 m, got "
                           f"{args.tolerance}")
    if args.simulate or args.no_wait:
        return _run_service(args, goal)
    return _run_action(args, goal)


def _run_action(args: argparse.Namespace, goal: ReachArgs) -> int:
    from rclpy.action import ActionClient

    from icub_interfaces.action import Reach as ReachAction
    from icub_pmp.cli.progress import ProgressLine
    from icub_pmp.cli.session import cli_node, spin_until, spin_until_ready

    with cli_node("icub_reach") as (node, executor):
        client = ActionClient(node, ReachAction, args.action)
        spin_until_ready(node, executor, client.server_is_ready, args.timeout, args.action,
                         "action", "pmp_planner")
        bar = ProgressLine(sys.stderr)

        def on_feedback(msg) -> None:
            fb = msg.feedback
            errs = "  ".join(f"{h} {e * 1e3:.1f} mm" for h, e in zip(fb.hands, fb.hand_errors))
            bar.show(fb.progress, f"{fb.phase:<9} {errs}  {fb.time_to_go:.1f} s to go")

        sent = client.send_goal_async(build_action_goal(goal, args.tolerance),
                                      feedback_callback=on_feedback)
        if not spin_until(executor, sent.done, args.timeout):
            raise TimeoutError(f"action {args.action}: the goal was not acknowledged")
        handle = sent.result()
        if not handle.accepted:
            raise RuntimeError(f"action {args.action}: goal rejected")
        result = handle.get_result_async()
        try:
            spin_until(executor, result.done, 0.0)
        except KeyboardInterrupt:
            bar.done()
            print("icub: canceling the goal (the arms hold where they are)", file=sys.stderr)
            handle.cancel_goal_async()
            spin_until(executor, result.done, 10.0)
            if not result.done():
                return 130
        bar.done()
        res = result.result().result
    print(f"success: {res.success}")
    print(f"outcome: {res.outcome}")
    print(f"message: {res.message}")
    for k, hand in enumerate(res.hands):
        line = f"{hand}:"
        if k < len(res.arrival_errors):
            line += f" arrival error {res.arrival_errors[k] * 1e3:.1f} mm (measured)"
        if k < len(res.planned_residuals):
            line += f", planned residual {res.planned_residuals[k] * 1e3:.2f} mm"
        print(line)
    if res.tau_used > 0:
        print(f"tau used: {res.tau_used:.2f} s, execution time {res.execution_time:.2f} s "
              "(simulated time)")
    return 0 if res.success else 1


def _run_service(args: argparse.Namespace, goal: ReachArgs) -> int:
    from icub_interfaces.srv import Reach
    from icub_pmp.cli.session import cli_node, spin_until, spin_until_ready

    request = build_request(goal)
    with cli_node("icub_reach") as (node, executor):
        client = node.create_client(Reach, args.service)
        spin_until_ready(node, executor, client.service_is_ready, args.timeout, args.service,
                         "service", "pmp_planner")
        future = client.call_async(request)
        if not spin_until(executor, future.done, max(args.timeout, 60.0)):
            raise TimeoutError(f"service {args.service} gave no answer")
        res = future.result()
    print(f"success: {res.success}")
    print(f"message: {res.message}")
    for hand, r in zip(res.hands, res.residuals):
        print(f"residual {hand}: {r * 1000:.2f} mm")
    n = len(res.trajectory.points)
    if n:
        last = res.trajectory.points[-1].time_from_start
        print(f"trajectory: {n} points over {last.sec + last.nanosec * 1e-9:.3f} s, "
              f"{len(res.trajectory.joint_names)} joints")
    return 0 if res.success else 1
