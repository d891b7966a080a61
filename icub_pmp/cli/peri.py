"""``icub peri check|allocate|empty|plan-pair``: the peripersonal_space node's queries.

    icub peri check -0.30,0.15,0.05 -0.30,-0.15,0.05       # which arm reaches which point
    icub peri check -0.30,0.15,0.05 --arm right
    icub peri allocate -0.3,-0.25,0.0 -0.3,0.02,0.0 -0.3,0.25,0.0   # which arm takes what
    icub peri empty -0.3,0.02,0.0 --arm left [--radius 0.1]         # a free spot in between
    icub peri plan-pair left=-0.28,0.05,0.05 right=-0.28,-0.05,0.05 # collide? parallel/serial

Points are X,Y,Z in root_link [m]. The answer is printed as YAML (``response: {...}``; the
imagined hand paths of plan-pair only with ``--paths``); the exit status is 1 when the node
answered success=false (its message says why).
"""

from __future__ import annotations

import argparse
import math
import sys

import yaml

from icub_pmp.cli.defaults import DISCOVERY_TIMEOUT
from icub_pmp.errors import InvalidInput

__all__ = ["register", "run", "parse_point"]


def parse_point(text: str, what: str = "point") -> tuple[float, float, float]:
    """``X,Y,Z`` [m] -> a finite 3-tuple (InvalidInput naming ``what`` otherwise)."""
    try:
        v = [float(x) for x in text.split(",")]
    except ValueError:
        raise InvalidInput(f"{what} {text!r}: expected X,Y,Z numbers [m]") from None
    if len(v) != 3 or not all(math.isfinite(x) for x in v):
        raise InvalidInput(f"{what} {text!r}: expected three finite numbers X,Y,Z [m]")
    return v[0], v[1], v[2]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``peri`` subcommand."""
    p = sub.add_parser("peri", help="peripersonal space: reach check, allocation, empty area, "
                                    "imagined pair plans",
                       description=__doc__.split("\n\n", 1)[1],
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    verbs = p.add_subparsers(dest="peri_command", metavar="{check,allocate,empty,plan-pair}")
    p.set_defaults(func=lambda _a: (p.print_help(), 2)[1])
    c = verbs.add_parser("check", help="which arm reaches these points")
    c.add_argument("points", nargs="*", metavar="X,Y,Z")
    c.add_argument("--arm", choices=("left", "right"), default="")
    a = verbs.add_parser("allocate", help="which arm acts on which object, in which round")
    a.add_argument("points", nargs="*", metavar="X,Y,Z")
    e = verbs.add_parser("empty", help="an empty area of the shared workspace")
    e.add_argument("points", nargs="*", metavar="X,Y,Z", help="the objects on the table")
    e.add_argument("--arm", choices=("left", "right"), default="left")
    e.add_argument("--radius", type=float, default=0.0,
                   help="free radius [m] (default: the gripper width)")
    pp = verbs.add_parser("plan-pair", help="imagine both reaches: collide? parallel/serial")
    pp.add_argument("targets", nargs=2, metavar="HAND=X,Y,Z")
    pp.add_argument("--from-current", action="store_true",
                    help="start from the measured posture (default: rest)")
    pp.add_argument("--first", choices=("left", "right"), default="left")
    pp.add_argument("--paths", action="store_true", help="print the imagined hand paths")
    for q in (c, a, e, pp):
        q.add_argument("--timeout", type=float, default=DISCOVERY_TIMEOUT,
                       help=f"wait this long for the node [s] (default {DISCOVERY_TIMEOUT:g})")
        # points may start with '-' (-0.3,0.1,0): main passes them on as extra positionals
        q.set_defaults(func=run, extra_positionals="points" if q is not pp else "targets")


def _request(args: argparse.Namespace):  # noqa: ANN202 - ROS types imported lazily
    from geometry_msgs.msg import Point

    from icub_interfaces.srv import AllocateObjects, CheckReach, FindEmptyArea, PlanPair

    pts = [Point(x=x, y=y, z=z) for x, y, z in
           (parse_point(t) for t in getattr(args, "points", []))]
    if not pts and args.peri_command in ("check", "allocate"):
        raise InvalidInput(f"peri {args.peri_command}: give at least one point X,Y,Z [m]")
    if args.peri_command == "check":
        return "/peripersonal/check_reach", CheckReach, CheckReach.Request(points=pts,
                                                                           arm=args.arm)
    if args.peri_command == "allocate":
        return "/peripersonal/allocate", AllocateObjects, AllocateObjects.Request(objects=pts)
    if args.peri_command == "empty":
        return "/peripersonal/empty_area", FindEmptyArea, FindEmptyArea.Request(
            objects=pts, arm=args.arm, radius=args.radius)
    targets = {}
    for t in args.targets:
        hand, _, xyz = t.partition("=")
        if hand not in ("left", "right") or not xyz:
            raise InvalidInput(f"target {t!r}: expected left=X,Y,Z or right=X,Y,Z")
        targets[hand] = Point(**dict(zip("xyz", parse_point(xyz, f"{hand} target"))))
    if set(targets) != {"left", "right"}:
        raise InvalidInput("plan-pair needs one target per hand: left=X,Y,Z right=X,Y,Z")
    return "/peripersonal/plan_pair", PlanPair, PlanPair.Request(
        left_target=targets["left"], right_target=targets["right"],
        from_current=args.from_current, first=args.first)


def run(args: argparse.Namespace) -> int:
    """Build the request (checked before anything is sent), call once, print the answer."""
    from icub_pmp.cli.session import TypedValues, cli_node, connect_typed, spin_until
    from icub_pmp.ros.msg_types import message_to_dict

    name, srv, request = _request(args)
    typed = TypedValues(name, "service", {}, interface=srv, message=request)
    with cli_node("icub_peri") as (node, executor):
        client = connect_typed(node, executor, typed, lambda s: node.create_client(s, name),
                               args.timeout)
        future = client.call_async(request)
        if not spin_until(executor, future.done, 120.0):
            raise TimeoutError(f"service {name} gave no answer within 120 s")
        response = future.result()
    out = message_to_dict(response, None)
    if not getattr(args, "paths", False):
        for k in ("left_path", "right_path"):
            if k in out:
                out[k] = f"({len(out[k])} points; --paths prints them)"
    sys.stdout.write(yaml.safe_dump({"response": out}, sort_keys=False))
    return 0 if response.success else 1
