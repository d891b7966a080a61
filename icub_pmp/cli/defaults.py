"""Defaults shared by the ``icub`` verbs (no ROS import: the parser is built without rclpy)."""

from __future__ import annotations

__all__ = ["DISCOVERY_TIMEOUT"]

#: how long a verb waits [s] for the topic, service, action or node it needs to be discovered
#: and matched. Every ``icub`` command is a new DDS participant that starts from nothing; on
#: the 2-core machine at load 6-10 a running node was matched after up to ~3 s and a restarted
#: one after ~4 s (bench/cli_discovery.py, BENCHMARKS.md); a planner starts more slowly than
#: the controller measured there. 30 s holds with a wide margin; a verb says on stderr what it
#: waits for after 3 s, and why it gave up at the end.
DISCOVERY_TIMEOUT = 30.0
