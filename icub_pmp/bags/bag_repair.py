"""BagRepair: make a bag whose recording was interrupted (SIGKILL, power loss, disk full) or
whose file was cut into a finalised bag that every reader opens.

An interrupted MCAP recording has no summary section, no footer and no ``metadata.yaml``;
rosbags' rosbag2 Reader and ``ros2 bag play`` refuse such a directory, and the ``mcap``
readers can only scan it. Repairing copies every message of the complete chunks (what
:class:`BagReader` recovers; the record cut by the end of the file is reported and left out)
into a new bag written by :class:`BagWriter` - chunk index, summary, footer and
``metadata.yaml`` - with every channel kept (service events, action topics and hidden topics
included) and each channel's recorded schema where the installed type differs.

Nothing is lost: in place, the damaged original is kept beside the repaired bag as
``<bag>.damaged`` (or ``<bag>.damaged.N``). What ``ros2 bag reindex`` does for a bag that lost
its ``metadata.yaml``, plus the MCAP summary the recovery tools of the ``mcap`` CLI write. No
ROS import.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

from icub_pmp.bags.bag_converter import BagConverter
from icub_pmp.bags.bag_reader import BagReader, BagStatus
from icub_pmp.bags.bag_writer import WriteStats
from icub_pmp.bags.record_selection import RecordSelection
from icub_pmp.errors import BagError

__all__ = ["BagRepair", "RepairResult", "EVERY_CHANNEL"]

#: every channel a bag may hold: topics, hidden topics, service events, action topics
EVERY_CHANNEL = RecordSelection(all_topics=True, include_hidden_topics=True, all_services=True,
                                all_actions=True)


@dataclass(frozen=True)
class RepairResult:
    """What :meth:`BagRepair.run` did."""

    path: Path  # the repaired (finalised) bag
    status_before: str  # BagStatus of the input
    stats: WriteStats | None  # None when nothing needed repairing
    damaged_kept_at: Path | None  # where the original went (in place), else None
    cut: tuple[str, ...] = ()  # "file at byte N": incomplete data left out
    kept_recorded_schema: tuple[str, ...] = ()  # topics written with their recorded schema

    @property
    def repaired(self) -> bool:
        """Whether a new bag was written."""
        return self.stats is not None


class BagRepair:
    """Repair the bag ``path`` (a bag directory or a bare ``.mcap``).

    ``output``: the directory of the repaired bag; default: in place for a directory (the
    original moves to ``<bag>.damaged``), ``<stem>_repaired`` beside a bare ``.mcap``.
    ``force``: rewrite a bag that was closed cleanly too (a no-op answer otherwise).
    """

    def __init__(self, path: str | Path, output: str | Path | None = None, *, force: bool = False):
        self.path = Path(path)
        if not self.path.exists():
            raise BagError(f"repair: {self.path} does not exist")
        self.output = None if output is None else Path(output)
        self.force = force
        if self.output is not None and self.output.exists():
            raise BagError(f"repair: the output {self.output} exists already; choose a new "
                           "directory")

    def run(self) -> RepairResult:
        """Repair; raises :class:`BagError` when not even the start of the bag is readable."""
        reader = BagReader(self.path)
        status = reader.status
        if status == BagStatus.CLOSED and not self.force:
            return RepairResult(self.path, status, None, None)
        in_place = self.output is None and self.path.is_dir()
        if self.output is not None:
            target = self.output
        elif in_place:
            target = self.path.with_name(self.path.name + ".repair-tmp")
            if target.exists():  # a previous repair interrupted before its swap
                shutil.rmtree(target)
        else:
            target = self.path.with_name(self.path.stem + "_repaired")
            if target.exists():
                raise BagError(f"repair: {target} exists already; give --output")
        compression, readable = self._contents(reader)
        if not readable:
            raise BagError(f"repair: {self.path} holds no complete chunk (the recording "
                           "stopped before its first chunk reached the file): nothing to "
                           "recover")
        converter = BagConverter(self.path, target, EVERY_CHANNEL, compression=compression)
        try:
            result = converter.run()
        except BagError as exc:
            if target.exists() and (in_place or self.output is None):
                shutil.rmtree(target, ignore_errors=True)
            raise BagError(f"repair of {self.path} failed: {exc}") from None
        cut = tuple(f"{f.name} at byte {o}" for f, o in converter.reader.truncated_at.items())
        damaged = None
        if in_place:
            damaged = _free_name(self.path.with_name(self.path.name + ".damaged"))
            self.path.rename(damaged)
            target.rename(self.path)
            target = self.path
        return RepairResult(target, status, result.stats, damaged, cut,
                            tuple(sorted(result.kept_recorded_schema)))

    @staticmethod
    def _contents(reader: BagReader) -> tuple[str, int]:
        """The input's chunk compression (``zstd`` or ``none``) and its readable messages."""
        info = reader.info(check=True)
        return ("zstd" if info.compression == "zstd" else "none"), info.message_count


def _free_name(path: Path) -> Path:
    """``path``, or ``path.N`` for the first N not taken."""
    if not path.exists():
        return path
    n = 1
    while path.with_name(f"{path.name}.{n}").exists():
        n += 1
    return path.with_name(f"{path.name}.{n}")
