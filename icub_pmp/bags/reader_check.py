"""ReaderCheck: which channels of a bag the readers roboticists use cannot decode.

Two Python readers are checked, each with its own code, on each channel's schema (name,
encoding, definition text) and the type hash stored in ``metadata.yaml``:

- the official MCAP reader with the ROS 2 decoder (``mcap_ros2.decoder.DecoderFactory``, the
  decoder Foxglove's Python tooling uses): a channel is decodable when the factory builds a
  decoder for it. It reads ``ros2msg`` schemas only and validates type names with rosidl's
  rules, so ``pkg/srv/Name_Event`` (service events) and ``pkg/action/Name_FeedbackMessage``
  (action feedback) are rejected whatever the text. ``McapReader.iter_decoded_messages``
  raises at the first message of such a channel, so one of them stops a whole-bag read.
- rosbags' ``AnyReader``: it parses every channel's definition into one type store, then checks
  each stored type hash against the hash it computes; an unresolvable type name or a hash
  mismatch makes it refuse the whole bag. The check repeats those steps per channel, then for
  all channels together (a channel can redefine a type another one uses).

No ROS import.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

from icub_pmp.bags.bag_reader import BagTopic
from icub_pmp.bags.message_definitions import DELIMITER

__all__ = ["ReaderCheck", "UnreadableChannel", "MCAP_ROS2", "ROSBAGS"]

MCAP_ROS2 = "mcap-ros2-support"
ROSBAGS = "rosbags"


class UnreadableChannel(NamedTuple):
    """A channel that ``reader`` cannot decode, and why (one line)."""

    topic: str
    msgtype: str
    reader: str  # MCAP_ROS2 or ROSBAGS
    reason: str


class ReaderCheck:
    """Check the channels of a bag (its :class:`BagTopic` list) against both readers."""

    def __init__(self, topics: Sequence[BagTopic]):
        self.topics = tuple(topics)

    def unreadable(self) -> tuple[UnreadableChannel, ...]:
        """Every (channel, reader) pair that fails, in topic order, mcap first."""
        out = [u for t in self.topics if (u := self.mcap_ros2(t)) is not None]
        out += self.rosbags()
        return tuple(sorted(out, key=lambda u: (u.topic, u.reader != MCAP_ROS2)))

    # ------------------------------------------------------------------ mcap
    @staticmethod
    def mcap_ros2(topic: BagTopic) -> UnreadableChannel | None:
        """Why the official MCAP ROS 2 decoder cannot decode ``topic`` (None if it can)."""
        from mcap.records import Schema
        from mcap_ros2.decoder import DecoderFactory

        schema = Schema(id=1, name=topic.msgtype, encoding=topic.encoding,
                        data=topic.msgdef.encode("utf-8"))
        try:
            decoder = DecoderFactory().decoder_for(topic.serialization_format, schema)
        except Exception as exc:  # the vendored rosidl parser raises several kinds
            return UnreadableChannel(topic.name, topic.msgtype, MCAP_ROS2, _one_line(exc))
        if decoder is None:
            return UnreadableChannel(
                topic.name, topic.msgtype, MCAP_ROS2,
                f"no decoder for schema encoding {topic.encoding!r} (it reads ros2msg only)")
        return None

    # ------------------------------------------------------------------ rosbags
    def rosbags(self) -> list[UnreadableChannel]:
        """Channels that make rosbags' AnyReader refuse the bag."""
        from rosbags.typesys import Stores, get_typestore

        out: list[UnreadableChannel] = []
        parsed: list[tuple[BagTopic, dict]] = []
        for t in self.topics:
            try:
                typs = _rosbags_types(t)
                store = get_typestore(Stores.EMPTY)
                store.register(typs)
                problem = _rosbags_problem(store, t)
            except Exception as exc:  # TypesysError, KeyError, ... : the reader's own errors
                problem = _one_line(exc)
                typs = {}
            if problem:
                out.append(UnreadableChannel(t.name, t.msgtype, ROSBAGS, problem))
            else:
                parsed.append((t, typs))
        if len(parsed) > 1:  # AnyReader merges every definition into one store
            merged: dict = {}
            for _, typs in parsed:
                merged.update(typs)
            store = get_typestore(Stores.EMPTY)
            store.register(merged)
            for t, _ in parsed:
                try:
                    problem = _rosbags_problem(store, t)
                except Exception as exc:
                    problem = _one_line(exc)
                if problem:
                    out.append(UnreadableChannel(
                        t.name, t.msgtype, ROSBAGS,
                        f"{problem} (another channel defines a type it uses differently)"))
        return out


def _rosbags_types(t: BagTopic) -> dict:
    """The type definitions AnyReader takes from the channel's schema."""
    from rosbags.typesys import get_types_from_idl, get_types_from_msg

    if t.encoding == "ros2msg":
        return get_types_from_msg(t.msgdef, t.msgtype)
    if t.encoding in ("ros2idl", "omgidl"):
        typs: dict = {}
        sep = DELIMITER + "\n"
        if t.msgdef.startswith(f"{sep}IDL: "):
            for block in t.msgdef.split(sep)[1:]:
                typs.update(get_types_from_idl(block.split("\n", 1)[1]))
        else:
            typs.update(get_types_from_idl(t.msgdef))
        return typs
    if t.encoding == "":
        return {}
    raise ValueError(f"schema encoding {t.encoding!r} is unknown to rosbags")


def _rosbags_problem(store: object, t: BagTopic) -> str:
    if not t.msgdef:
        return ""  # no definition: AnyReader then needs a default_typestore, not our case
    if t.msgtype not in store.fielddefs:  # type: ignore[attr-defined]
        short = t.msgtype.rsplit("/", 1)[-1]
        named = [n for n in store.fielddefs if n.rsplit("/", 1)[-1] == short]  # type: ignore
        as_what = f"as {named[0]!r}" if named else "under another name"
        return (f"it reads the type {as_what} (its ros2msg parser allows pkg/msg/ and "
                f"pkg/action/ names only): KeyError {t.msgtype!r} in AnyReader")
    if t.type_hash:
        have = store.hash_rihs01(t.msgtype)  # type: ignore[attr-defined]
        if have != t.type_hash:
            return (f"type hash {t.type_hash!r} in metadata.yaml differs from the hash of the "
                    f"definition ({have})")
    return ""


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    msg = text[0] if text else ""
    return f"{type(exc).__name__}: {msg}"[:240]
