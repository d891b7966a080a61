"""``icub reach``: send a PMP reach goal and print the answer.

    icub reach right=-0.30,0.15,0.05                       # executes, waits, prints the error
    icub reach left=-0.3,-0.1,0.1 right=-0.3,0.1,0.1 --torso --tau 1.5
    icub reach right=-0.3,0.15,0.05,1,0,0,0 --simulate     # with orientation (qw,qx,qy,qz)
    icub reach right=-0.30,0.15,0.05 --no-wait             # send and return (not monitored)
    icub reach --hold=-0.25,0.0,0.15 --torso --simulate    # carry the object between the hands
    icub reach right=-0.28,0.10,0.20 --obstacle sphere:-0.29,0.15,0.11,0.03 --clearance 0.02
    icub reach right=-0.28,0.10,0.20 --force 0,0,-10 --torque-limit r_elbow=0.3 --simulate
    icub reach right=-0.20,0.05,0.30 --trunk compliant --freeze r_wrist_prosup --simulate

By default the goal goes to the ``/pmp/reach_action`` action: a progress bar shows the phase
and the hands' measured distance to their targets, and the answer is the arrival error
measured on the robot (exit 0 only when every hand arrived within the tolerance). Ctrl-C
cancels the goal (the arms hold where they are). ``--simulate`` (mental simulation) and
``--no-wait`` call the ``/pmp/reach`` service instead. Arguments are checked before anything
is sent: a NaN, an unknown hand or a negative tau exits with a one-line error and no request.

The PMP fields of the request (icub_interfaces/srv/Reach.srv documents each):
``--hold X,Y,Z`` carries the object held between both hands to that goal (Sect. 3.2; its
reference point starts at ``--hold-from``, default the hands' midpoint); ``--obstacle``
(repeatable) ``sphere:X,Y,Z,R``, ``capsule:X1,Y1,Z1,X2,Y2,Z2,R`` (between two cap centres) or
``box:X,Y,Z,SX,SY,SZ`` (centre and edge lengths, axes of --frame), with ``--clearance M``;
``--force [HAND=]FX,FY,FZ`` (the force the hand exerts at its target [N]) and
``--torque-limit JOINT=NM`` (repeatable); ``--trunk stiff|compliant|FACTOR`` (implies
``--torso``), ``--freeze JOINT`` and ``--scale JOINT=FACTOR`` (admittances, repeatable).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from dataclasses import dataclass, field

from icub_pmp.cli.defaults import DISCOVERY_TIMEOUT
from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS

__all__ = ["register", "run", "ReachArgs", "parse_reach_args"]


_EXAMPLES = """examples (positions in root_link [m]: x backward, y right, z up):
  icub reach right=-0.30,0.15,0.05
  icub reach left=-0.3,-0.1,0.1 right=-0.3,0.1,0.1 --torso --tau 1.5
  icub reach --hold=-0.25,0.0,0.15 --torso --simulate     carry the held object (both hands)
  icub reach right=-0.28,0.10,0.20 --obstacle sphere:-0.29,0.15,0.11,0.03 --clearance 0.02
  icub reach right=-0.28,0.10,0.20 --obstacle box:-0.3,0.15,0.1,0.05,0.05,0.05 --simulate
  icub reach right=-0.28,0.10,0.20 --force 0,0,-10 --torque-limit r_elbow=0.3 --simulate
  icub reach right=-0.20,0.05,0.30 --trunk compliant --freeze r_wrist_prosup --simulate
  icub reach right=-0.20,0.05,0.30 --trunk stiff --scale r_shoulder_yaw=2 --simulate
"""


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
    extras: dict = field(default_factory=dict)  # the PMP fields: request field -> value


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``reach`` subcommand."""
    p = sub.add_parser(
        "reach",
        help="send a PMP reach goal (/pmp/reach_action) and wait for the arrival",
        description="HAND=X,Y,Z[,QW,QX,QY,QZ] per hand (left, right); positions in metres.",
        epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("targets", nargs="*", metavar="HAND=X,Y,Z[,QW,QX,QY,QZ]")
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
    p.add_argument("--hold", metavar="X,Y,Z",
                   help="carry the object held between both hands to this goal [m] (no hand "
                        "targets then; write --hold=-0.25,0,0.15 when X is negative)")
    p.add_argument("--hold-from", metavar="X,Y,Z",
                   help="the held object's reference point now [m] (default: the hands' "
                        "midpoint; the grasps are where the hands are)")
    p.add_argument("--obstacle", action="append", default=[], metavar="SHAPE:VALUES",
                   help="sphere:X,Y,Z,R | capsule:X1,Y1,Z1,X2,Y2,Z2,R | box:X,Y,Z,SX,SY,SZ "
                        "[m] (repeatable; e.g. --obstacle sphere:-0.29,0.15,0.11,0.03)")
    p.add_argument("--clearance", type=float, default=0.0,
                   help="clearance the hands keep from the obstacles [m] (0 = planner default)")
    p.add_argument("--force", action="append", default=[], metavar="[HAND=]FX,FY,FZ",
                   help="force the hand exerts on the world at its target [N] (e.g. 0,0,-10)")
    p.add_argument("--torque-limit", action="append", default=[], metavar="JOINT=NM",
                   help="torque limit of a joint [N m] (repeatable; e.g. r_elbow=0.3)")
    p.add_argument("--trunk", metavar="stiff|compliant|FACTOR",
                   help="trunk admittance: stiff (grounded shoulders), compliant, or a factor "
                        "on the configured one; implies --torso")
    p.add_argument("--freeze", action="append", default=[], metavar="JOINT",
                   help="a joint that must not move (repeatable; e.g. r_wrist_prosup)")
    p.add_argument("--scale", action="append", default=[], metavar="JOINT=FACTOR",
                   help="admittance factor of a joint (repeatable; 0 freezes, > 1 recruits)")
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
    if not targets:
        raise InvalidInput("no target: give HAND=X,Y,Z (or --hold X,Y,Z)")
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
    fill_pmp_fields(req, goal)
    return req


def build_action_goal(goal: ReachArgs, tolerance: float = 0.0):  # noqa: ANN201
    """The icub_interfaces/action/Reach goal for ``goal``."""
    from icub_interfaces.action import Reach as ReachAction

    req = build_request(goal)
    g = ReachAction.Goal()
    for f in g.get_fields_and_field_types():
        if f in req.get_fields_and_field_types():
            setattr(g, f, getattr(req, f))
    g.arrival_tolerance = float(tolerance)
    return g


def run(args: argparse.Namespace) -> int:
    """Validate, send the goal, print the answer; exit 1 unless it succeeded."""
    extras = parse_pmp_args(args)
    if "hold_object" in extras:
        if args.targets:
            raise InvalidInput("--hold: the hands follow the held object; give no HAND=X,Y,Z")
        goal = parse_reach_args(["left=0,0,0", "right=0,0,0"], args.frame,
                                args.torso or "trunk_admittance" in extras, args.tau,
                                args.simulate)
    else:
        goal = parse_reach_args(args.targets, args.frame,
                                args.torso or "trunk_admittance" in extras
                                or "trunk_admittance_scale" in extras, args.tau, args.simulate)
    if "force" in extras:
        extras.update(_hand_forces(extras.pop("force"), tuple(goal.positions)))
    goal = dataclasses.replace(goal, extras=extras)
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
    _print_pmp_answer(res)
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
    _print_pmp_answer(res)
    return 0 if res.success else 1


# ---------------------------------------------------------------------- the PMP fields
_SHAPE_VALUES = {"sphere": 4, "capsule": 7, "box": 6}


def _numbers(flag: str, text: str, n: int | tuple[int, ...]) -> list[float]:
    counts = (n,) if isinstance(n, int) else n
    try:
        nums = [float(v) for v in text.split(",")]
    except ValueError:
        raise InvalidInput(f"{flag} {text!r}: values must be numbers") from None
    if len(nums) not in counts:
        raise InvalidInput(f"{flag} {text!r}: expected {' or '.join(map(str, counts))} values, "
                           f"got {len(nums)}")
    if not all(math.isfinite(v) for v in nums):
        raise InvalidInput(f"{flag} {text!r}: contains NaN or infinite values")
    return nums


def _joint_values(flag: str, items: list[str], joints: tuple[str, ...]) -> dict[str, float]:
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep:
            raise InvalidInput(f"{flag} {item!r}: expected JOINT=VALUE")
        if name not in joints:
            raise InvalidInput(f"{flag}: {UnknownName('joint', name, joints)}")
        v = _numbers(flag, value, 1)[0]
        if v < 0 or (flag == "--torque-limit" and v == 0):
            raise InvalidInput(f"{flag} {item!r}: expected a value "
                               f"{'> 0' if flag == '--torque-limit' else '>= 0'}")
        out[name] = v
    return out


def _obstacle(text: str) -> dict:
    """``SHAPE:VALUES`` -> {type, centre, radius, length, size, axis} (validated)."""
    shape, sep, values = text.partition(":")
    if not sep or shape not in _SHAPE_VALUES:
        raise InvalidInput(f"--obstacle {text!r}: expected sphere:X,Y,Z,R, "
                           f"capsule:X1,Y1,Z1,X2,Y2,Z2,R or box:X,Y,Z,SX,SY,SZ")
    v = _numbers(f"--obstacle {shape}", values, _SHAPE_VALUES[shape])
    if shape == "sphere":
        ob = {"type": shape, "centre": v[:3], "radius": v[3]}
        sizes = [v[3]]
    elif shape == "capsule":
        a, b = v[:3], v[3:6]
        axis = [bi - ai for ai, bi in zip(a, b)]
        length = math.sqrt(sum(c * c for c in axis))
        ob = {"type": shape, "centre": [(ai + bi) / 2 for ai, bi in zip(a, b)],
              "radius": v[6], "length": length, "axis": axis}
        sizes = [v[6], length]
    else:
        ob = {"type": shape, "centre": v[:3], "size": v[3:]}
        sizes = v[3:]
    if min(sizes) <= 0:
        raise InvalidInput(f"--obstacle {text!r}: sizes must be > 0 m")
    return ob


def parse_pmp_args(args: argparse.Namespace) -> dict:
    """The PMP fields of ``icub reach`` (validated, no ROS import): request field -> value
    (``force`` stays a list of ``[HAND=]FX,FY,FZ`` until the hands are known)."""
    from icub_pmp.kinematics.robot_spec import RobotSpec

    joints = RobotSpec.load().actuated_joints
    out: dict = {}
    if args.hold is not None:
        out["hold_object"] = True
        out["object_goal"] = _numbers("--hold", args.hold, 3)
        if args.hold_from is not None:
            out["object_pose"] = _numbers("--hold-from", args.hold_from, 3)
    elif args.hold_from is not None:
        raise InvalidInput("--hold-from needs --hold")
    if args.obstacle:
        out["obstacles"] = [_obstacle(t) for t in args.obstacle]
    if not math.isfinite(args.clearance) or args.clearance < 0:
        raise InvalidInput(f"--clearance must be a finite distance >= 0 m, got {args.clearance}")
    if args.clearance:
        out["obstacle_clearance"] = args.clearance
    if args.force:
        out["force"] = list(args.force)
    limits = _joint_values("--torque-limit", args.torque_limit, joints)
    if limits:
        out["torque_limit_joints"], out["torque_limits"] = list(limits), list(limits.values())
    if args.trunk is not None:
        if args.trunk in ("stiff", "compliant"):
            out["trunk_admittance"] = args.trunk
        else:
            try:
                value = float(args.trunk)
            except ValueError:
                raise InvalidInput(f"--trunk {args.trunk!r}: expected stiff, compliant or a "
                                   f"factor > 0") from None
            if not math.isfinite(value) or value <= 0:
                raise InvalidInput(f"--trunk {args.trunk!r}: expected a finite factor > 0")
            out["trunk_admittance_scale"] = value
    for j in args.freeze:
        if j not in joints:
            raise InvalidInput(f"--freeze: {UnknownName('joint', j, joints)}")
    if args.freeze:
        out["frozen_joints"] = list(args.freeze)
    scales = _joint_values("--scale", args.scale, joints)
    if scales:
        out["admittance_scale_joints"] = list(scales)
        out["admittance_scales"] = list(scales.values())
    return out


def _hand_forces(items: list[str], hands: tuple[str, ...]) -> dict:
    out = {}
    for item in items:
        hand, sep, values = item.rpartition("=")
        if not sep:
            if len(hands) != 1:
                raise InvalidInput(f"--force {item!r}: with two hands, say which: HAND=FX,FY,FZ")
            hand = hands[0]
        if hand not in hands:
            raise InvalidInput(f"--force {item!r}: the {hand} hand has no target")
        if f"{hand}_force" in out:
            raise InvalidInput(f"--force: the {hand} hand's force is given twice")
        out[f"{hand}_force"] = _numbers("--force", values, 3)
    return out


def fill_pmp_fields(req, goal: ReachArgs) -> None:  # noqa: ANN001 - ROS type
    """Copy ``goal.extras`` into a Reach request (or action goal)."""
    from icub_interfaces.msg import Obstacle
    from icub_pmp.kinematics.rotations import matrix_to_quat_wxyz

    def xyz(msg, v) -> None:
        msg.x, msg.y, msg.z = (float(c) for c in v)

    for key, value in goal.extras.items():
        if key in ("object_goal", "object_pose"):
            stamped = getattr(req, key)
            stamped.header.frame_id = goal.frame
            xyz(stamped.pose.position, value)
        elif key.endswith("_force"):
            xyz(getattr(req, key), value)
        elif key == "obstacles":
            msgs = []
            for ob in value:
                m = Obstacle(type=ob["type"])
                m.header.frame_id = goal.frame
                xyz(m.pose.position, ob["centre"])
                m.radius = float(ob.get("radius", 0.0))
                m.length = float(ob.get("length", 0.0))
                xyz(m.size, ob.get("size", (0.0, 0.0, 0.0)))
                if "axis" in ob:  # the capsule's local z along its axis
                    w, x, y, z = matrix_to_quat_wxyz(_frame_with_z(ob["axis"]))
                    o = m.pose.orientation
                    o.w, o.x, o.y, o.z = float(w), float(x), float(y), float(z)
                msgs.append(m)
            req.obstacles = msgs
        else:
            setattr(req, key, value)
    if goal.extras.get("hold_object"):
        req.use_orientation = False


def _frame_with_z(axis) -> "list[list[float]]":
    """A rotation matrix whose third column is ``axis`` (normalised)."""
    import numpy as np

    z = np.asarray(axis, dtype=float)
    z = z / np.linalg.norm(z)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _print_pmp_answer(res) -> None:  # noqa: ANN001 - ROS type
    """The answer's PMP fields, when present."""
    if len(res.object_path):
        p = res.object_path[-1]
        print(f"object path: {len(res.object_path)} points, ends at "
              f"({p.x:.3f}, {p.y:.3f}, {p.z:.3f}) m")
    if res.obstacle_clearance >= 0:
        print(f"obstacle clearance: {res.obstacle_clearance * 1e3:.1f} mm")
    if len(res.torque_joints):
        torques = ", ".join(f"{j} {t:.2f}" for j, t in zip(res.torque_joints, res.torques))
        print(f"torques at the final posture [N m]: {torques}")
        print(f"torques within limits: {res.torques_within_limits}")
