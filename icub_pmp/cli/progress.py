"""ProgressLine: a one-line progress bar for long CLI goals (redrawn on a terminal, a line per
second otherwise, so logs stay readable)."""

from __future__ import annotations

import time
from typing import TextIO

__all__ = ["ProgressLine"]


class ProgressLine:
    """Shows ``[#####.....]  45 %  text`` on ``stream``."""

    def __init__(self, stream: TextIO, width: int = 24, period: float = 1.0):
        self.stream = stream
        self.width = width
        self.period = period
        self.tty = hasattr(stream, "isatty") and stream.isatty()
        self._last = 0.0
        self._shown = False

    def show(self, fraction: float, text: str) -> None:
        """Redraw with ``fraction`` in [0, 1] done and ``text``."""
        f = min(1.0, max(0.0, fraction if fraction == fraction else 0.0))
        n = int(round(f * self.width))
        line = f"[{'#' * n}{'.' * (self.width - n)}] {f * 100:3.0f} %  {text}"
        now = time.monotonic()
        if self.tty:
            self.stream.write("\r" + line[:160].ljust(80))
            self._shown = True
        elif now - self._last >= self.period:
            self.stream.write(line + "\n")
            self._last = now
        self.stream.flush()

    def done(self) -> None:
        """End the line (terminal only)."""
        if self.tty and self._shown:
            self.stream.write("\n")
            self.stream.flush()
            self._shown = False
