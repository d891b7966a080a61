"""TimeJumpDetector: notice that a stream's clock went back, as ROS time sources (jump
callbacks) and tf2 buffers (cleared on a backward jump) do.

Simulated time starts again from 0 when the simulator is restarted. A node that keeps state
ordered in time (a stamp synchroniser that processes only newer samples, filters that
differentiate, a stereo pairing that skips older frames) would otherwise drop everything until
the new time passes the old maximum, silently. Feed it every stamp of the stream that carries
the clock (:meth:`observe`); a stamp older than the newest seen by more than ``tolerance_ns``
is a jump back: say so (:meth:`TimeJump.describe`), clear the time-ordered state and go on at
once with that stamp.
"""

from __future__ import annotations

from typing import NamedTuple

from icub_pmp.errors import InvalidInput

__all__ = ["TimeJumpDetector", "TimeJump"]


class TimeJump(NamedTuple):
    """A backward jump of a stream's clock: from the newest stamp seen to the new one [ns]."""

    from_ns: int
    to_ns: int

    def describe(self) -> str:
        """E.g. 'simulated time went back from t = 198.654 s to t = 0.001 s'."""
        return (f"simulated time went back from t = {self.from_ns * 1e-9:.3f} s to "
                f"t = {self.to_ns * 1e-9:.3f} s")


class TimeJumpDetector:
    """Detect backward jumps in a stream of stamps (module doc).

    Args:
        tolerance_ns: a stamp at most this much older than the newest is not a jump (>= 0)
            [ns]; 0: any older stamp is one.
    """

    def __init__(self, tolerance_ns: int = 0) -> None:
        if tolerance_ns < 0:
            raise InvalidInput(f"tolerance_ns: expected >= 0 ns, got {tolerance_ns}")
        self.tolerance_ns = int(tolerance_ns)
        self.newest_ns: int | None = None
        self.jumps = 0

    def observe(self, stamp_ns: int) -> TimeJump | None:
        """Take the stamp ``stamp_ns`` [ns] of the next message: the :class:`TimeJump` when
        it is a jump back (it then becomes the newest), else None."""
        stamp_ns = int(stamp_ns)
        newest = self.newest_ns
        if newest is not None and stamp_ns < newest - self.tolerance_ns:
            self.newest_ns = stamp_ns
            self.jumps += 1
            return TimeJump(newest, stamp_ns)
        if newest is None or stamp_ns > newest:
            self.newest_ns = stamp_ns
        return None

    def reset(self) -> None:
        """Forget the newest stamp (the next one starts a new timeline)."""
        self.newest_ns = None
