"""BagWriter: a rosbag2 bag (``metadata.yaml`` + one ``.mcap``) written with ``rosbags``.

The layout is what ``ros2 bag record -s mcap`` writes: a directory holding ``metadata.yaml``
(rosbag2 format version 9) and an MCAP file of CDR messages with the schemas of
:class:`MessageDefinitions`, each topic's RIHS01 type hash and its offered QoS profiles, so a
stock ``ros2 bag play``, rosbags, Foxglove and the official ``mcap`` readers open it (which
channel which reader decodes: :class:`ReaderCheck`). Nothing is serialised here: messages
arrive as the CDR bytes taken off the wire.

Crash safety: rosbags writes a chunk to the file every 1 MiB; this class also closes the
pending chunk every ``flush_interval`` seconds and flushes the file after every chunk, so
after a SIGKILL everything up to the last flushed chunk is readable (:class:`BagReader`
recovers it; ``metadata.yaml`` is only written by :meth:`close`, so its absence marks a bag
that was not closed cleanly). No ROS import.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

from rosbags.interfaces import Qos
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.rosbag2.enums import CompressionFormat, CompressionMode
from rosbags.rosbag2.errors import WriterError

from icub_pmp.bags.message_definitions import MessageDefinitions
from icub_pmp.errors import BagError, InvalidInput

__all__ = ["BagWriter", "TopicHandle", "WriteStats", "COMPRESSIONS"]

COMPRESSIONS = ("none", "zstd")


@dataclass(frozen=True)
class TopicHandle:
    """A topic added to a :class:`BagWriter` (pass it to :meth:`BagWriter.write`)."""

    topic: str
    msgtype: str
    connection: object


@dataclass(frozen=True)
class WriteStats:
    """What a closed :class:`BagWriter` wrote."""

    path: Path
    counts: Mapping[str, int]  # messages written per topic
    bytes_written: int  # size of the .mcap file [bytes]
    duration_s: float  # last minus first log time [s]

    @property
    def total(self) -> int:
        """Messages written on all topics."""
        return sum(self.counts.values())


class BagWriter:
    """Write CDR messages into a new rosbag2 MCAP bag directory ``path``.

    ``compression``: ``'none'`` or ``'zstd'`` (MCAP chunk compression, what
    ``ros2 bag record --compression-format zstd`` with the mcap storage preset does).
    ``flush_interval`` [s]: longest time a written message may stay in memory before its chunk
    reaches the file. ``custom_data``: strings stored in ``metadata.yaml``.
    """

    def __init__(
        self,
        path: str | Path,
        *,
        compression: str = "none",
        flush_interval: float = 0.5,
        definitions: MessageDefinitions | None = None,
        custom_data: Mapping[str, str] | None = None,
    ):
        if compression not in COMPRESSIONS:
            raise InvalidInput(
                f"compression: got {compression!r}, expected one of {', '.join(COMPRESSIONS)}"
            )
        if not flush_interval > 0:
            raise InvalidInput(f"flush_interval: expected > 0 s, got {flush_interval}")
        self.path = Path(path)
        if self.path.exists():
            raise BagError(f"{self.path} exists already; choose a new bag directory")
        self.flush_interval = float(flush_interval)
        self.definitions = definitions or MessageDefinitions()
        self._writer = Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
        if compression == "zstd":
            self._writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        for k, v in (custom_data or {}).items():
            self._writer.set_custom_data(str(k), str(v))
        try:
            self._writer.open()
        except (WriterError, OSError) as exc:
            raise BagError(f"cannot create bag {self.path}: {exc}") from None
        self._storage = self._writer.storage
        self._topics: dict[str, TopicHandle] = {}
        self._counts: dict[str, int] = {}
        self._chunks_flushed = 0
        self._last_flush = time.monotonic()
        self._closed = False
        self.write_error = ""  # why a write failed (disk full, size limit), "" while none did

    # ------------------------------------------------------------------ topics
    @property
    def topics(self) -> Mapping[str, TopicHandle]:
        """Topics added so far, by name."""
        return dict(self._topics)

    def add_topic(
        self,
        topic: str,
        msgtype: str,
        *,
        qos_profiles: Sequence[Qos] = (),
        type_hash: str | None = None,
        msgdef: str | None = None,
    ) -> TopicHandle:
        """Add ``topic`` of ``msgtype`` ('pkg/kind/Type') with its publishers' offered QoS.

        ``type_hash``: the RIHS01 hash seen on the graph (default: from the installed type
        description files, see :meth:`MessageDefinitions.type_hash`). ``msgdef``: the complete
        definition, ``ros2msg`` or rosbag2's ``ros2idl`` layout (default: from
        :class:`MessageDefinitions`).
        """
        self._check_open()
        if topic in self._topics:
            raise InvalidInput(f"topic {topic!r} was already added to {self.path}")
        if msgdef is None:
            msgdef = self.definitions.definition(msgtype)
        if not type_hash:
            type_hash = self.definitions.type_hash(msgtype)
        try:
            conn = self._writer.add_connection(
                topic,
                msgtype,
                msgdef=msgdef,
                rihs01=type_hash or "unknown",
                offered_qos_profiles=list(qos_profiles),
            )
        except WriterError as exc:
            raise BagError(f"cannot add topic {topic} to {self.path}: {exc}") from None
        handle = TopicHandle(topic, msgtype, conn)
        self._topics[topic] = handle
        self._counts[topic] = 0
        return handle

    # ------------------------------------------------------------------ messages
    def write(self, handle: TopicHandle, log_time_ns: int, data: bytes | memoryview) -> None:
        """Append one CDR message received at ``log_time_ns`` [ns since the epoch]."""
        self._check_open()
        try:
            self._writer.write(handle.connection, int(log_time_ns), data)
            self._counts[handle.topic] += 1
            if len(self._storage.chunks) != self._chunks_flushed:  # rosbags closed a chunk
                self._flush_file()
        except OSError as exc:
            raise self._write_failed(exc) from None

    def flush(self) -> None:
        """Write the pending chunk (if any) to the file now and flush the file."""
        self._check_open()
        try:
            if self._storage.chunk.msgs:  # messages in the open chunk
                self._storage.close_chunk()
            self._flush_file()
        except OSError as exc:
            raise self._write_failed(exc) from None

    def _write_failed(self, exc: OSError) -> BagError:
        """The error of a write the file system refused (disk full, file size limit): the
        bag keeps every chunk flushed before it."""
        self.write_error = (f"cannot write to {self._storage.path}: "
                            f"{exc.strerror or exc} (errno {exc.errno}); the bag is readable "
                            "up to its last complete chunk")
        return BagError(self.write_error)

    def flush_if_due(self) -> bool:
        """:meth:`flush` when ``flush_interval`` has passed since the last one."""
        if time.monotonic() - self._last_flush >= self.flush_interval:
            self.flush()
            return True
        return False

    def _flush_file(self) -> None:
        self._storage.bio.flush()
        self._chunks_flushed = len(self._storage.chunks)
        self._last_flush = time.monotonic()

    # ------------------------------------------------------------------ close
    @property
    def counts(self) -> Mapping[str, int]:
        """Messages written so far per topic."""
        return dict(self._counts)

    @property
    def closed(self) -> bool:
        """True after :meth:`close`."""
        return self._closed

    def close(self) -> WriteStats:
        """Finalise: last chunk, summary and footer of the .mcap, then ``metadata.yaml``."""
        if self._closed:
            raise BagError(f"bag {self.path} is already closed")
        w = self._writer
        duration = max(0, w.max_timestamp - w.min_timestamp) * 1e-9
        mcap_path = self._storage.path
        try:
            w.close()
        except (WriterError, OSError) as exc:
            raise BagError(f"cannot finalise bag {self.path}: {exc}") from None
        finally:
            self._closed = True
        return WriteStats(self.path, dict(self._counts), mcap_path.stat().st_size, duration)

    def _check_open(self) -> None:
        if self._closed:
            raise BagError(f"bag {self.path} is closed")

    def __enter__(self) -> "BagWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        if not self._closed:
            self.close()
