"""The ``main()`` body shared by the nodes: init, build, spin, clean shutdown.

:func:`spin_node` spins an ``EventsExecutor`` (the 1 kHz nodes); :func:`run_node` uses the
default single-threaded executor (``rclpy.spin``: service-driven and camera-rate nodes).

``spin_node`` spins an ``EventsExecutor`` (several times the message throughput of the
default executor) with ``spin_once`` in a loop: its ``spin()`` in the Jazzy wheel neither
processes callbacks reliably nor returns on SIGINT. It can run a worker beside the executor
(the simulator's physics loop) on its own thread; the node then stops when the worker returns
or fails. :func:`spin_nodes` spins several nodes of one process on one ``EventsExecutor`` (a
composed process: :mod:`icub_pmp.nodes.torque_loop`). Ctrl-C and external shutdowns end
quietly; a node refusing its parameters (:class:`~icub_pmp.errors.ConfigError`) exits with a
one-line message.
"""

from __future__ import annotations

import threading
from typing import Callable, Sequence, TypeVar

import rclpy
from rclpy.executors import Executor, ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.node import Node

from icub_pmp.errors import ConfigError

__all__ = ["spin_node", "spin_nodes", "run_node", "guard_parameter_services"]

N = TypeVar("N", bound=Node)

#: a worker: ``worker(node, should_stop)`` runs until ``should_stop()`` is True
Worker = Callable[[N, Callable[[], bool]], None]


def spin_node(
    factory: Callable[[], N],
    args: list[str] | None = None,
    name: str = "node",
    worker: Worker | None = None,
) -> None:
    """``rclpy.init(args)``, build the node with ``factory()``, spin until shutdown, then
    destroy the node and shut rclpy down (``try_shutdown``).

    ``worker(node, should_stop)``, if given, runs on its own thread from the start; the
    executor keeps spinning on the main thread (where rclpy's signal handling works). When the
    worker fails, the failure is logged and the process exits with status 1.
    """
    _spin(lambda: [factory()], args, name, worker)


def spin_nodes(factory: Callable[[], Sequence[Node]], args: list[str] | None = None,
               name: str = "process", worker: Worker | None = None) -> None:
    """As :func:`spin_node` for the nodes ``factory()`` builds, all on one
    ``EventsExecutor`` (so their callbacks never run at the same time); ``worker`` runs on
    the first node (:mod:`icub_sim_bridge.robot_loop_node`: the simulator's physics loop)."""
    _spin(factory, args, name, worker)


def _spin(factory: Callable[[], Sequence[Node]], args: list[str] | None, name: str,
          worker: Worker | None) -> None:
    """The body of :func:`spin_node` and :func:`spin_nodes` (``worker`` runs on the first
    node)."""
    rclpy.init(args=args)
    nodes: list[Node] = []
    node = None
    executor = None
    stop = threading.Event()
    thread = None
    failed: list[BaseException] = []
    try:
        nodes = list(factory())
        node = nodes[0]
        executor = EventsExecutor()
        for n in nodes:
            guard_parameter_services(n)
            executor.add_node(n)
        if worker is not None:
            thread = threading.Thread(target=_run_worker, args=(worker, node, stop, failed),
                                      name=f"{name}-worker")
            thread.start()
        # spin_once in a loop: EventsExecutor.spin() of the Jazzy wheel never returns on
        # SIGINT, and waking it from another thread deadlocks
        while rclpy.ok() and (thread is None or thread.is_alive()):
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except ConfigError as exc:
        raise SystemExit(f"{name}: {exc}") from exc
    except Exception:
        if rclpy.ok():
            raise
        # a callback racing the shutdown (publishing on a context a signal just shut down):
        # the node is stopping anyway
    finally:
        stop.set()
        if thread is not None:
            thread.join(timeout=10.0)
        for n in nodes:
            n.destroy_node()
        if executor is not None:
            executor.shutdown()
        rclpy.try_shutdown()
    if failed:
        raise SystemExit(1)


def guard_parameter_services(node: Node) -> None:
    """Make rclpy's parameter services answer a request they cannot parse instead of raising.

    rclpy's own ``~/set_parameters`` (and the other parameter services) raise from their
    callback on a malformed request, e.g. a ``ParameterValue`` of an unknown type (found by
    the fuzzer: ``type: 254`` killed every node), and an exception from a callback ends the
    executor's spin. Each callback is wrapped: such a request is answered with every change
    refused and the reason (or an empty answer for the read-only services), and a warning."""
    from rcl_interfaces.msg import SetParametersResult

    for srv in list(node.services):
        name = srv.srv_name.rsplit("/", 1)[-1]
        if name not in ("set_parameters", "set_parameters_atomically", "get_parameters",
                        "get_parameter_types", "describe_parameters", "list_parameters"):
            continue

        def guarded(request, response, _cb=srv.callback, _name=name):  # noqa: ANN001, ANN202
            try:
                return _cb(request, response)
            except Exception as exc:  # a malformed request: refuse it, keep serving
                reason = f"invalid request: {type(exc).__name__}: {exc}"
                node.get_logger().warning(f"~/{_name}: {reason}")
                if _name == "set_parameters":
                    response.results = [SetParametersResult(successful=False, reason=reason)
                                        for _ in request.parameters]
                elif _name == "set_parameters_atomically":
                    response.result = SetParametersResult(successful=False, reason=reason)
                return response

        srv.callback = guarded


def _run_worker(worker: Worker, node: Node, stop: threading.Event,
                failed: list[BaseException]) -> None:
    """The worker thread: on a failure (not during shutdown) log it and record it."""
    def should_stop() -> bool:
        return stop.is_set() or not rclpy.ok()

    try:
        worker(node, should_stop)
    except Exception as exc:
        if should_stop():
            return  # shutting down: publishers may already be invalid
        failed.append(exc)
        node.get_logger().fatal(f"{threading.current_thread().name} failed: "
                                f"{type(exc).__name__}: {exc}")


def run_node(factory: Callable[[], Node], args: list[str] | None = None,
             name: str = "node", executor: Callable[[], Executor] | None = None) -> None:
    """``rclpy.init(args)``, build the node with ``factory()``, ``rclpy.spin`` until shutdown
    (Ctrl-C and external shutdowns end quietly), then destroy it and ``try_shutdown``. A
    :class:`~icub_pmp.errors.ConfigError` while building exits with a one-line message.
    ``executor``: a factory of the executor to spin with (default: rclpy's single-threaded
    one), e.g. ``MultiThreadedExecutor`` for a node whose service waits on its topics."""
    rclpy.init(args=args)
    node = None
    try:
        node = factory()
        guard_parameter_services(node)
        rclpy.spin(node, executor=executor() if executor is not None else None)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except ConfigError as exc:
        raise SystemExit(f"{name}: {exc}") from exc
    except Exception:
        if rclpy.ok():
            raise
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
