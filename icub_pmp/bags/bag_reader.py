"""BagReader: read a rosbag2 MCAP bag, also one that was not closed cleanly, and check it.

Messages come out in the order they were written (= the order the recorder received them),
read record by record from the MCAP data section with the official ``mcap`` record classes.
A bag whose recording was killed (no MCAP footer, no ``metadata.yaml``) yields every message of
its complete chunks; a record cut short at the end of the file is reported, not raised. Damage
anywhere else (bad magic, bad record, undecompressable chunk, unknown channel) raises
:class:`~icub_pmp.errors.BagError` with a one-line message naming the file and the byte
offset. No ROS import.
"""

from __future__ import annotations

import os
import struct
from dataclasses import dataclass, field
from io import BytesIO
from pathlib import Path
from typing import Iterable, Iterator, NamedTuple

import yaml
from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, Message, Schema
from mcap.stream_reader import breakup_chunk
from rosbags.interfaces import Qos
from rosbags.rosbag2.errors import ReaderError
from rosbags.rosbag2.metadata import parse_qos

from icub_pmp.errors import BagError

__all__ = ["BagReader", "BagMessage", "BagTopic", "BagInfo", "BagStatus"]

MAGIC = b"\x89MCAP0\r\n"
_FOOTER_LEN = 1 + 8 + 20  # opcode, length, (summary_start, summary_offset_start, crc)
_KNOWN_OPCODES = frozenset(int(o) for o in Opcode)


class BagStatus:
    """Values of :attr:`BagInfo.status`."""

    CLOSED = "closed"  # finalised: MCAP footer and metadata.yaml present
    UNCLOSED = "unclosed"  # recording interrupted (SIGKILL, power loss): no footer, no metadata
    TRUNCATED = "truncated"  # metadata.yaml says finalised, but the .mcap lost its end


class BagMessage(NamedTuple):
    """One recorded message: topic, type, receive time [ns], publish time [ns], CDR bytes."""

    topic: str
    msgtype: str
    log_time: int
    publish_time: int
    data: bytes


@dataclass(frozen=True)
class BagTopic:
    """A recorded topic: type, message count, ros2msg definition, offered QoS profiles."""

    name: str
    msgtype: str
    count: int
    msgdef: str = field(default="", repr=False)
    encoding: str = "ros2msg"
    serialization_format: str = "cdr"
    qos_profiles: tuple[Qos, ...] = ()
    type_hash: str = ""


@dataclass(frozen=True)
class BagInfo:
    """Summary and integrity of a bag (what ``icub bag info`` prints)."""

    path: Path
    files: tuple[Path, ...]
    status: str  # a BagStatus value
    topics: tuple[BagTopic, ...]
    message_count: int
    start_ns: int  # first log time [ns since the epoch] (0 if empty)
    end_ns: int  # last log time [ns]
    size_bytes: int
    compression: str
    notes: tuple[str, ...] = field(default=())  # one line per problem found

    @property
    def closed_cleanly(self) -> bool:
        """True when the recording was finalised and the files are complete."""
        return self.status == BagStatus.CLOSED

    @property
    def duration_s(self) -> float:
        """Last minus first log time [s]."""
        return max(0, self.end_ns - self.start_ns) * 1e-9

    def topic(self, name: str) -> BagTopic:
        """The recorded topic ``name`` (raises BagError listing the topics)."""
        for t in self.topics:
            if t.name == name:
                return t
        raise BagError(f"topic {name!r} is not in {self.path}; topics: "
                       + ", ".join(t.name for t in self.topics))


class _Truncated(Exception):
    def __init__(self, offset: int):
        self.offset = offset


class BagReader:
    """Open the bag at ``path``: a rosbag2 directory or a bare ``.mcap`` file.

    Raises :class:`BagError` when it does not exist, holds no MCAP file, or a file is not
    MCAP. :meth:`info` summarises (and with ``check=True`` scans every chunk);
    :meth:`messages` iterates.
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.metadata: dict | None = None
        if not self.path.exists():
            raise BagError(f"bag {self.path} does not exist")
        if self.path.is_dir():
            meta = self.path / "metadata.yaml"
            if meta.is_file():
                self.metadata = _load_metadata(meta)
                rel = self.metadata.get("relative_file_paths") or []
                files = [self.path / r for r in rel]
                missing = [str(f.name) for f in files if not f.is_file()]
                if missing:
                    raise BagError(
                        f"bag {self.path}: metadata.yaml lists {', '.join(missing)} "
                        "but the file is missing"
                    )
                storage = self.metadata.get("storage_identifier", "mcap")
                if storage != "mcap":
                    raise BagError(
                        f"bag {self.path} uses storage {storage!r}; only mcap bags are supported"
                    )
            else:
                files = sorted(self.path.glob("*.mcap"))
            if not files:
                raise BagError(f"{self.path} is not a bag: no metadata.yaml and no .mcap file")
        elif self.path.suffix == ".mcap":
            files = [self.path]
        else:
            raise BagError(f"{self.path} is not a bag directory or an .mcap file")
        self.files: tuple[Path, ...] = tuple(files)
        self._footer = {f: _check_magic_and_footer(f) for f in self.files}
        self.truncated_at: dict[Path, int] = {}  # file -> byte offset of the cut record

    # ------------------------------------------------------------------ status
    @property
    def status(self) -> str:
        """BagStatus of the files (from the footers and metadata.yaml only)."""
        if all(self._footer.values()) and self.metadata is not None:
            return BagStatus.CLOSED
        if self.metadata is None and not self.path.is_file():
            return BagStatus.UNCLOSED
        if self.metadata is None and all(self._footer.values()):
            return BagStatus.CLOSED  # a bare, finalised .mcap
        return BagStatus.UNCLOSED if self.metadata is None else BagStatus.TRUNCATED

    # ------------------------------------------------------------------ messages
    def messages(self, topics: Iterable[str] | None = None) -> Iterator[BagMessage]:
        """Messages in written order, optionally only those on ``topics``.

        Stops quietly at a record cut by the end of the file (the offset is then in
        :attr:`truncated_at`); raises :class:`BagError` on any other damage.
        """
        wanted = None if topics is None else set(topics)
        for f in self.files:
            channels: dict[int, tuple[str, str]] = {}
            schemas: dict[int, str] = {}
            for rec, offset in self._records(f):
                if isinstance(rec, Schema):
                    schemas[rec.id] = rec.name
                elif isinstance(rec, Channel):
                    channels[rec.id] = (rec.topic, schemas.get(rec.schema_id, ""))
                elif isinstance(rec, Message):
                    ch = channels.get(rec.channel_id)
                    if ch is None:
                        raise BagError(
                            f"{f}: corrupt: message for unknown channel {rec.channel_id} "
                            f"near byte {offset}"
                        )
                    if wanted is None or ch[0] in wanted:
                        yield BagMessage(ch[0], ch[1], rec.log_time, rec.publish_time, rec.data)

    # ------------------------------------------------------------------ info
    def info(self, check: bool = False) -> BagInfo:
        """Summary of the bag. A finalised bag is summarised from its MCAP index unless
        ``check``; otherwise every record is read (raises BagError on damage)."""
        size = sum(f.stat().st_size for f in self.files)
        notes: list[str] = []
        status = self.status
        compression = (self.metadata or {}).get("compression_format") or ""
        fast = status == BagStatus.CLOSED and not check
        summary = _summaries(self.files) if fast else None
        if summary is not None:
            topics, count, start, end, comp = summary
        else:
            topics, count, start, end, comp = self._scan_info()
        compression = compression or comp
        meta_counts = _metadata_counts(self.metadata)
        meta_topics = _metadata_topics(self.metadata)
        topics = [
            BagTopic(t.name, t.msgtype, t.count, t.msgdef, t.encoding, t.serialization_format,
                     t.qos_profiles, meta_topics.get(t.name, ("", ""))[1])
            for t in topics
        ]
        if status == BagStatus.UNCLOSED:
            cut = ", ".join(f"{f.name} at byte {o}" for f, o in self.truncated_at.items())
            notes.append(
                "not closed cleanly: the recording was interrupted (no MCAP footer, no "
                f"metadata.yaml); {count} messages in complete chunks are readable"
                + (f"; incomplete data from {cut} ignored" if cut else "")
            )
        elif status == BagStatus.TRUNCATED:
            expected = sum(meta_counts.values())
            notes.append(
                f"truncated: metadata.yaml lists {expected} messages but the .mcap file lost "
                f"its end; {count} messages are readable"
            )
        elif meta_counts:
            for t in topics:
                if t.name in meta_counts and meta_counts[t.name] != t.count:
                    notes.append(
                        f"{t.name}: metadata.yaml lists {meta_counts[t.name]} messages, "
                        f"the .mcap holds {t.count}"
                    )
        return BagInfo(
            path=self.path,
            files=self.files,
            status=status,
            topics=tuple(sorted(topics, key=lambda t: t.name)),
            message_count=count,
            start_ns=start,
            end_ns=end,
            size_bytes=size,
            compression=compression or "none",
            notes=tuple(notes),
        )

    def _scan_info(self) -> tuple[list[BagTopic], int, int, int, str]:
        counts: dict[int, int] = {}
        chans: dict[tuple[Path, int], Channel] = {}
        schemas: dict[tuple[Path, int], Schema] = {}
        start, end, total, comp = 2**63 - 1, 0, 0, ""
        for f in self.files:
            for rec, _ in self._records(f, want_chunk_compression=True):
                if isinstance(rec, str):
                    comp = comp or rec
                elif isinstance(rec, Schema):
                    schemas[(f, rec.id)] = rec
                elif isinstance(rec, Channel):
                    chans.setdefault((f, rec.id), rec)
                elif isinstance(rec, Message):
                    key = (f, rec.channel_id)
                    if key not in chans:
                        raise BagError(f"{f}: corrupt: message for unknown channel "
                                       f"{rec.channel_id}")
                    counts[id(chans[key])] = counts.get(id(chans[key]), 0) + 1
                    total += 1
                    start = min(start, rec.log_time)
                    end = max(end, rec.log_time)
        topics = _merge_topics(
            (c, schemas.get((f, c.schema_id)), counts.get(id(c), 0)) for (f, _), c in chans.items()
        )
        return topics, total, (start if total else 0), end, comp

    # ------------------------------------------------------------------ records
    def _records(self, f: Path, want_chunk_compression: bool = False) -> Iterator[tuple]:
        """(record, file offset) of Schema/Channel/Message records in the data section."""
        try:
            fh = f.open("rb")
        except OSError as exc:
            raise BagError(f"cannot open {f}: {exc.strerror}") from None
        with fh:
            size = os.fstat(fh.fileno()).st_size
            fh.seek(len(MAGIC))
            offset = len(MAGIC)
            while True:
                head = fh.read(9)
                if not head:
                    return  # ends on a record boundary (unclosed, no footer)
                if len(head) < 9:
                    self.truncated_at[f] = offset
                    return
                opcode, length = struct.unpack("<BQ", head)
                if opcode not in _KNOWN_OPCODES and opcode < 0x80:
                    raise BagError(
                        f"{f}: corrupt: invalid MCAP record opcode 0x{opcode:02x} at byte {offset}"
                    )
                if offset + 9 + length > size:
                    self.truncated_at[f] = offset
                    return
                if opcode in (Opcode.FOOTER, Opcode.DATA_END):
                    return
                if opcode in (Opcode.CHUNK, Opcode.SCHEMA, Opcode.CHANNEL, Opcode.MESSAGE):
                    body = fh.read(length)
                    try:
                        yield from _parse(opcode, body, want_chunk_compression, offset)
                    except BagError:
                        raise
                    except Exception as exc:  # any parse failure of a complete record = damage
                        raise BagError(
                            f"{f}: corrupt {Opcode(opcode).name.lower()} record at byte "
                            f"{offset}: {exc or type(exc).__name__}"
                        ) from None
                else:
                    fh.seek(length, os.SEEK_CUR)
                offset += 9 + length


def _parse(opcode: int, body: bytes, want_comp: bool, offset: int) -> Iterator[tuple]:
    stream = ReadDataStream(BytesIO(body))
    if opcode == Opcode.CHUNK:
        chunk = Chunk.read(stream)
        if stream.count != len(body) or (
            not chunk.compression and len(chunk.data) != chunk.uncompressed_size
        ):
            raise ValueError("chunk lengths do not match its record")
        if want_comp and chunk.compression:
            yield chunk.compression, offset
        records = breakup_chunk(chunk, validate_crc=True)
        for r in records:
            yield r, offset
    elif opcode == Opcode.SCHEMA:
        yield Schema.read(stream), offset
    elif opcode == Opcode.CHANNEL:
        yield Channel.read(stream), offset
    else:
        yield Message.read(stream, len(body)), offset


def _check_magic_and_footer(f: Path) -> bool:
    """Check the leading magic (raises BagError); True when the file ends with a footer."""
    try:
        with f.open("rb") as fh:
            head = fh.read(len(MAGIC))
            size = os.fstat(fh.fileno()).st_size
            if size < len(MAGIC):
                raise BagError(f"{f} is truncated: only {size} bytes, not even an MCAP header")
            if head != MAGIC:
                raise BagError(f"{f} is not an MCAP file (bad magic bytes)")
            if size < len(MAGIC) * 2 + _FOOTER_LEN:
                return False
            fh.seek(size - len(MAGIC) - _FOOTER_LEN)
            tail = fh.read()
    except OSError as exc:
        raise BagError(f"cannot read {f}: {exc.strerror}") from None
    return tail[-len(MAGIC):] == MAGIC and tail[0] == Opcode.FOOTER


def _load_metadata(meta: Path) -> dict:
    try:
        doc = yaml.safe_load(meta.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        line = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise BagError(f"{meta} is not valid YAML: {line}") from None
    info = doc.get("rosbag2_bagfile_information") if isinstance(doc, dict) else None
    if not isinstance(info, dict):
        raise BagError(f"{meta} has no rosbag2_bagfile_information section")
    return info


def _metadata_counts(meta: dict | None) -> dict[str, int]:
    out: dict[str, int] = {}
    for t in (meta or {}).get("topics_with_message_count") or []:
        try:
            out[t["topic_metadata"]["name"]] = int(t["message_count"])
        except (KeyError, TypeError, ValueError):
            continue
    return out


def _metadata_topics(meta: dict | None) -> dict[str, tuple[str, str]]:
    out: dict[str, tuple[str, str]] = {}
    for t in (meta or {}).get("topics_with_message_count") or []:
        try:
            tm = t["topic_metadata"]
            out[tm["name"]] = (tm.get("type", ""), tm.get("type_description_hash", ""))
        except (KeyError, TypeError):
            continue
    return out


def _qos_from_channel(ch: Channel) -> tuple[Qos, ...]:
    text = (ch.metadata or {}).get("offered_qos_profiles", "")
    try:
        return tuple(parse_qos(text)) if text else ()
    except (ReaderError, KeyError, TypeError):
        return ()


def _merge_topics(items: Iterable[tuple[Channel, Schema | None, int]]) -> list[BagTopic]:
    by_name: dict[str, BagTopic] = {}
    for ch, schema, n in items:
        old = by_name.get(ch.topic)
        if old is not None:
            by_name[ch.topic] = BagTopic(old.name, old.msgtype, old.count + n, old.msgdef,
                                         old.encoding, old.serialization_format,
                                         old.qos_profiles, old.type_hash)
            continue
        by_name[ch.topic] = BagTopic(
            name=ch.topic,
            msgtype=schema.name if schema else "",
            count=n,
            msgdef=schema.data.decode("utf-8", "replace") if schema else "",
            encoding=schema.encoding if schema else "",
            serialization_format=ch.message_encoding,
            qos_profiles=_qos_from_channel(ch),
        )
    return list(by_name.values())


def _summaries(files: Iterable[Path]) -> tuple[list[BagTopic], int, int, int, str] | None:
    """Topics and statistics from the summary sections (None if one has no statistics)."""
    from mcap.reader import make_reader

    items: list[tuple[Channel, Schema | None, int]] = []
    total, start, end, comp = 0, 2**63 - 1, 0, ""
    for f in files:
        try:
            with f.open("rb") as fh:
                summary = make_reader(fh).get_summary()
        except Exception as exc:  # a damaged summary section
            raise BagError(f"{f}: corrupt summary section: {exc}") from None
        if summary is None or summary.statistics is None:
            return None
        st = summary.statistics
        for cid, ch in summary.channels.items():
            items.append((ch, summary.schemas.get(ch.schema_id),
                          st.channel_message_counts.get(cid, 0)))
        total += st.message_count
        if st.message_count:
            start, end = min(start, st.message_start_time), max(end, st.message_end_time)
        for ci in summary.chunk_indexes:
            comp = comp or ci.compression
    return _merge_topics(items), total, (start if total else 0), end, comp
