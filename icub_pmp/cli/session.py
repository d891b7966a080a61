"""A short-lived rclpy node for one CLI command."""

from __future__ import annotations

import contextlib
import os
import sys
import time
import uuid
from dataclasses import dataclass
from typing import Any, Callable, Iterator

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

__all__ = ["cli_node", "TypedValues", "typed_values", "connect_typed", "spin_until",
           "wait_for_topic_type", "offered_types", "type_mismatch", "discover",
           "not_ready_reason", "spin_until_ready"]


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
    """Why a service, action or topic ``name`` was not ready after ``timeout`` s: either
    nothing in the graph offers it (with the hint ``server``: which node should), or it
    exists but this client was not matched with it yet (discovery is slow on a loaded
    machine). ``kind``: 'service', 'action' or 'topic' (a topic is offered by a publisher)."""
    domain = os.environ.get("ROS_DOMAIN_ID", "0")
    if kind == "topic":
        if node.count_publishers(name) > 0:
            return (f"topic {name} has a publisher in the graph but no message arrived "
                    f"after {timeout:g} s (not matched yet on a loaded machine, or nothing "
                    "published: retry, or give a longer --timeout)")
        subs = node.count_subscribers(name)
        known = f" ({subs} subscriber(s) wait for it)" if subs else ""
        return (f"topic {name} has no publisher after {timeout:g} s in ROS_DOMAIN_ID "
                f"{domain}{known} (is {server} running?)")
    if kind == "action":
        probe = f"{name}/_action/send_goal"
    else:
        probe = name
    if node.count_services(probe) > 0:
        return (f"{kind} {name} exists in the graph but was not matched after {timeout:g} s "
                f"(DDS discovery is slow on a loaded machine: retry, or give a longer "
                f"--timeout)")
    return (f"{kind} {name} not available after {timeout:g} s: no node offers it in "
            f"ROS_DOMAIN_ID {domain} (is {server} running?)")


def spin_until_ready(node: Node, executor: SingleThreadedExecutor, ready: Callable[[], bool],
                     timeout: float, name: str, kind: str, server: str,
                     note_after: float = 3.0) -> None:
    """Spin until ``ready()``; after ``note_after`` s say once on stderr what is awaited
    (discovery can take seconds right after a node starts); after ``timeout`` s raise
    TimeoutError with :func:`not_ready_reason`."""
    if spin_until(executor, ready, min(note_after, timeout)):
        return
    if timeout > note_after:
        print(f"icub: waiting for {kind} {name} (up to {timeout:g} s)...", file=sys.stderr,
              flush=True)
        if spin_until(executor, ready, timeout - note_after):
            return
    raise TimeoutError(not_ready_reason(node, name, kind, timeout, server))


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


def discover(node: Node, executor: SingleThreadedExecutor, name: str, kind: str,
             wanted: str | None, timeout: float, server: str) -> str:
    """The type ('pkg/srv/Type', 'pkg/action/Type') under which the graph offers service or
    action ``name``, once it does (TimeoutError with :func:`not_ready_reason` after
    ``timeout`` s). With ``wanted`` given, ValueError when the graph offers it only under
    other types. Call it before creating the client: a client adds its own type to the
    graph."""
    spin_until_ready(node, executor, lambda: bool(offered_types(node, name, kind)), timeout,
                     name, kind, server)
    if wanted is not None:
        mismatch = type_mismatch(node, name, kind, wanted)
        if mismatch:
            raise ValueError(mismatch)
        return wanted
    return offered_types(node, name, kind)[0]


@dataclass
class TypedValues:
    """A service request or action goal given on the command line: its full name, its type
    (``None`` until the graph says it) and the message filled from the YAML values."""

    name: str
    kind: str
    values: dict
    interface: Any = None
    message: Any = None

    def fill(self, interface: Any) -> None:
        """Bind the type and fill its request/goal (ValueError naming a bad field)."""
        from icub_pmp.ros.msg_types import set_message_fields

        self.interface = interface
        part = interface.Request if self.kind == "service" else interface.Goal
        self.message = set_message_fields(part(), self.values)


def typed_values(name: str, args: list[str], kind: str) -> TypedValues:
    """``NAME [TYPE] [VALUES]`` of ``icub call``/``send-goal``, checked before anything is
    sent: bad YAML, an unknown type or a bad field raise ValueError here."""
    from icub_pmp.cli.yaml_values import (
        full_name,
        interface_name,
        parse_values,
        split_type_and_values,
    )
    from icub_pmp.ros.msg_types import get_interface

    tname, text = split_type_and_values(args)
    typed = TypedValues(full_name(name), kind, parse_values(text))
    if tname is not None:
        typed.fill(get_interface(interface_name(tname, "srv" if kind == "service" else kind)))
    return typed


def connect_typed(node: Node, executor: SingleThreadedExecutor, typed: TypedValues,
                  make_client: Callable[[Any], Any], timeout: float) -> Any:
    """Wait for the server of ``typed`` (its type from the graph when not given), fill the
    message, create the client with ``make_client(interface)`` and wait until it is matched;
    the whole wait is bounded by ``timeout`` s. Returns the client."""
    from icub_pmp.ros.msg_types import get_interface, type_name

    deadline = time.monotonic() + timeout
    # the graph's type first: our own client would add its type to the graph
    wanted = None if typed.interface is None else type_name(typed.interface)
    found = discover(node, executor, typed.name, typed.kind, wanted, timeout, "its server")
    if typed.interface is None:
        typed.fill(get_interface(found))
    client = make_client(typed.interface)
    ready = client.service_is_ready if typed.kind == "service" else client.server_is_ready
    remaining = max(1e-3, deadline - time.monotonic())
    spin_until_ready(node, executor, ready, remaining, typed.name, typed.kind, "its server",
                     note_after=remaining)
    return client
