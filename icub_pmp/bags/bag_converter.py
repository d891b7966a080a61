"""BagConverter: rewrite a bag with today's schemas, keeping the channels a selection keeps.

What ``ros2 bag convert`` does for one input and one output, and the way to bring a bag
written by an older version of this project up to what every reader decodes: every message is
copied as its CDR bytes with its receive time, the offered QoS profiles are kept, and each
channel gets the schema and RIHS01 hash of :class:`MessageDefinitions`. A channel whose
recorded hash differs from the installed type's (the interface changed since the recording),
or whose type is not installed, keeps its recorded schema and hash: its bytes follow that
definition. Channels the :class:`RecordSelection` does not keep are left out; by default
(every topic) that drops service events and action topics, which the official MCAP ROS 2
decoder cannot decode. A bag whose recording was interrupted is converted up to its last
complete chunk. No ROS import.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from icub_pmp.bags.bag_reader import BagReader, BagTopic
from icub_pmp.bags.bag_writer import BagWriter, TopicHandle, WriteStats
from icub_pmp.bags.message_definitions import MessageDefinitions
from icub_pmp.bags.record_selection import RecordSelection
from icub_pmp.errors import BagError

__all__ = ["BagConverter", "ConvertResult"]


@dataclass(frozen=True)
class ConvertResult:
    """What a conversion wrote, left out, and where it kept the recorded schema."""

    stats: WriteStats
    dropped: tuple[str, ...] = ()  # topics of the input the selection does not keep
    kept_recorded_schema: dict[str, str] = field(default_factory=dict)  # topic -> why


class BagConverter:
    """Copy the bag ``src`` into the new bag directory ``dst``.

    ``selection``: the channels kept (default: every topic, no service events, no action
    topics). ``compression``: ``'none'`` or ``'zstd'``.
    """

    def __init__(
        self,
        src: str | Path,
        dst: str | Path,
        selection: RecordSelection | None = None,
        *,
        compression: str = "none",
        definitions: MessageDefinitions | None = None,
    ):
        self.reader = BagReader(src)
        self.dst = Path(dst)
        if self.dst.resolve() == self.reader.path.resolve():
            raise BagError(f"convert: the output {self.dst} is the input; choose a new directory")
        self.selection = selection or RecordSelection(all_topics=True)
        self.compression = compression
        self.definitions = definitions or MessageDefinitions()

    def run(self) -> ConvertResult:
        """Write the new bag and return what was written (raises BagError on damage)."""
        info = self.reader.info()
        kept = [t for t in info.topics if self.selection.wants(t.name)]
        dropped = tuple(t.name for t in info.topics if not self.selection.wants(t.name))
        if not kept:
            raise BagError(
                f"convert: none of the {len(info.topics)} topics of {self.reader.path} is "
                "selected (service events and action topics need --all-services / "
                "--all-actions)")
        custom = dict((self.reader.metadata or {}).get("custom_data") or {})
        custom["converted_from"] = str(self.reader.path)
        writer = BagWriter(self.dst, compression=self.compression,
                           definitions=self.definitions, custom_data=custom)
        recorded: dict[str, str] = {}
        try:
            handles = {t.name: self._add(writer, t, recorded) for t in kept}
            for m in self.reader.messages(list(handles)):
                writer.write(handles[m.topic], m.log_time, m.data)
        finally:
            stats = writer.close()
        return ConvertResult(stats, dropped, recorded)

    def _add(self, writer: BagWriter, t: BagTopic, recorded: dict[str, str]) -> TopicHandle:
        """Add ``t`` with today's schema, or with its recorded one (reason in ``recorded``)."""
        installed_hash = self.definitions.type_hash(t.msgtype)
        try:
            msgdef = self.definitions.definition(t.msgtype)
        except BagError:
            msgdef = ""
        why = ""
        if not msgdef:
            why = f"{t.msgtype} is not installed here"
        elif t.type_hash.startswith("RIHS01_") and installed_hash and t.type_hash != installed_hash:
            why = (f"the installed {t.msgtype} (hash {installed_hash}) differs from the recorded "
                   f"one ({t.type_hash}): the interface changed since the recording")
        if why:
            if not t.msgdef:
                raise BagError(f"convert: {t.name}: {why}, and the bag holds no schema for it")
            recorded[t.name] = why
            return writer.add_topic(t.name, t.msgtype, qos_profiles=t.qos_profiles,
                                    type_hash=t.type_hash or None, msgdef=t.msgdef)
        return writer.add_topic(t.name, t.msgtype, qos_profiles=t.qos_profiles,
                                type_hash=installed_hash or t.type_hash or None, msgdef=msgdef)
