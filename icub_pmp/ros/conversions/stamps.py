"""builtin_interfaces Time / Duration <-> seconds [s] (and Time -> nanoseconds)."""

from __future__ import annotations

from builtin_interfaces.msg import Duration, Time

__all__ = ["time_to_sec", "time_to_ns", "sec_to_time", "sec_to_duration", "duration_to_sec"]


def time_to_sec(t: Time) -> float:
    """builtin_interfaces/Time -> seconds."""
    return t.sec + t.nanosec * 1e-9


def time_to_ns(t: Time) -> int:
    """builtin_interfaces/Time -> integer nanoseconds (exact: stamps compare equal)."""
    return t.sec * 1_000_000_000 + t.nanosec


def sec_to_time(s: float) -> Time:
    """Seconds -> builtin_interfaces/Time (rounded to the nanosecond)."""
    ns = int(round(s * 1e9))
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def sec_to_duration(s: float) -> Duration:
    """Seconds -> builtin_interfaces/Duration."""
    ns = int(round(s * 1e9))
    return Duration(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def duration_to_sec(d: Duration) -> float:
    """builtin_interfaces/Duration -> seconds."""
    return d.sec + d.nanosec * 1e-9
