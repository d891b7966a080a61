"""The ``main()`` body shared by the nodes: init, build, spin, clean shutdown.

:func:`spin_node` spins an ``EventsExecutor`` (the 1 kHz nodes); :func:`run_node` uses the
default single-threaded executor (``rclpy.spin``: service-driven and camera-rate nodes).

``spin_node`` spins an ``EventsExecutor`` (several times the message throughput of the
default executor, ENVIRONMENT.md) with ``spin_once`` in a loop: its ``spin()`` in the Jazzy
wheel neither processes callbacks reliably nor returns on SIGINT. Ctrl-C and external
shutdowns end quietly.
"""

from __future__ import annotations

from typing import Callable

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.node import Node

__all__ = ["spin_node", "run_node"]


def spin_node(factory: Callable[[], Node], args: list[str] | None = None) -> None:
    """``rclpy.init(args)``, build the node with ``factory()``, spin until shutdown, then
    destroy the node and shut rclpy down (``try_shutdown``)."""
    rclpy.init(args=args)
    node = None
    executor = None
    try:
        node = factory()
        executor = EventsExecutor()
        executor.add_node(node)
        while rclpy.ok():
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        if executor is not None:
            executor.shutdown()
        rclpy.try_shutdown()


def run_node(factory: Callable[[], Node], args: list[str] | None = None,
             name: str = "node") -> None:
    """``rclpy.init(args)``, build the node with ``factory()``, ``rclpy.spin`` until shutdown
    (Ctrl-C and external shutdowns end quietly), then destroy it and ``try_shutdown``. A
    :class:`~icub_pmp.errors.ConfigError` while building exits with a one-line message."""
    from icub_pmp.errors import ConfigError

    rclpy.init(args=args)
    node = None
    try:
        node = factory()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except ConfigError as exc:
        raise SystemExit(f"{name}: {exc}") from exc
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
