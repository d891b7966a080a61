"""sensor_msgs/JointState <-> numpy: building, validating, reading by joint name."""

from __future__ import annotations

import math
from typing import Iterable, Sequence

import numpy as np
from builtin_interfaces.msg import Time
from sensor_msgs.msg import JointState

from icub_pmp.errors import InvalidInput, UnknownName

__all__ = ["make_joint_state", "validate_joint_state", "joint_state_field", "joint_state_arrays"]


def make_joint_state(
    names: Sequence[str],
    position: Iterable[float] | None = None,
    velocity: Iterable[float] | None = None,
    effort: Iterable[float] | None = None,
    stamp: Time | None = None,
    frame_id: str = "",
) -> JointState:
    """Build a JointState; absent fields stay empty (as ROS allows)."""
    msg = JointState()
    if stamp is not None:
        msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.name = list(names)
    if position is not None:
        msg.position = np.asarray(position, dtype=float).tolist()
    if velocity is not None:
        msg.velocity = np.asarray(velocity, dtype=float).tolist()
    if effort is not None:
        msg.effort = np.asarray(effort, dtype=float).tolist()
    return msg


def validate_joint_state(
    msg: JointState,
    required: Sequence[str] = ("position",),
    valid_names: Iterable[str] | None = None,
) -> None:
    """Check a JointState: unique names, each ``required`` field as long as ``name`` and
    finite, optional fields empty or as long as ``name``, names among ``valid_names``."""
    n = len(msg.name)
    if n == 0:
        raise InvalidInput("JointState has no joint names")
    if len(set(msg.name)) != n:
        raise InvalidInput("JointState has duplicate joint names")
    for field in ("position", "velocity", "effort"):
        values = getattr(msg, field)
        if field in required and len(values) != n:
            raise InvalidInput(f"JointState.{field} has {len(values)} values for {n} names")
        if len(values) not in (0, n):
            raise InvalidInput(f"JointState.{field} has {len(values)} values for {n} names")
        if len(values) and not np.all(np.isfinite(np.asarray(values, dtype=float))):
            raise InvalidInput(f"JointState.{field} contains NaN or infinite values")
    if valid_names is not None:
        valid = set(valid_names)
        for name in msg.name:
            if name not in valid:
                raise UnknownName("joint", name, valid)


def joint_state_field(msg: JointState, field: str = "position") -> dict[str, float]:
    """{joint: value} for one field of a JointState (empty if the field is empty)."""
    values = getattr(msg, field)
    if len(values) == 0:
        return {}
    return dict(zip(msg.name, (float(v) for v in values)))


def joint_state_arrays(
    msg: JointState, names: Sequence[str], index: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """(positions (n,) [rad], velocities (n,) [rad/s] or None when the message has none,
    index) of joints ``names``, in that order, from a JointState (joints the message has
    beyond ``names`` are ignored).

    ``index`` = the positions of ``names`` in ``msg.name`` returned by a previous call for
    the same name list (skips the name lookup: the 1 kHz path). Raises InvalidInput when a
    joint is missing, a field has the wrong length or a value is NaN/inf.
    """
    n = len(msg.name)
    if index is None:
        lookup = {name: i for i, name in enumerate(msg.name)}
        missing = [name for name in names if name not in lookup]
        if missing:
            raise InvalidInput(f"JointState lacks joints {missing}")
        index = np.array([lookup[name] for name in names], dtype=int)
    pos = np.asarray(msg.position, dtype=float)
    if pos.shape != (n,):
        raise InvalidInput(f"JointState.position has {pos.size} values for {n} names")
    q = pos[index]
    v = None
    if len(msg.velocity):
        vel = np.asarray(msg.velocity, dtype=float)
        if vel.shape != (n,):
            raise InvalidInput(f"JointState.velocity has {vel.size} values for {n} names")
        v = vel[index]
        if not math.isfinite(float(v.sum())):
            raise InvalidInput("JointState.velocity contains NaN or infinite values")
    if not math.isfinite(float(q.sum())):
        raise InvalidInput("JointState.position contains NaN or infinite values")
    return q, v, index
