"""Private DDS domains for tests: a free ``ROS_DOMAIN_ID`` and an environment that keeps all
DDS traffic on this machine."""

from __future__ import annotations

import contextlib
import os
import random
from typing import Iterator

__all__ = ["reserve_domain_id", "ros_environment"]


@contextlib.contextmanager
def reserve_domain_id() -> Iterator[int]:
    """Reserve a ROS_DOMAIN_ID in 1..100 not used by another test process on this machine.

    Uses ``domain_coordinator`` (a lock port per domain), starting at a random id so parallel
    sessions spread out. The id is free again when the context exits.
    """
    from domain_coordinator import domain_id

    start = random.randrange(100)

    class _Selector:
        def __init__(self) -> None:
            self.value = start

        def __call__(self) -> int:
            self.value += 1
            return self.value % 100 + 1

    with domain_id(_Selector()) as did:
        yield did


def ros_environment(domain_id: int, base: dict[str, str] | None = None) -> dict[str, str]:
    """A process environment for ``domain_id`` with DDS discovery limited to localhost."""
    env = dict(os.environ if base is None else base)
    env["ROS_DOMAIN_ID"] = str(domain_id)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env.setdefault("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
    env.setdefault("PYTHONUNBUFFERED", "1")
    return env
