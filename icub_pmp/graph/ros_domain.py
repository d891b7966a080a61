"""Private DDS domains for tests: a free ``ROS_DOMAIN_ID`` and an environment that keeps all
DDS traffic on this machine."""

from __future__ import annotations

import contextlib
import os
import random
import socket
from typing import Iterator

__all__ = ["reserve_domain_id", "ros_environment"]

#: the ROS_DOMAIN_ID of the shell this process came from (scripts/env.sh exports 42 unless the
#: user exports another): a graph started by hand there (scripts/graph.sh) reserves nothing,
#: and a test that picked its domain talked to it (a restarted simulator's estimates came with
#: the hand-started graph's stamps, 60 s where the test's were 3 s; check CI, 2026-12-04)
_SHELL_DOMAIN = os.environ.get("ROS_DOMAIN_ID", "")


@contextlib.contextmanager
def reserve_domain_id() -> Iterator[int]:
    """Reserve a ROS_DOMAIN_ID in 1..100 not used by another test process on this machine,
    nor the shell's own ``ROS_DOMAIN_ID`` (:data:`_SHELL_DOMAIN`: where graphs started by hand
    run) or the one the environment has now.

    The lock of ``domain_coordinator`` (the ros2 test tool): a TCP port ``PORT_BASE + id``
    bound for as long as the domain is in use, starting at a random id so parallel sessions
    spread out. The id is free again when the context exits. Written here rather than through
    ``domain_coordinator.domain_id``: that generator catches ``OSError`` around its ``yield``,
    so a ``TimeoutError`` (an ``OSError``) raised by the caller's code was swallowed and came
    out as "generator didn't stop after throw()", hiding the real reason.
    """
    from domain_coordinator.impl import PORT_BASE

    avoid = {v for v in (_SHELL_DOMAIN, os.environ.get("ROS_DOMAIN_ID", "")) if v.isdigit()}
    start = random.randrange(100)
    for k in range(100):
        did = (start + k + 1) % 100 + 1
        if str(did) in avoid:
            continue
        lock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            lock.bind(("", PORT_BASE + did))
        except OSError:  # taken by another process
            lock.close()
            continue
        try:
            yield did
        finally:
            lock.close()
        return
    raise RuntimeError("no free ROS_DOMAIN_ID in 1..100 (every domain_coordinator lock port "
                       "is taken)")


def ros_environment(domain_id: int, base: dict[str, str] | None = None) -> dict[str, str]:
    """A process environment for ``domain_id`` with DDS discovery limited to localhost."""
    env = dict(os.environ if base is None else base)
    env["ROS_DOMAIN_ID"] = str(domain_id)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env.setdefault("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
    env.setdefault("PYTHONUNBUFFERED", "1")
    return env
