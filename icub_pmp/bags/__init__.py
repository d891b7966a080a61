"""MCAP bags in the rosbag2 layout: write, read, check (no ROS import).

A bag is a directory with ``metadata.yaml`` and one ``.mcap`` file of CDR messages with
``ros2msg`` schemas, written with ``rosbags`` and read with the official ``mcap`` records, so a
stock ``ros2 bag play`` and Foxglove open it. The rclpy side (recording from the graph,
replaying) is in ``icub_pmp.ros.bag_recorder`` / ``bag_player``; the CLI is ``icub bag``.
"""

from icub_pmp.bags.bag_reader import BagInfo, BagMessage, BagReader, BagStatus, BagTopic
from icub_pmp.bags.bag_writer import COMPRESSIONS, BagWriter, TopicHandle, WriteStats
from icub_pmp.bags.message_definitions import MessageDefinitions

__all__ = [
    "BagInfo",
    "BagMessage",
    "BagReader",
    "BagStatus",
    "BagTopic",
    "BagWriter",
    "COMPRESSIONS",
    "MessageDefinitions",
    "TopicHandle",
    "WriteStats",
]
