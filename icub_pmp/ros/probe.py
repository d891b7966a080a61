"""RosProbe: an in-process rclpy node in its own context, for tests and the demo that talk to
the graph over DDS."""

from __future__ import annotations

import queue
import threading
import time
from typing import Any, Callable

import rclpy
from rclpy.client import Client
from rclpy.context import Context
from rclpy.exceptions import InvalidHandle
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.qos import QoSProfile, qos_profile_sensor_data
from rclpy.service import Service
from rclpy.subscription import Subscription
from rclpy.timer import Timer

__all__ = ["RosProbe"]


class RosProbe:
    """A node spun in a background thread, with waits on the ROS graph.

    ``RosProbe(domain_id)`` joins that domain only (own rclpy context). Use
    :meth:`wait_for_topic`, :meth:`wait_for_service`, :meth:`collect`, :meth:`call`.

    Destroy the entities you create on :attr:`node` with :meth:`destroy`, not with
    ``node.destroy_*``: destroying a subscription, client or publisher from another thread while
    the executor waits on it makes rclpy raise ``InvalidHandle`` ("cannot use Destroyable because
    destruction was requested") inside the spin thread (ros2/rclpy#1142, #1206), which would kill
    the probe's spin thread (every later wait would time out). :meth:`destroy` runs the
    destruction on the spin thread, between two ``spin_once`` calls; the spin loop also survives
    that exception (counted in :attr:`spin_errors`) for code that destroys directly.
    """

    def __init__(self, domain_id: int, name: str = "test_probe"):
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = Node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.spin_errors = 0
        self._pending: queue.SimpleQueue[tuple[Callable[[], Any], threading.Event]] = \
            queue.SimpleQueue()
        self._stop = False
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop and self.context.ok():
            self._run_pending()
            try:
                self.executor.spin_once(timeout_sec=0.02)
            except InvalidHandle:  # an entity destroyed from another thread (class doc)
                self.spin_errors += 1
            except Exception:  # shutting down
                if self._stop:
                    return
                raise
        self._run_pending()

    def _run_pending(self) -> None:
        while True:
            try:
                fn, done = self._pending.get_nowait()
            except queue.Empty:
                return
            try:
                fn()
            finally:
                done.set()

    def destroy(self, *entities: Subscription | Publisher | Client | Service | Timer) -> None:
        """Destroy entities of :attr:`node` on the spin thread (see the class doc); returns
        when they are destroyed."""
        destroyers = {Subscription: self.node.destroy_subscription,
                      Publisher: self.node.destroy_publisher, Client: self.node.destroy_client,
                      Service: self.node.destroy_service, Timer: self.node.destroy_timer}
        for entity in entities:
            if type(entity).__name__ == "ActionClient":
                self._on_spin_thread(entity.destroy)
                continue
            fn = next((f for cls, f in destroyers.items() if isinstance(entity, cls)), None)
            if fn is None:
                raise TypeError(f"RosProbe.destroy: cannot destroy {type(entity).__name__}")
            self._on_spin_thread(lambda fn=fn, e=entity: fn(e))

    def _on_spin_thread(self, fn: Callable[[], Any]) -> Any:
        if not self._thread.is_alive() or threading.current_thread() is self._thread:
            return fn()
        done = threading.Event()
        out: list[Any] = []
        err: list[BaseException] = []

        def run() -> None:
            try:
                out.append(fn())
            except Exception as exc:  # raised in the caller's thread, not the spin thread
                err.append(exc)

        self._pending.put((run, done))
        self.executor.wake()  # end the current wait now
        if not done.wait(10.0):
            raise TimeoutError("RosProbe: the spin thread did not run a call in 10 s")
        if err:
            raise err[0]
        return out[0] if out else None

    def on_spin_thread(self, fn: Callable[[], Any]) -> Any:
        """Run ``fn`` on the spin thread and return its result. Send action goals and cancel
        requests this way: rclpy's ActionClient registers a request only after sending it, so
        an answer taken by the spin thread in between is dropped ("Ignoring unexpected goal
        response") and the future never completes (seen under load, 2026-12-02)."""
        return self._on_spin_thread(fn)

    # ---------------------------------------------------------------- graph waits
    def wait_for(self, predicate: Callable[[], bool], timeout: float,
                 period: float = 0.02) -> bool:
        """Poll ``predicate`` every ``period`` s (20 ms) until true or ``timeout`` s pass (a
        costly predicate, such as reading a bag being written, polls less often)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if predicate():
                return True
            time.sleep(period)
        return predicate()

    def wait_for_topic(self, topic: str, timeout: float = 20.0, publishers: int = 1) -> bool:
        """Wait until ``topic`` has at least ``publishers`` publishers."""
        return self.wait_for(lambda: self.node.count_publishers(topic) >= publishers, timeout)

    def wait_for_service(self, service: str, srv_type: Any, timeout: float = 20.0) -> bool:
        """Wait until ``service`` is available."""
        client = self.node.create_client(srv_type, service)
        try:
            return client.wait_for_service(timeout_sec=timeout)
        finally:
            self.destroy(client)

    def node_names(self) -> list[str]:
        """Fully qualified names of the nodes visible in the domain."""
        return self.node.get_fully_qualified_node_names()

    # ---------------------------------------------------------------- data
    def collect(
        self,
        topic: str,
        msg_type: Any,
        count: int,
        timeout: float = 20.0,
        qos: QoSProfile | int = qos_profile_sensor_data,
    ) -> list[Any]:
        """Subscribe and return the first ``count`` messages (fewer on timeout)."""
        got: list[Any] = []
        lock = threading.Lock()

        def cb(msg: Any) -> None:
            with lock:
                if len(got) < count:
                    got.append(msg)

        sub = self.node.create_subscription(msg_type, topic, cb, qos)
        try:
            self.wait_for(lambda: len(got) >= count, timeout)
        finally:
            self.destroy(sub)
        with lock:
            return list(got)

    def call(self, service: str, srv_type: Any, request: Any, timeout: float = 30.0) -> Any:
        """Call ``service`` and return the response (raises TimeoutError)."""
        client = self.node.create_client(srv_type, service)
        try:
            if not client.wait_for_service(timeout_sec=timeout):
                raise TimeoutError(f"service {service} not available after {timeout} s")
            future = client.call_async(request)
            if not self.wait_for(future.done, timeout):
                raise TimeoutError(f"service {service} gave no answer within {timeout} s")
            return future.result()
        finally:
            self.destroy(client)

    def action_client(self, action: str, action_type: Any, timeout: float = 30.0) -> Any:
        """An ActionClient of this probe's node, once its server is ready (raises
        TimeoutError). Reuse it for several goals; destroy it with :meth:`destroy`."""
        from rclpy.action import ActionClient

        client = ActionClient(self.node, action_type, action)
        if not self.wait_for(client.server_is_ready, timeout):
            self.destroy(client)
            raise TimeoutError(f"action {action} not available after {timeout} s")
        return client

    def send_goal(self, client: Any, goal: Any, timeout: float = 60.0,
                  feedback: list | None = None, on_accepted: Callable[[Any], None] | None = None
                  ) -> Any:
        """Send ``goal`` with ``client`` (:meth:`action_client`) and wait for the result
        (``GetResult`` response: ``.status``, ``.result``); feedback messages are appended to
        ``feedback``; ``on_accepted(goal_handle)`` runs once accepted (e.g. to cancel it or
        to kill a node mid-motion). Raises TimeoutError."""
        cb = (lambda m: feedback.append(m.feedback)) if feedback is not None else None
        sent = self.on_spin_thread(lambda: client.send_goal_async(goal, feedback_callback=cb))
        if not self.wait_for(sent.done, 30.0):
            raise TimeoutError("the goal was not acknowledged within 30 s")
        handle = sent.result()
        if not handle.accepted:
            raise RuntimeError("goal rejected")
        if on_accepted is not None:
            on_accepted(handle)
        result = handle.get_result_async()
        if not self.wait_for(result.done, timeout):
            raise TimeoutError(f"no result within {timeout} s")
        return result.result()

    def close(self) -> None:
        """Stop spinning and shut the context down."""
        self._stop = True
        self._thread.join(2.0)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)

    def __enter__(self) -> "RosProbe":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
