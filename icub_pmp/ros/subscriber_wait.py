"""wait_for_subscribers: give DDS discovery a moment before publishing a one-off command.

A trajectory is published once, on a volatile topic: a subscriber that has not yet been
matched with the publisher (discovery is still running a few seconds after the graph starts,
longer on a loaded machine) never receives it, and the robot does not move. Nodes that publish
such commands (pmp_planner, cartesian_solver) first wait, for a bounded wall time, until their
publisher has at least one matched subscriber. Matching is done by the middleware's own
threads, so polling from a callback is safe.
"""

from __future__ import annotations

import time

from rclpy.publisher import Publisher

__all__ = ["wait_for_subscribers", "subscriber_note"]


def wait_for_subscribers(publisher: Publisher, timeout: float, poll: float = 0.005) -> int:
    """Wait up to ``timeout`` s (wall time) until ``publisher`` has a matched subscriber.

    Returns the number of matched subscribers (0 if none came in time).
    """
    deadline = time.monotonic() + max(0.0, timeout)
    while True:
        n = publisher.get_subscription_count()
        if n > 0 or time.monotonic() >= deadline:
            return n
        time.sleep(poll)


def subscriber_note(count: int, timeout: float) -> str:
    """What to add to a "published" message when nobody was listening."""
    if count > 0:
        return ""
    return (f" (no subscriber after {timeout:g} s: nothing may execute it; is "
            f"impedance_controller running?)")
