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

__all__ = ["cli_node", "spin_until", "wait_for_topic_type", "wait_for_service_type",
           "wait_for_action_type", "offered_types", "type_mismatch", "not_ready_reason",
           "DISCOVERY_TIMEOUT"]

#: default wait [s] for a node, topic, service or action to be discovered and matched: DDS
#: discovery took up to several seconds on a 2-core machine at load 6 (BENCHMARKS.md,
#: cli_discovery); a short-lived CLI node starts from nothing every time
DISCOVERY_TIMEOUT = 30.0


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


def wait_for_service_type(
    node: Node, executor: SingleThreadedExecutor, service: str, timeout: float
) -> str | None:
    """The type name ('pkg/srv/Type') of ``service`` once a server offers it, else None."""
    found: list[str] = []

    def check() -> bool:
        for name, types in node.get_service_names_and_types():
            if name == service and types:
                found.append(types[0])
                return True
        return False

    spin_until(executor, check, timeout)
    return found[0] if found else None


def offered_types(node: Node, name: str, kind: str) -> list[str]:
    """The types under which the graph offers service or action ``name`` (actions as
    'pkg/action/Type'); empty when nothing offers it yet."""
    probe = f"{name}/_action/send_goal" if kind == "action" else name
    for n, types in node.get_service_names_and_types():
        if n == probe:
            if kind == "action":
                return [t[: -len("_SendGoal")] for t in types if t.endswith("_SendGoal")]
            return list(types)
    return []


def type_mismatch(node: Node, name: str, kind: str, wanted: str) -> str | None:
    """A one-line error when the graph offers ``name`` only under other types than
    ``wanted`` ('pkg/srv/Type'), else None (not offered yet, or offered as ``wanted``)."""
    types = offered_types(node, name, kind)
    if not types or wanted in types:
        return None
    return f"{kind} {name} has type {', '.join(types)}, not {wanted}"


def wait_for_action_type(
    node: Node, executor: SingleThreadedExecutor, action: str, timeout: float
) -> str | None:
    """The type name ('pkg/action/Type') of ``action`` once a server offers it, else None
    (from the type of its ``<action>/_action/send_goal`` service)."""
    srv = wait_for_service_type(node, executor, f"{action}/_action/send_goal", timeout)
    if srv is None or not srv.endswith("_SendGoal"):
        return None
    return srv[: -len("_SendGoal")]

