"""RosProbe: an in-process rclpy node in its own context, for tests that talk over DDS."""

from __future__ import annotations

import threading
import time
from typing import Any, Callable

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, qos_profile_sensor_data

__all__ = ["RosProbe"]


class RosProbe:
    """A node spun in a background thread, with waits on the ROS graph.

    ``RosProbe(domain_id)`` joins that domain only (own rclpy context). Use
    :meth:`wait_for_topic`, :meth:`wait_for_service`, :meth:`collect`, :meth:`call`.
    """

    def __init__(self, domain_id: int, name: str = "test_probe"):
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = Node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._stop = False
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        while not self._stop and self.context.ok():
            try:
                self.executor.spin_once(timeout_sec=0.05)
            except Exception:  # shutting down
                if self._stop:
                    return
                raise

    # ---------------------------------------------------------------- graph waits
    def wait_for(self, predicate: Callable[[], bool], timeout: float) -> bool:
        """Poll ``predicate`` every 20 ms until true or ``timeout`` s pass."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if predicate():
                return True
            time.sleep(0.02)
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
            self.node.destroy_client(client)

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
            self.node.destroy_subscription(sub)
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
            self.node.destroy_client(client)

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
