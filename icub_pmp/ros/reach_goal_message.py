"""Build an ``icub_interfaces/action/Reach`` goal from hand targets: the one place the demo,
the benchmarks, the fault injection and the tests fill the goal's hands and target points."""

from __future__ import annotations

from typing import Any, Iterable, Mapping, Sequence

__all__ = ["reach_goal_message"]


def reach_goal_message(targets: Mapping[str, Sequence[float]], tau: float = 2.0,
                       use_torso: bool = False, frame: str = "root_link",
                       frozen_joints: Iterable[str] = ()) -> Any:
    """A ``Reach.Goal`` moving each hand of ``targets`` (``"left"`` / ``"right"`` -> a point
    [m] in ``frame``) in ``tau`` [s]; the hands are listed left first, the targets' orientations
    left at identity (``use_orientation`` false). Other fields (obstacles, forces, a held
    object) are set by the caller on the returned goal.

    :raises ValueError: a hand other than ``left`` / ``right``.
    """
    from icub_interfaces.action import Reach

    unknown = sorted(set(targets) - {"left", "right"})
    if unknown:
        raise ValueError(f"unknown hand(s) {unknown}: expected 'left' and/or 'right'")
    goal = Reach.Goal()
    goal.hands = [h for h in ("left", "right") if h in targets]
    goal.tau = float(tau)
    goal.use_torso = bool(use_torso)
    goal.frozen_joints = list(frozen_joints)
    for hand in goal.hands:
        stamped = goal.left_target if hand == "left" else goal.right_target
        stamped.header.frame_id = frame
        p = stamped.pose.position
        p.x, p.y, p.z = (float(v) for v in targets[hand])
        stamped.pose.orientation.w = 1.0
    return goal
