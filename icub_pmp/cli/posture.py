"""``icub posture``: move joints to a named posture of config/robot.yaml and wait for it.

    icub posture rest                          # torso and both arms back to the home posture
    icub posture rest --parts torso            # only the torso upright (after --torso reaches)
    icub posture park --parts left_arm,right_arm --duration 3
    icub posture --list                        # the postures and their joints [deg]

The robot's "home" button (yarpmotorgui's, or ctpService's one-shot move): one trajectory point
at the posture, sent to the impedance controller's FollowJointTrajectory action
(``/impedance_controller/follow_joint_trajectory``), executed as a minimum-jerk motion from the
measured joints. Without ``--duration`` the motion takes the time that keeps every joint within
half its velocity and acceleration limits (``config/robot.yaml``), at least 1 s. The answer is
the controller's result: the largest measured error at the end [deg] and the joint it is on.
PMP reaches with the torso (``icub reach --torso``) leave the trunk where the last reach put it
(PMP relaxes from the measured posture and has no rest-posture pull): this is how it comes back.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from icub_pmp.cli.defaults import DISCOVERY_TIMEOUT
from icub_pmp.errors import InvalidInput, UnknownName

__all__ = ["register", "run", "PARTS", "posture_goal", "posture_duration"]

#: the joint groups a posture move can take, as config/robot.yaml names them
PARTS = ("torso", "left_arm", "right_arm", "neck", "eyes")
#: parts moved when ``--parts`` is not given (the head belongs to the gaze controller)
DEFAULT_PARTS = ("torso", "left_arm", "right_arm")
#: share of each joint's velocity and acceleration limits the automatic duration stays within
LIMIT_SHARE = 0.5
#: shortest automatic duration [s]
MIN_DURATION = 1.0
#: peak speed and acceleration of a minimum-jerk move of amplitude d in time T:
#: 1.875 d / T and 5.774 d / T^2
_MJ_PEAK_V, _MJ_PEAK_A = 1.875, 10.0 / math.sqrt(3.0)

_EXAMPLES = """examples:
  icub posture rest                          torso and both arms to the home posture
  icub posture rest --parts torso            the torso upright again after --torso reaches
  icub posture park --parts left_arm,right_arm --duration 3
  icub posture --list
"""


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``posture`` subcommand."""
    p = sub.add_parser("posture", help="move joints to a named posture of config/robot.yaml "
                                       "(the home button) and wait for it",
                       description=__doc__.split("\n\n")[0], epilog=_EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("name", nargs="?", default="", help="posture name (see --list)")
    p.add_argument("--parts", default=",".join(DEFAULT_PARTS),
                   help=f"comma-separated joint groups of {', '.join(PARTS)} (default "
                        f"{','.join(DEFAULT_PARTS)})")
    p.add_argument("--duration", type=float, default=0.0,
                   help="motion time [s] (0 = within half the joints' rate limits, >= 1 s)")
    p.add_argument("--list", action="store_true", help="print the postures and exit")
    p.add_argument("--action", default="/impedance_controller/follow_joint_trajectory")
    p.add_argument("--timeout", type=float, default=DISCOVERY_TIMEOUT,
                   help="wait this long for the controller and a joint state [s]")
    p.set_defaults(func=run)


def part_joints(spec, parts: str) -> tuple[str, ...]:  # noqa: ANN001 - RobotSpec
    """The joints of the comma-separated ``parts`` (raises UnknownName / InvalidInput)."""
    groups = {"torso": spec.torso_joints, "left_arm": spec.left_arm_joints,
              "right_arm": spec.right_arm_joints, "neck": spec.neck_joints,
              "eyes": spec.eye_joints}
    names = [p.strip() for p in parts.split(",") if p.strip()]
    if not names:
        raise InvalidInput("--parts: no joint group given")
    joints: list[str] = []
    for name in names:
        if name not in groups:
            raise UnknownName("part", name, PARTS)
        joints.extend(j for j in groups[name] if j not in joints)
    return tuple(joints)


def posture_duration(joints: tuple[str, ...], start: np.ndarray, goal: np.ndarray,
                     spec=None) -> float:  # noqa: ANN001 - RobotSpec
    """Time [s] of a minimum-jerk move from ``start`` to ``goal`` (rad, per joint of
    ``joints``) that keeps every joint within :data:`LIMIT_SHARE` of its velocity and
    acceleration limits, at least :data:`MIN_DURATION`."""
    from icub_pmp.control.trajectory_limits import JointRateLimits

    limits = JointRateLimits.from_spec(spec, joints)
    d = np.abs(np.asarray(goal, dtype=float) - np.asarray(start, dtype=float))
    v = _MJ_PEAK_V * d / (LIMIT_SHARE * np.asarray(limits.velocity))
    a = np.sqrt(_MJ_PEAK_A * d / (LIMIT_SHARE * np.asarray(limits.acceleration)))
    return float(max(MIN_DURATION, v.max(initial=0.0), a.max(initial=0.0)))


def posture_goal(name: str, parts: str, duration: float, measured: dict[str, float] | None,
                 spec=None):  # noqa: ANN001, ANN201 - RobotSpec, FollowJointTrajectory.Goal
    """The FollowJointTrajectory goal that takes ``parts`` to posture ``name`` in
    ``duration`` s (0: :func:`posture_duration` from the ``measured`` joints [rad]); raises
    InvalidInput / UnknownName on bad input."""
    from icub_interfaces.action import FollowJointTrajectory
    from icub_pmp.kinematics import RobotSpec
    from icub_pmp.ros.conversions import arrays_to_trajectory

    spec = spec or RobotSpec.load()
    if not math.isfinite(duration) or duration < 0:
        raise InvalidInput(f"--duration: expected a finite time >= 0 s, got {duration}")
    target = spec.posture(name)
    joints = part_joints(spec, parts)
    q = np.array([target[j] for j in joints])
    if duration == 0:
        if measured is None or any(j not in measured for j in joints):
            missing = [j for j in joints if measured is None or j not in measured]
            raise InvalidInput(f"no measured position of {missing[:3]} in /joint_states: "
                               "give --duration")
        duration = posture_duration(joints, np.array([measured[j] for j in joints]), q, spec)
    goal = FollowJointTrajectory.Goal()
    goal.trajectory = arrays_to_trajectory(list(joints), [duration], q[None, :])
    return goal


def _list(spec) -> int:  # noqa: ANN001 - RobotSpec
    for name in spec.postures:
        q = spec.posture(name)
        listed = {j: v for j, v in q.items() if v != 0.0}
        text = ", ".join(f"{j} {math.degrees(v):.0f}" for j, v in listed.items()) or "all 0"
        print(f"{name}: {text}")
    return 0


def run(args: argparse.Namespace) -> int:
    """Send the posture move and print the controller's result."""
    from rclpy.action import ActionClient
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import JointState

    from icub_interfaces.action import FollowJointTrajectory
    from icub_pmp.cli.session import cli_node, spin_until, spin_until_ready
    from icub_pmp.kinematics import RobotSpec

    spec = RobotSpec.load()
    if args.list:
        return _list(spec)
    if not args.name:
        raise InvalidInput(f"no posture: give one of {', '.join(spec.postures)} (or --list)")
    spec.posture(args.name)  # an unknown name fails before anything is sent
    part_joints(spec, args.parts)
    with cli_node("icub_posture") as (node, executor):
        latest: list = []
        node.create_subscription(JointState, "/joint_states", latest.append,
                                 qos_profile_sensor_data)
        measured = None
        if args.duration == 0:
            if not spin_until(executor, lambda: bool(latest), args.timeout):
                raise TimeoutError(f"no /joint_states within {args.timeout:g} s (is the "
                                   "simulator running?); or give --duration")
            measured = dict(zip(latest[-1].name, latest[-1].position))
        goal = posture_goal(args.name, args.parts, args.duration, measured, spec)
        client = ActionClient(node, FollowJointTrajectory, args.action)
        spin_until_ready(node, executor, client.server_is_ready, args.timeout, args.action,
                         "action", "impedance_controller")
        duration = goal.trajectory.points[-1].time_from_start
        print(f"posture {args.name}: {len(goal.trajectory.joint_names)} joints "
              f"({args.parts}) in {duration.sec + duration.nanosec * 1e-9:.2f} s",
              file=sys.stderr)
        sent = client.send_goal_async(goal)
        if not spin_until(executor, sent.done, args.timeout):
            raise TimeoutError(f"{args.action}: the goal was not acknowledged within "
                               f"{args.timeout:g} s")
        handle = sent.result()
        if not handle.accepted:
            print("icub: error: the controller rejected the goal", file=sys.stderr)
            return 1
        result = handle.get_result_async()
        try:
            spin_until(executor, result.done, 0.0)
        except KeyboardInterrupt:
            print("icub: canceling (the joints hold where they are)", file=sys.stderr)
            handle.cancel_goal_async()
            spin_until(executor, result.done, 10.0)
            return 130
        res = result.result().result
    if res.error_code != 0:
        print(f"icub: error: posture {args.name} not reached (code {res.error_code}): "
              f"{res.error_string}", file=sys.stderr)
        return 1
    err = np.abs(np.asarray(res.final_error, dtype=float))
    worst = int(np.argmax(err)) if err.size else 0
    print(f"posture {args.name}: reached in {res.execution_time:.2f} s; largest error "
          f"{math.degrees(float(err.max(initial=0.0))):.2f} deg"
          + (f" ({res.joint_names[worst]})" if err.size else ""))
    return 0
