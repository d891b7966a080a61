"""Reach request -> ReachGoal: the validation shared by /pmp/reach and /pmp/reach_action.

Plain Python (no ROS import): the request is read by attribute, so the service request and the
action goal (``icub_interfaces/srv/Reach``, ``icub_interfaces/action/Reach``, same field
names) and the obstacle messages go through the same code. Every rejection is an
:class:`~icub_pmp.errors.InvalidInput` whose message starts with the field's name
(``obstacles[1].radius: ...``), so the node answers ``success=false`` with it.

What it builds (Mohan, Morasso, Metta, Sandini 2009):

- hand targets (eq 1) in root_link, from any frame of the model at the start posture;
- a held object (Sect. 3.2, Fig 8): :class:`~icub_pmp.pmp.HeldObject` with both hands'
  grasp offsets, the goal pulls the object and the object pulls the hands;
- obstacles (Sect. 2.3's external constraints): sphere, capsule and box fields inflated by the
  clearance the hands must keep (+ a safety margin for the sampled trajectory); a target or a
  start hand within the clearance of an obstacle is rejected;
- target forces and per-joint torque limits (Sect. 2.3, Fig 3: the saturation block);
- the trunk admittance ``A_trunk`` (Sect. 3.1, Fig 7: stiff = grounded shoulders), frozen
  joints and per-joint admittance factors.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Callable, Collection, Mapping, NamedTuple, Sequence

import numpy as np

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError, InvalidInput, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS
from icub_pmp.kinematics.rotations import quat_wxyz_to_matrix, rotation_angle
from icub_pmp.pmp.box_obstacle_field import BoxObstacleField
from icub_pmp.pmp.capsule_obstacle_field import CapsuleObstacleField
from icub_pmp.pmp.held_object import HeldObject
from icub_pmp.pmp.obstacle_field import ObstacleField
from icub_pmp.pmp.reach_goal import ReachGoal

__all__ = [
    "ReachRequestConfig",
    "FramePose",
    "ParsedReach",
    "OBSTACLE_TYPES",
    "TRUNK_MODES",
    "parse_reach_request",
    "parse_obstacles",
]

OBSTACLE_TYPES = ("sphere", "capsule", "box")
TRUNK_MODES = ("", "stiff", "compliant")
#: the held object's goal orientation may differ from its start by this much [rad]
OBJECT_ROTATION_TOLERANCE = 0.01


@dataclasses.dataclass(frozen=True)
class ReachRequestConfig(ConfigBase):
    """Defaults of the request fields (ROS parameters of pmp_planner).

    Attributes:
        obstacle_clearance: [m] clearance the hands keep from obstacles when a request gives 0.
        obstacle_margin: [m] the fields act on obstacles grown by clearance + this, so the
            sampled trajectory (interpolated between the relaxation's nodes) keeps the clearance.
        obstacle_influence: [m] reach of an obstacle's repulsive field beyond its grown surface.
        obstacle_gain: [N m^2] gain of the repulsive field (FIRAS, Khatib 1986).
        trunk_compliant_scale: factor on A_trunk for ``trunk_admittance: compliant``.
        object_goal_stiffness: [N/m] K_goal of a held object's goal field (Sect. 3.2).
        object_grasp_stiffness: [N/m] K_grasp coupling each hand to its grasp point.
        object_admittance: [m/(s N)] A_E of the held object node.
    """

    obstacle_clearance: float = 0.02
    obstacle_margin: float = 0.005
    obstacle_influence: float = 0.05
    obstacle_gain: float = 1.0e-3
    trunk_compliant_scale: float = 5.0
    object_goal_stiffness: float = 1000.0
    object_grasp_stiffness: float = 1.0e5
    object_admittance: float = 1.0

    def validate(self) -> None:
        """Clearance and margin >= 0, the others > 0 (all finite)."""
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            low_ok = v >= 0 if f.name in ("obstacle_clearance", "obstacle_margin") else v > 0
            if not math.isfinite(v) or not low_ok:
                raise ConfigError(f"ReachRequestConfig.{f.name}: out of range, got {v}")


class FramePose(NamedTuple):
    """A frame of the model at the start posture: ``R_base_frame`` (3, 3), origin (3,) [m]."""

    rotation: np.ndarray
    translation: np.ndarray


#: frame name -> its pose at the start posture; raises UnknownName for an unknown frame
FrameLookup = Callable[[str], FramePose]


class ParsedReach(NamedTuple):
    """A validated request: the goal and what the answer reports on."""

    goal: ReachGoal
    clearance: float  # [m] clearance the hands keep (meaningful with obstacles)
    report_torques: bool  # target forces or torque limits were given


# ---------------------------------------------------------------------- small readers
def _vec(field: str, v) -> np.ndarray:
    a = np.array([v.x, v.y, v.z], dtype=float)
    if not np.all(np.isfinite(a)):
        raise InvalidInput(f"{field}: ({v.x}, {v.y}, {v.z}) contains NaN or infinite values")
    return a


def _number(field: str, v: float, *, positive: bool = False) -> float:
    v = float(v)
    if not math.isfinite(v) or v < 0 or (positive and v == 0):
        bound = "> 0" if positive else ">= 0"
        raise InvalidInput(f"{field}: expected a finite value {bound}, got {v}")
    return v


def _quat(field: str, o, *, allow_zero: bool = False) -> np.ndarray:
    q = np.array([o.w, o.x, o.y, o.z], dtype=float)
    if not np.all(np.isfinite(q)):
        raise InvalidInput(f"{field}: orientation contains NaN or infinite values")
    norm = float(np.linalg.norm(q))
    if norm < 1e-9:
        if allow_zero:
            return np.array([1.0, 0.0, 0.0, 0.0])
        raise InvalidInput(f"{field}: orientation is a zero quaternion")
    return q / norm


def _frame(field: str, header, frames: FrameLookup) -> FramePose | None:
    """The pose of header.frame_id (None = root_link)."""
    name = header.frame_id or "root_link"
    if name == "root_link":
        return None
    try:
        return frames(name)
    except UnknownName as exc:
        raise InvalidInput(f"{field}.header.frame_id: {exc}") from None


def _to_base(frame: FramePose | None, pos: np.ndarray, rot: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    if frame is None:
        return pos, rot
    return frame.rotation @ pos + frame.translation, frame.rotation @ rot


def _pose(field: str, stamped, frames: FrameLookup, *, allow_zero_quat: bool = False
          ) -> tuple[np.ndarray, np.ndarray]:
    """PoseStamped -> (position (3,) [m], R (3, 3)) in root_link."""
    pos = _vec(f"{field}.pose.position", stamped.pose.position)
    rot = quat_wxyz_to_matrix(_quat(field, stamped.pose.orientation, allow_zero=allow_zero_quat))
    return _to_base(_frame(field, stamped.header, frames), pos, rot)


def _named_values(field_names: str, field_values: str, names, values, valid: Collection[str]
                  ) -> dict[str, float]:
    names, values = list(names), list(values)
    if len(names) != len(values):
        raise InvalidInput(f"{field_names}/{field_values}: wrong lengths, {len(names)} names "
                           f"and {len(values)} values")
    out: dict[str, float] = {}
    for j, v in zip(names, values):
        _joint(field_names, j, valid)
        if j in out:
            raise InvalidInput(f"{field_names}: {j!r} is named twice")
        out[j] = float(v)
    return out


def _joint(field: str, name: str, valid: Collection[str]) -> None:
    if name not in valid:
        raise InvalidInput(f"{field}: {UnknownName('joint', name, valid)}")


# ---------------------------------------------------------------------- obstacles
def parse_obstacles(field: str, msgs: Sequence, frames: FrameLookup, inflation: float,
                    config: ReachRequestConfig) -> list[ObstacleField]:
    """Obstacle messages -> fields in root_link, grown by ``inflation`` [m]."""
    out: list[ObstacleField] = []
    kw = dict(influence=config.obstacle_influence, gain=config.obstacle_gain,
              inflation=inflation)
    for i, ob in enumerate(msgs):
        name = f"{field}[{i}]"
        kind = ob.type
        if kind not in OBSTACLE_TYPES:
            raise InvalidInput(f"{name}.type: {UnknownName('obstacle type', kind, OBSTACLE_TYPES)}")
        frame = _frame(name, ob.header, frames)
        centre = _vec(f"{name}.pose.position", ob.pose.position)
        rot = quat_wxyz_to_matrix(_quat(f"{name}.pose", ob.pose.orientation,
                                        allow_zero=kind == "sphere"))
        centre, rot = _to_base(frame, centre, rot)
        try:
            if kind == "sphere":
                out.append(ObstacleField(centre, _number(f"{name}.radius", ob.radius,
                                                         positive=True), **kw))
            elif kind == "capsule":
                r = _number(f"{name}.radius", ob.radius, positive=True)
                half = 0.5 * _number(f"{name}.length", ob.length, positive=True)
                axis = rot[:, 2]
                out.append(CapsuleObstacleField(centre - half * axis, centre + half * axis, r,
                                                **kw))
            else:
                size = _vec(f"{name}.size", ob.size)
                if np.any(size <= 0):
                    raise InvalidInput(f"{name}.size: expected 3 edge lengths > 0 m, got "
                                       f"{size.tolist()}")
                out.append(BoxObstacleField(centre, rot, 0.5 * size, **kw))
        except InvalidInput as exc:
            msg = str(exc)
            raise InvalidInput(msg if msg.startswith(name) else f"{name}: {msg}") from None
    return out


# ---------------------------------------------------------------------- the request
def parse_reach_request(
    req,
    *,
    frames: FrameLookup,
    hand_positions: Mapping[str, np.ndarray],
    joint_names: Collection[str],
    config: ReachRequestConfig,
    scene: Sequence = (),
    hand_frames: Mapping[str, str] | None = None,
) -> ParsedReach:
    """Validate a Reach request (service or action goal) and build its :class:`ReachGoal`.

    Args:
        req: the request; its fields as in ``icub_interfaces/srv/Reach.srv``.
        frames: pose of a model frame at the start posture (targets, obstacles, object).
        hand_positions: hand -> position (3,) [m] at the start posture (root_link).
        joint_names: the joints of the body model (frozen, scaled, torque-limited joints).
        config: defaults of the request fields.
        scene: obstacle messages from /pmp/obstacles, merged with the request's.
        hand_frames: hand -> its frame; with hold_object and use_orientation each grasping
            hand keeps its start orientation (the frame's at the start posture).

    Raises:
        InvalidInput: a message naming the field, the value and what was expected.
    """
    hands = list(req.hands)
    if not hands:
        raise InvalidInput("hands: empty; give 'left', 'right' or both")
    if len(set(hands)) != len(hands):
        raise InvalidInput(f"hands: {hands} names a hand twice")
    for h in hands:
        if h not in HANDS:
            raise UnknownName("hand", h, HANDS)
    if not math.isfinite(req.tau) or req.tau < 0:
        raise InvalidInput(f"tau: expected a finite duration >= 0 s (0 = default), got {req.tau}")

    # held object (Sect. 3.2)
    held = None
    targets: dict[str, np.ndarray] = {}
    orientations: dict[str, np.ndarray] = {}
    if req.hold_object:
        held = _held_object(req, hands, frames, hand_positions, config)
        if req.use_orientation:  # a rigid grasp in translation: the hands do not turn
            if hand_frames is None:
                raise InvalidInput("use_orientation with hold_object: the hands' frames are "
                                   "not known here")
            orientations = {h: frames(hand_frames[h]).rotation for h in held.hands}
    else:
        for h in hands:
            pos, rot = _pose(f"{h}_target", getattr(req, f"{h}_target"), frames)
            targets[h] = pos
            if req.use_orientation:
                orientations[h] = rot

    # force targets and torque limits (Sect. 2.3, Fig 3)
    forces = {}
    for h in HANDS:
        f = _vec(f"{h}_force", getattr(req, f"{h}_force"))
        if np.any(f):
            if h not in hands:
                raise InvalidInput(f"{h}_force: given for the {h} hand, which is not in hands "
                                   f"{hands}")
            if held is not None:
                raise InvalidInput(f"{h}_force: a force target cannot be combined with "
                                   f"hold_object (the hands follow the object)")
            forces[h] = f
    torque_limits = _named_values("torque_limit_joints", "torque_limits",
                                  req.torque_limit_joints, req.torque_limits, joint_names)
    for j, v in torque_limits.items():
        if not math.isfinite(v) or v <= 0:
            raise InvalidInput(f"torque_limits: {j} = {v}; expected a finite limit > 0 N m")

    # admittances (Sect. 3.1, Fig 7)
    trunk_scale = _trunk_scale(req, config)
    for j in req.frozen_joints:
        _joint("frozen_joints", j, joint_names)
    scales = _named_values("admittance_scale_joints", "admittance_scales",
                           req.admittance_scale_joints, req.admittance_scales, joint_names)
    for j, v in scales.items():
        if not math.isfinite(v) or v < 0:
            raise InvalidInput(f"admittance_scales: {j} = {v}; expected a finite factor >= 0")

    # obstacles (Sect. 2.3's external constraints)
    clearance = _number("obstacle_clearance", req.obstacle_clearance) or config.obstacle_clearance
    inflation = clearance + config.obstacle_margin
    obstacles = parse_obstacles("obstacles", req.obstacles, frames, inflation, config)
    obstacles += parse_obstacles("/pmp/obstacles", scene, frames, inflation, config)
    final = dict(targets)
    if held is not None:
        final.update(held.hand_targets())
    _check_free(obstacles, final, hand_positions, clearance, len(req.obstacles))

    goal = ReachGoal(
        targets=targets, orientations=orientations, use_torso=req.use_torso,
        tau=req.tau if req.tau > 0 else None, obstacles=tuple(obstacles),
        frozen_joints=tuple(req.frozen_joints), target_forces=forces, held_object=held,
        trunk_admittance_scale=trunk_scale, torque_limits=torque_limits,
        admittance_scales=scales,
    )
    return ParsedReach(goal, clearance, bool(forces or torque_limits))


def _held_object(req, hands, frames, hand_positions, config) -> HeldObject:
    if sorted(hands) != sorted(HANDS):
        raise InvalidInput(f"hold_object: a held object needs both hands (hands = [left, "
                           f"right]), got hands {list(hands)}")
    given = bool(req.object_pose.header.frame_id) or bool(
        np.any(_vec("object_pose.pose.position", req.object_pose.pose.position)))
    if given:
        pos, rot = _pose("object_pose", req.object_pose, frames)
    else:
        pos = np.mean([np.asarray(hand_positions[h], dtype=float) for h in HANDS], axis=0)
        rot = np.eye(3)
    goal, goal_rot = _pose("object_goal", req.object_goal, frames)
    angle = rotation_angle(rot, goal_rot)
    if angle > OBJECT_ROTATION_TOLERANCE:
        raise InvalidInput(f"object_goal.pose.orientation: turns the object by {angle:.3f} rad; "
                           f"the transport is a translation (Sect. 3.2): give object_pose's "
                           f"orientation")
    grasps = {h: _vec(f"{h}_grasp", getattr(req, f"{h}_grasp")) for h in HANDS}
    if not any(np.any(g) for g in grasps.values()):
        offsets = {h: np.asarray(hand_positions[h], dtype=float) - pos for h in HANDS}
    else:
        offsets = {h: rot @ g for h, g in grasps.items()}
    if np.linalg.norm(offsets["left"] - offsets["right"]) < 1e-3:
        raise InvalidInput("left_grasp/right_grasp: the two grasp points coincide; a held "
                           "object needs one grasp point per hand")
    return HeldObject(pos, goal, offsets, goal_stiffness=config.object_goal_stiffness,
                      grasp_stiffness=config.object_grasp_stiffness,
                      admittance=config.object_admittance)


def _trunk_scale(req, config: ReachRequestConfig) -> float:
    mode = req.trunk_admittance
    if mode not in TRUNK_MODES:
        raise InvalidInput(f"trunk_admittance: {mode!r}; valid: '' (configured), 'stiff', "
                           f"'compliant'")
    value = _number("trunk_admittance_scale", req.trunk_admittance_scale)
    if (mode or value) and not req.use_torso:
        raise InvalidInput("trunk_admittance: the trunk admittance needs use_torso (the torso "
                           "is not in the network)")
    if value > 0:
        return value
    return {"": 1.0, "stiff": 0.0, "compliant": config.trunk_compliant_scale}[mode]


def _check_free(obstacles: Sequence[ObstacleField], targets: Mapping[str, np.ndarray],
                starts: Mapping[str, np.ndarray], clearance: float, n_request: int) -> None:
    """Reject targets and start hands closer to an obstacle than its field's grown surface
    (the clearance + the planning margin)."""
    for i, ob in enumerate(obstacles):
        name = f"obstacles[{i}]" if i < n_request else f"/pmp/obstacles[{i - n_request}]"
        keep = (f"the hands keep {clearance * 1e3:.1f} mm + a "
                f"{(ob.inflation - clearance) * 1e3:.1f} mm planning margin")
        for h, p in targets.items():
            d = float(ob.surface_distance(p))
            if d < ob.inflation:
                what = "encloses" if d < 0 else "comes within the clearance of"
                raise InvalidInput(f"{name}: the {ob.kind} {what} the {h} hand's target (its "
                                   f"surface is {d * 1e3:.1f} mm from it; {keep})")
        for h, p in starts.items():
            if h not in targets:
                continue
            d = float(ob.surface_distance(p))
            if d < ob.inflation:
                raise InvalidInput(f"{name}: the {h} hand starts {d * 1e3:.1f} mm from this "
                                   f"{ob.kind} ({keep}); move it away first")
