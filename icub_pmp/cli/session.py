"""A short-lived rclpy node for one CLI command."""

from __future__ import annotations

import contextlib
import os
import time
import uuid
from typing import Callable, Iterator

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

__all__ = ["cli_node", "spin_until", "wait_for_topic_type", "not_ready_reason"]


@contextlib.contextmanager
def cli_node(prefix: str = "icub_cli") -> Iterator[tuple[Node, SingleThreadedExecutor]]:
    """An anonymous node in its own context (DDS kept on localhost), shut down on exit."""
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    ctx = Context()
    rclpy.init(context=ctx)
    node = Node(f"{prefix}_{uuid.uuid4().hex[:8]}", context=ctx)
    executor = SingleThreadedExecutor(context=ctx)
    executor.add_node(node)
    try:
        yield node, executor
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=ctx)


def spin_until(executor: SingleThreadedExecutor, done: Callable[[], bool], timeout: float) -> bool:
    """Spin until ``done()`` or ``timeout`` s (``timeout <= 0``: forever). Returns done()."""
    deadline = time.monotonic() + timeout if timeout > 0 else float("inf")
    while not done() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=min(0.05, max(0.0, deadline - time.monotonic())))
    return done()


def not_ready_reason(node: Node, name: str, kind: str, timeout: float, server: str) -> str:
    """Why a service or action ``name`` was not ready after ``timeout`` s: either nothing in
    the graph offers it (with the hint ``server``: which node should), or it exists but this
    client was not matched with it yet (discovery is slow on a loaded machine)."""
    if kind == "action":
        probe = f"{name}/_action/send_goal"
    else:
        probe = name
    if node.count_services(probe) > 0:
        return (f"{kind} {name} exists in the graph but was not matched after {timeout:g} s "
                f"(DDS discovery is slow on a loaded machine: retry, or give a longer "
                f"--timeout)")
    domain = os.environ.get("ROS_DOMAIN_ID", "0")
    return (f"{kind} {name} not available after {timeout:g} s: no node offers it in "
            f"ROS_DOMAIN_ID {domain} (is {server} running?)")


def wait_for_topic_type(
    node: Node, executor: SingleThreadedExecutor, topic: str, timeout: float
) -> str | None:
    """The type name ('pkg/msg/Type') of ``topic`` once it has a publisher, else None."""
    found: list[str] = []

    def check() -> bool:
        for name, types in node.get_topic_names_and_types():
            if name == topic and types and node.count_publishers(topic) > 0:
                found.append(types[0])
                return True
        return False

    spin_until(executor, check, timeout)
    return found[0] if found else None
