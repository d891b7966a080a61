"""QoS profiles: a subscription profile compatible with the publishers of a topic (used by the
recorder and the CLI's echo and hz), and the latched profile of status topics."""

from __future__ import annotations

from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

__all__ = ["matching_qos", "LATCHED_QOS"]

#: status and description topics: reliable, the latest kept for late subscribers (the ROS
#: "latched" topic: /robot_description, /impedance_controller/status, /sim/status)
LATCHED_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)


def matching_qos(node: Node, topic: str, depth: int = 100) -> QoSProfile:
    """A subscription QoS compatible with every current publisher of ``topic``.

    Reliable only if all publishers are reliable; transient local only if all publishers are
    (so latched topics such as /robot_description are received).
    """
    infos = node.get_publishers_info_by_topic(topic)
    reliable = bool(infos) and all(
        i.qos_profile.reliability == ReliabilityPolicy.RELIABLE for i in infos
    )
    latched = bool(infos) and all(
        i.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for i in infos
    )
    return QoSProfile(
        depth=depth,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE,
    )
