"""TakenSubscription: a subscription that a worker thread takes its messages from itself.

A subscription made with ``Node.create_subscription`` is handed to the executor: every
message wakes the executor's thread, which runs the callback, which then has to wake the
thread that needs the message (in the simulator's lockstep, the physics loop waiting for the
controller's answer). At 1 kHz that second thread hop and the executor's dispatch are a
sizeable part of a step (docs/decisions/0065). A ``TakenSubscription`` is the same rcl
subscription on the node (same topic, type and QoS; it shows in the graph as the node's
subscription) that the executor does not know about: the thread that needs the messages waits
on it with its own rcl wait set (:meth:`wait`, the GIL released meanwhile) and takes them
(:meth:`take`), serialised (raw) or deserialised.

Use it from one thread only; :meth:`destroy` it before the node.
"""

from __future__ import annotations

from typing import Any

from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.type_support import check_is_valid_msg_type

__all__ = ["TakenSubscription"]


class TakenSubscription:
    """A subscription of ``node`` to ``topic`` (``msg_type``, ``qos``) outside the executor
    (module doc); ``raw``: :meth:`take` returns the serialised bytes."""

    def __init__(self, node: Node, msg_type: Any, topic: str, qos: QoSProfile,
                 raw: bool = False):
        check_is_valid_msg_type(msg_type)  # imports the type support
        self.msg_type = msg_type
        self.topic = topic
        self.raw = raw
        with node.handle:
            self._sub = _rclpy.Subscription(node.handle, msg_type, topic,
                                            qos.get_c_qos_profile())
        self._wait_set = _rclpy.WaitSet(1, 0, 0, 0, 0, 0, node.context.handle)

    def wait(self, timeout: float) -> bool:
        """Wait up to ``timeout`` [s] of wall time for a message (the GIL is released while
        waiting); True when one is there to take."""
        ws = self._wait_set
        with self._sub:
            ws.clear_entities()
            ws.add_subscription(self._sub)
            ws.wait(max(0, int(timeout * 1e9)))
            return bool(ws.get_ready_entities("subscription"))

    def take(self) -> Any:
        """The next message (bytes when ``raw``), or None when none is waiting."""
        with self._sub:
            got = self._sub.take_message(self.msg_type, self.raw)
        return None if got is None else got[0]

    def destroy(self) -> None:
        """Destroy the rcl subscription (before the node)."""
        self._sub.destroy_when_not_in_use()
