"""wait_for_subscribers: a one-off command waits (bounded) for DDS discovery before publishing."""

from __future__ import annotations

import time

import pytest
from std_msgs.msg import String

from icub_pmp.errors import ConfigError
from icub_pmp.ros.cartesian_node_config import CartesianNodeConfig
from icub_pmp.ros.subscriber_wait import subscriber_note, wait_for_subscribers


def test_waits_the_timeout_when_nobody_listens_then_says_so(ros_probe):
    pub = ros_probe.node.create_publisher(String, "/subscriber_wait_test/lonely", 10)
    t0 = time.monotonic()
    assert wait_for_subscribers(pub, 0.3) == 0
    assert time.monotonic() - t0 >= 0.3
    assert "no subscriber after 0.3 s" in subscriber_note(0, 0.3)
    ros_probe.destroy(pub)


def test_returns_as_soon_as_a_subscriber_is_matched(ros_probe):
    topic = "/subscriber_wait_test/heard"
    pub = ros_probe.node.create_publisher(String, topic, 10)
    sub = ros_probe.node.create_subscription(String, topic, lambda m: None, 10)
    t0 = time.monotonic()
    assert wait_for_subscribers(pub, 10.0) >= 1
    assert time.monotonic() - t0 < 5.0
    assert subscriber_note(1, 10.0) == ""
    ros_probe.destroy(sub, pub)


def test_cartesian_node_rejects_a_negative_timeout():
    with pytest.raises(ConfigError, match="subscriber_timeout"):
        CartesianNodeConfig(subscriber_timeout=-1.0).validate()
