"""TakenSubscription (icub_pmp.ros.taken_subscription): a thread takes the messages of a
node's subscription itself, serialised or deserialised, while the node's executor (which does
not see the subscription) serves the rest; it is a subscription of the node in the graph."""

from __future__ import annotations

import time

import pytest
import rclpy
from rclpy.context import Context
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState

from icub_pmp.ros.taken_subscription import TakenSubscription


@pytest.fixture
def nodes(ros_domain_id):
    ctx = Context()
    rclpy.init(context=ctx, domain_id=ros_domain_id)
    made: list[Node] = []

    def make(name: str) -> Node:
        node = Node(name, context=ctx, start_parameter_services=False)
        made.append(node)
        return node

    try:
        yield make
    finally:
        for n in made:
            n.destroy_node()
        rclpy.try_shutdown(context=ctx)


def _wait_matched(pub, timeout: float = 30.0) -> None:
    end = time.monotonic() + timeout
    while pub.get_subscription_count() == 0:
        assert time.monotonic() < end, "the subscription was never matched"
        time.sleep(0.01)


@pytest.mark.parametrize("raw", [True, False])
def test_messages_are_taken_in_order_by_the_waiting_thread(nodes, raw):
    """Nothing to take: wait returns False after its timeout and take None; published
    messages are then taken in order, as bytes (raw) or as messages."""
    sub_node, pub_node = nodes("taker"), nodes("sender")
    sub = TakenSubscription(sub_node, JointState, "/taken_test", qos_profile_sensor_data,
                            raw=raw)
    pub = pub_node.create_publisher(JointState, "/taken_test", qos_profile_sensor_data)
    try:
        _wait_matched(pub)
        assert sub.wait(0.05) is False
        assert sub.take() is None
        for k in range(3):
            pub.publish(JointState(name=["j"], effort=[float(k)]))
        got = []
        end = time.monotonic() + 10.0
        while len(got) < 3 and time.monotonic() < end:
            if sub.wait(0.5):
                while (m := sub.take()) is not None:
                    got.append(deserialize_message(m, JointState) if raw else m)
        assert [list(m.effort) for m in got] == [[0.0], [1.0], [2.0]]
        assert all(list(m.name) == ["j"] for m in got)
    finally:
        sub.destroy()


def test_the_executor_leaves_the_messages_to_the_taker(nodes):
    """Spinning the node's executor runs its own callbacks but takes nothing from the taken
    subscription; the graph lists the topic among the node's subscriptions."""
    node, pub_node = nodes("taker_exec"), nodes("sender_exec")
    sub = TakenSubscription(node, JointState, "/taken_exec", qos_profile_sensor_data,
                            raw=True)
    seen = []
    node.create_subscription(JointState, "/taken_other", seen.append, qos_profile_sensor_data)
    pub = pub_node.create_publisher(JointState, "/taken_exec", qos_profile_sensor_data)
    other = pub_node.create_publisher(JointState, "/taken_other", qos_profile_sensor_data)
    executor = EventsExecutor(context=node.context)
    executor.add_node(node)
    try:
        _wait_matched(pub)
        _wait_matched(other)
        pub.publish(JointState(name=["a"], effort=[1.0]))
        other.publish(JointState(name=["b"], effort=[2.0]))
        end = time.monotonic() + 10.0
        while not seen and time.monotonic() < end:
            executor.spin_once(timeout_sec=0.1)
        assert [list(m.name) for m in seen] == [["b"]]
        assert sub.wait(5.0)
        m = deserialize_message(sub.take(), JointState)
        assert list(m.name) == ["a"]
        topics = dict(node.get_subscriber_names_and_types_by_node("taker_exec", "/"))
        assert topics.get("/taken_exec") == ["sensor_msgs/msg/JointState"]
    finally:
        executor.shutdown()
        sub.destroy()
