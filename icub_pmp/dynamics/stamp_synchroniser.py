"""StampSynchroniser: pairs a primary stream (joint states) with secondary streams (the arm FT
wrenches) by message stamp, for the wrench estimator.

Two policies, as wholeBodyDynamics reads its ports:

- exact stamps (lockstep with the simulator): a sample is complete when the primary item and
  every secondary item of the same stamp have arrived, in any order (:meth:`match`); items
  older than a completed sample are dropped: the estimator never goes back in time;
- latest (free-running sensors): each primary item is paired with the newest item of every
  secondary stream, unless one is older than ``stale_timeout`` (:meth:`latest`).

In both, a stamp is processed at most once and never one older than the last processed
(:meth:`release`). Buffers hold at most ``buffer`` items per stream (the earliest received
go first: after a clock jump back the new, smaller stamps are kept, not evicted).
:meth:`reset` forgets everything, e.g. when the clock jumps back.
"""

from __future__ import annotations

from typing import Generic, Hashable, NamedTuple, Sequence, TypeVar

from icub_pmp.errors import InvalidInput

__all__ = ["StampSynchroniser", "SyncedSample"]

T = TypeVar("T")


class SyncedSample(NamedTuple, Generic[T]):
    """A complete sample: stamp [ns], the primary item and one item per secondary key."""

    stamp_ns: int
    primary: T
    secondary: dict[Hashable, T]


class StampSynchroniser(Generic[T]):
    """Buffers and pairs items by stamp (module doc).

    Args:
        keys: the secondary streams (e.g. the hands of the arm FT sensors).
        buffer: items kept per stream while waiting for their partners (>= 1).
    """

    def __init__(self, keys: Sequence[Hashable], buffer: int = 64) -> None:
        if not keys:
            raise InvalidInput("keys: expected at least one secondary stream, got none")
        if buffer < 1:
            raise InvalidInput(f"buffer: expected >= 1 item, got {buffer}")
        self.keys = tuple(keys)
        self.buffer = int(buffer)
        self._primary: dict[int, T] = {}
        self._secondary: dict[Hashable, dict[int, T]] = {k: {} for k in self.keys}
        self.last_ns = -1  # the stamp last released [ns]

    def reset(self) -> None:
        """Forget every buffered item and the last released stamp."""
        self._primary.clear()
        for buf in self._secondary.values():
            buf.clear()
        self.last_ns = -1

    # ------------------------------------------------------------------ input
    def add_primary(self, stamp_ns: int, item: T) -> None:
        """Buffer a primary item (joint state) stamped ``stamp_ns`` [ns]."""
        self._put(self._primary, stamp_ns, item)

    def add(self, key: Hashable, stamp_ns: int, item: T) -> None:
        """Buffer an item of the secondary stream ``key`` stamped ``stamp_ns`` [ns]."""
        buf = self._secondary.get(key)
        if buf is None:
            raise InvalidInput(f"unknown stream {key!r}; valid: {list(self.keys)}")
        self._put(buf, stamp_ns, item)

    def has_primary(self, stamp_ns: int) -> bool:
        """Whether the primary item of ``stamp_ns`` is buffered."""
        return stamp_ns in self._primary

    def _put(self, buf: dict[int, T], stamp_ns: int, item: T) -> None:
        buf[stamp_ns] = item
        if len(buf) > self.buffer:
            del buf[next(iter(buf))]  # the earliest received (dicts keep insertion order)

    # ------------------------------------------------------------------ pairing
    def match(self, stamp_ns: int) -> SyncedSample[T] | None:
        """The complete sample of ``stamp_ns`` (exact stamps), removed from the buffers with
        every older item; None while an item of that stamp is missing."""
        if stamp_ns not in self._primary or any(
                stamp_ns not in buf for buf in self._secondary.values()):
            return None
        primary = self._primary.pop(stamp_ns)
        secondary = {k: buf.pop(stamp_ns) for k, buf in self._secondary.items()}
        for buf in (self._primary, *self._secondary.values()):
            for old in [s for s in buf if s < stamp_ns]:  # never go back in time
                del buf[old]
        return SyncedSample(stamp_ns, primary, secondary)

    def latest(self, stamp_ns: int, stale_timeout: float) -> dict[Hashable, T]:
        """The newest item of each secondary stream for a primary item of ``stamp_ns``
        (latest policy). Raises :class:`InvalidInput` when a stream has no item yet or its
        newest is more than ``stale_timeout`` [s] older than ``stamp_ns``."""
        out: dict[Hashable, T] = {}
        for key, buf in self._secondary.items():
            if not buf:
                raise InvalidInput(f"no {key} item received yet")
            newest = max(buf)
            age = (stamp_ns - newest) * 1e-9
            if age > stale_timeout:
                raise InvalidInput(f"{key} is stale ({age:.3f} s older than the primary "
                                   f"stream, limit {stale_timeout} s)")
            out[key] = buf[newest]
        return out

    def release(self, stamp_ns: int) -> bool:
        """Claim ``stamp_ns`` for processing: False when it is not newer than the stamp last
        released (a duplicate or a step back in time), else True (and it becomes the last)."""
        if stamp_ns <= self.last_ns:
            return False
        self.last_ns = stamp_ns
        return True
