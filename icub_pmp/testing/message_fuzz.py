"""Hypothesis strategies for any ROS message, service request or action goal, derived from
the type itself (``SLOT_TYPES`` / ``get_fields_and_field_types``), so an interface that gains a
field is fuzzed on that field without touching the tests.

What a drawn message holds (the cases issue 22 lists):

- every float: NaN, +-inf, huge (+-1e300, or +-3e38 for float32), negative, zero, or an
  ordinary value in [-2, 2] (durations, tolerances and tau come out negative often);
- every integer: its type's extremes, 0, 1 or a small value (``uint32`` ``nanosec`` may exceed
  1e9: an invalid time);
- every ``builtin_interfaces/Time``: zero, the far past, the far future (``sec`` up to 2**31-1)
  or "now"; every ``Duration``: negative, zero, huge;
- strings by field name: joint names (``name``/``joint_names``: the known set, a subset,
  unknown names, duplicates, empty), frames (``frame_id``: known frames, unknown, empty), other
  strings from a vocabulary of known words plus unknown ones;
- sequences: empty, short, or (when the message names joints) of the same length as the names,
  one more or one less, so a message can be well-formed enough to reach a node's deeper code;
- ``uint8[]`` data: empty, a few bytes or as long as ``step * height`` (images).

One message in three is drawn *plausible* instead: ordinary floats only, known names and
frames only, coherent lengths, zero stamps. Those get past the first validation and reach a
node's deeper code (planning, solving, executing), where bugs hide behind valid inputs.

Pure Python + hypothesis; imports message modules by name only (no rclpy node).
"""

from __future__ import annotations

import dataclasses
import importlib
import math
from typing import Any, Iterable, Mapping, Sequence

from hypothesis import strategies as st

__all__ = [
    "FuzzVocabulary",
    "message_strategy",
    "request_strategy",
    "goal_strategy",
    "message_class",
    "out_of_order_stamps",
    "SPECIAL_FLOATS",
]

#: the floats every float field may receive besides ordinary values
SPECIAL_FLOATS: tuple[float, ...] = (math.nan, math.inf, -math.inf, 1e300, -1e300, 0.0, -1.0,
                                     -1e-9, 1e9)
_SPECIAL_FLOAT32 = (math.nan, math.inf, -math.inf, 3e38, -3e38, 0.0, -1.0, 1e9)

_INT_RANGES = {
    "int8": (-2**7, 2**7 - 1), "uint8": (0, 2**8 - 1), "int16": (-2**15, 2**15 - 1),
    "uint16": (0, 2**16 - 1), "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1),
    "int64": (-2**63, 2**63 - 1), "uint64": (0, 2**64 - 1), "octet": (0, 255),
}

#: a joint-name field: ``JointState.name``, ``JointTrajectory.joint_names``, ``*.joint_names``
_NAME_FIELDS = ("name", "joint_names")


@dataclasses.dataclass(frozen=True)
class FuzzVocabulary:
    """Known strings the fuzzer mixes with unknown ones.

    ``joint_names``: the robot's joint names; ``frames``: frames the graph knows; ``words``:
    other valid string values (hands, chains, postures, objects, modes); ``fields``: the valid
    values of particular string fields by field name (``hands``, ``chain``, ...), used by
    plausible messages; ``unknown``: values no node should accept; ``max_sequence``: longest
    free-length sequence drawn.
    """

    joint_names: tuple[str, ...] = ()
    frames: tuple[str, ...] = ("root_link",)
    words: tuple[str, ...] = ()
    fields: Mapping[str, tuple[str, ...]] = dataclasses.field(default_factory=dict)
    unknown: tuple[str, ...] = ("", "no_such_thing", "ROOT_LINK", " left", "\u00e9\u00e8",
                                "x" * 300)
    max_sequence: int = 6

    @classmethod
    def icub(cls, extra_words: Iterable[str] = ()) -> "FuzzVocabulary":
        """The iCub's vocabulary: joints, hand/FT frames, hands, chains, postures, objects
        (from config/robot.yaml and the Cartesian chains)."""
        from icub_pmp.cartesian.kinematic_chain import CHAIN_NAMES
        from icub_pmp.kinematics.robot_spec import RobotSpec

        spec = RobotSpec.load()
        frames = ("root_link", *spec.hand_frames.values(), *spec.arm_ft_frames.values())
        words = ("left", "right", "both", "head", *CHAIN_NAMES, *spec.postures,
                 "box", "cylinder", *spec.hand_frames, *extra_words)
        fields = {"hands": ("left", "right"), "chain": tuple(CHAIN_NAMES),
                  "posture": tuple(spec.postures), "name": ("box", "cylinder"),
                  "target": ("r_hand", "l_hand", "box")}
        return cls(joint_names=tuple(spec.actuated_joints), frames=frames,
                   words=tuple(dict.fromkeys(words)), fields=fields)


def message_class(type_: Any) -> type:
    """The Python class of a rosidl ``NamespacedType`` (e.g. ``geometry_msgs/msg/Pose``)."""
    module = importlib.import_module(".".join(type_.namespaces))
    return getattr(module, type_.name)


def _float_strategy(float32: bool) -> st.SearchStrategy[float]:
    special = _SPECIAL_FLOAT32 if float32 else SPECIAL_FLOATS
    return st.one_of(st.sampled_from(special),
                     st.floats(-2.0, 2.0, width=32 if float32 else 64))


def _int_strategy(typename: str) -> st.SearchStrategy[int]:
    lo, hi = _INT_RANGES[typename]
    edges = sorted({lo, hi, 0, min(hi, 1), max(lo, -1)})
    return st.one_of(st.sampled_from(edges), st.integers(max(lo, -5), min(hi, 1000)))


def _names_strategy(vocab: FuzzVocabulary, plausible: bool = False
                    ) -> st.SearchStrategy[list[str]]:
    known = list(vocab.joint_names) or ["joint"]
    if plausible:
        return st.one_of(st.just(known),
                         st.lists(st.sampled_from(known), min_size=1, max_size=8, unique=True))
    return st.one_of(
        st.just(known),                                              # the full, valid set
        st.lists(st.sampled_from(known), max_size=8, unique=True),   # a valid subset
        st.lists(st.sampled_from(known), min_size=2, max_size=6).map(
            lambda xs: xs + xs[:1]),                                 # duplicates
        st.lists(st.sampled_from(known + list(vocab.unknown)), max_size=6),  # unknown names
    )


class _Draw:
    """The recursive message drawer: one instance per drawn message (it remembers the length
    of the last joint-name list to draw coherent sequence lengths)."""

    def __init__(self, draw: Any, vocab: FuzzVocabulary):
        self.draw = draw
        self.vocab = vocab
        self.n_names: int | None = None
        self.plausible = draw(st.sampled_from([False, False, True]))

    def message(self, cls: type) -> Any:
        msg = cls()
        fields = list(cls.get_fields_and_field_types())
        typename = f"{cls.__module__.split('.')[0]}/{cls.__name__}"
        if typename in ("builtin_interfaces/Time", "builtin_interfaces/Duration"):
            return self._time(msg, typename.endswith("Duration"))
        values: dict[str, Any] = {}
        for name, slot in zip(fields, cls.SLOT_TYPES):
            values[name] = self.value(name, slot, values)
            setattr(msg, name, values[name])
        return msg

    def _time(self, msg: Any, duration: bool) -> Any:
        d = self.draw
        if self.plausible:
            msg.sec, msg.nanosec = (1 if duration else 0), 0
        elif duration:
            msg.sec = d(st.sampled_from([0, 1, -1, -100, 2**31 - 1, -2**31]))
        else:
            msg.sec = d(st.sampled_from([0, 1, 10, 1_000_000_000, 2**31 - 1, -1, -2**31]))
        if not self.plausible:
            msg.nanosec = d(st.sampled_from([0, 500_000_000, 999_999_999, 2**32 - 1]))
        return msg

    def value(self, name: str, slot: Any, siblings: dict[str, Any]) -> Any:
        from rosidl_parser import definition as d

        if isinstance(slot, d.Array):
            return [self.scalar(name, slot.value_type) for _ in range(slot.size)]
        if isinstance(slot, (d.UnboundedSequence, d.BoundedSequence)):
            return self.sequence(name, slot, siblings)
        return self.scalar(name, slot)

    def sequence(self, name: str, slot: Any, siblings: dict[str, Any]) -> Any:
        from rosidl_parser import definition as d

        vt = slot.value_type
        bound = slot.maximum_size if isinstance(slot, d.BoundedSequence) else None
        if isinstance(vt, d.AbstractGenericString):
            if name in _NAME_FIELDS:
                names = self.draw(_names_strategy(self.vocab, self.plausible))
                self.n_names = len(names)
                return names[:bound] if bound else names
            if self.plausible and name in self.vocab.fields:
                known = list(self.vocab.fields[name])
                return self.draw(st.lists(st.sampled_from(known), min_size=1,
                                          max_size=len(known), unique=True))
            n = self.draw(st.integers(0, self.vocab.max_sequence))
            out = [self.scalar(name, vt) for _ in range(n)]
            if out and self.draw(st.booleans()):
                out.append(out[0])  # a duplicate
            return out[:bound] if bound else out
        if isinstance(vt, d.BasicType) and vt.typename in ("uint8", "octet") \
                and name == "data":
            return self._data(siblings)
        n = self._length()
        if bound is not None:
            n = min(n, bound)
        return [self.scalar(name, vt) for _ in range(n)]

    def _length(self) -> int:
        if self.plausible and self.n_names is not None:
            return self.n_names
        choices = [0, 1, 3]
        if self.n_names is not None:
            k = self.n_names
            choices += [k, k, k, k + 1, max(k - 1, 0)]
        return self.draw(st.sampled_from(choices))

    def _data(self, siblings: dict[str, Any]) -> bytes:
        step, height = siblings.get("step"), siblings.get("height")
        choices = [0, 1, 7]
        if isinstance(step, int) and isinstance(height, int) and step * height <= 2_000_000:
            choices += [step * height, step * height, max(step * height - 1, 0)]
        n = self.draw(st.sampled_from(choices))
        return bytes((i * 37) % 256 for i in range(n))

    def scalar(self, name: str, slot: Any) -> Any:
        from rosidl_parser import definition as d

        if isinstance(slot, d.NamespacedType):
            return self.message(message_class(slot))
        if isinstance(slot, d.AbstractGenericString):
            return self._string(name, slot)
        t = slot.typename
        if t in ("double", "long double", "float"):
            if self.plausible:
                return self.draw(st.floats(-1.0, 1.0, width=32 if t == "float" else 64))
            return self.draw(_float_strategy(t == "float"))
        if t == "boolean":
            return self.draw(st.booleans())
        if t == "char":
            return self.draw(st.sampled_from(["a", "\0", "Z"]))
        if t == "octet":
            return bytes([self.draw(_int_strategy("octet"))])
        if t in _INT_RANGES:
            if name in ("height", "width", "step"):
                sizes = [2, 4, 12] if self.plausible else [0, 1, 2, 4, 12, 240, 320, 960,
                                                           2**32 - 1]
                return self.draw(st.sampled_from(sizes))
            if self.plausible:
                return self.draw(st.integers(0, 3))
            return self.draw(_int_strategy(t))
        raise TypeError(f"message_fuzz: no strategy for field {name!r} of type {t!r}")

    def _string(self, name: str, slot: Any) -> str:
        v = self.vocab
        unknown = [] if self.plausible else list(v.unknown)
        if self.plausible and name in v.fields:
            pool = list(v.fields[name])
        elif name == "frame_id":
            pool = list(v.frames) + unknown
        elif name in _NAME_FIELDS:
            pool = list(v.joint_names) + unknown
        elif name == "encoding":
            pool = ["rgb8", "bgr8", "mono8", "32FC1", "16UC1"] + (
                [] if self.plausible else ["no_such_encoding", ""])
        else:
            pool = list(v.words) + unknown
        s = self.draw(st.sampled_from(pool or [""]))
        bound = getattr(slot, "maximum_size", None)
        return s[:bound] if isinstance(bound, int) else s


def message_strategy(msg_type: type, vocab: FuzzVocabulary | None = None
                     ) -> st.SearchStrategy[Any]:
    """A strategy drawing instances of the ROS message class ``msg_type`` (module doc)."""
    voc = vocab or FuzzVocabulary()

    @st.composite
    def _messages(draw: Any) -> Any:
        return _Draw(draw, voc).message(msg_type)

    return _messages()


def request_strategy(srv_type: type, vocab: FuzzVocabulary | None = None
                     ) -> st.SearchStrategy[Any]:
    """A strategy drawing requests of the service type ``srv_type``."""
    return message_strategy(srv_type.Request, vocab)


def goal_strategy(action_type: type, vocab: FuzzVocabulary | None = None
                  ) -> st.SearchStrategy[Any]:
    """A strategy drawing goals of the action type ``action_type``."""
    return message_strategy(action_type.Goal, vocab)


def out_of_order_stamps(n: int, t0: float, dt: float) -> list[float]:
    """``n`` stamps [s] around ``t0`` spaced ``dt`` apart but out of order: every pair
    swapped and one stamp repeated (topic-level fuzzing: late and duplicated messages)."""
    ts = [t0 + i * dt for i in range(n)]
    for i in range(0, n - 1, 2):
        ts[i], ts[i + 1] = ts[i + 1], ts[i]
    if n >= 3:
        ts[-1] = ts[0]
    return ts


def stamp_of(t: float) -> tuple[int, int]:
    """(sec, nanosec) of ``t`` [s] for a ``builtin_interfaces/Time`` (t >= 0)."""
    sec = int(math.floor(t))
    return sec, int(round((t - sec) * 1e9)) % 1_000_000_000


def restamp(msgs: Sequence[Any], stamps: Sequence[float]) -> list[Any]:
    """Set ``header.stamp`` of each message (those with a header) to the matching stamp."""
    for m, t in zip(msgs, stamps):
        if hasattr(m, "header"):
            m.header.stamp.sec, m.header.stamp.nanosec = stamp_of(t)
    return list(msgs)
