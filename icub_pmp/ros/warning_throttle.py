"""WarningThrottle: throttled warnings with one budget per kind of warning.

rclpy's ``throttle_duration_sec`` keys the throttle on the call site: a node that routes every
warning through one helper method shares one budget between all of them, and a frequent
warning ("FT stale") hides a rarer one ("a message dropped on arrival") for good. Here each
kind has its own period, and the next warning of a kind says how many were held back.
"""

from __future__ import annotations

import math
import time
from typing import Any, Callable

__all__ = ["WarningThrottle"]


class WarningThrottle:
    """Log ``warning(text)`` at most once per ``period`` [s] of wall time per kind.

    Args:
        logger: an rclpy logger (anything with ``warning(str)``).
        period: the shortest interval between two warnings of one kind [s].
        clock: wall clock [s] (default ``time.monotonic``).
    """

    def __init__(self, logger: Any, period: float = 2.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.logger = logger
        self.period = float(period)
        self._clock = clock
        self._last: dict[str, float] = {}
        self._held: dict[str, int] = {}
        self.count = 0  # warnings of every kind, logged or held back

    def __call__(self, kind: str, text: str) -> bool:
        """Count a warning of ``kind``; log ``text`` unless one of that kind was logged less
        than ``period`` ago. Returns whether it was logged."""
        self.count += 1
        now = self._clock()
        if now - self._last.get(kind, -math.inf) < self.period:
            self._held[kind] = self._held.get(kind, 0) + 1
            return False
        held = self._held.pop(kind, 0)
        self._last[kind] = now
        more = f" ({held} more like it held back)" if held else ""
        self.logger.warning(text + more)
        return True
