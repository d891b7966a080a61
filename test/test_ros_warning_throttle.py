"""WarningThrottle: each kind of warning has its own budget (a frequent one does not hide a
rare one), and the next logged warning counts those held back."""

from __future__ import annotations

from icub_pmp.ros.warning_throttle import WarningThrottle


class _Logger:
    def __init__(self) -> None:
        self.lines: list[str] = []

    def warning(self, text: str) -> None:
        self.lines.append(text)


def test_one_budget_per_kind_and_the_held_back_are_counted(fake_clock):
    log = _Logger()
    warn = WarningThrottle(log, 2.0, fake_clock)
    assert warn("stale", "FT stale")
    assert not warn("stale", "FT stale")
    assert warn("bad", "a message dropped on arrival")  # not hidden by the frequent one
    fake_clock.t += 2.5
    assert warn("stale", "FT stale")
    assert log.lines == ["FT stale", "a message dropped on arrival",
                         "FT stale (1 more like it held back)"]
    assert warn.count == 4
