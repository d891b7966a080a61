"""MCAP bags in the rosbag2 layout: write, read, check, convert (no ROS import).

A bag is a directory with ``metadata.yaml`` and one ``.mcap`` file of CDR messages with the
schema and type hash of each channel, written with ``rosbags`` and read with the official
``mcap`` records, so a stock ``ros2 bag play``, rosbags and Foxglove open it;
:class:`ReaderCheck` tells which channels a reader cannot decode, :class:`RecordSelection`
what a recording keeps (by default nothing a common reader cannot decode) and
:class:`BagConverter` rewrites an older bag, :class:`BagRepair` finalises an interrupted one.
The rclpy side (recording from the graph, replaying) is in ``icub_pmp.ros.bag_recorder`` /
``bag_player``; the CLI is ``icub bag``.
"""

from icub_pmp.bags.bag_converter import BagConverter, ConvertResult
from icub_pmp.bags.bag_reader import BagInfo, BagMessage, BagReader, BagStatus, BagTopic
from icub_pmp.bags.bag_repair import BagRepair, RepairResult
from icub_pmp.bags.bag_writer import COMPRESSIONS, BagWriter, TopicHandle, WriteStats
from icub_pmp.bags.message_definitions import MessageDefinitions
from icub_pmp.bags.reader_check import MCAP_ROS2, ROSBAGS, ReaderCheck, UnreadableChannel
from icub_pmp.bags.record_selection import RecordSelection

__all__ = [
    "BagConverter",
    "BagInfo",
    "BagMessage",
    "BagReader",
    "BagRepair",
    "BagStatus",
    "BagTopic",
    "BagWriter",
    "COMPRESSIONS",
    "MCAP_ROS2",
    "ROSBAGS",
    "ConvertResult",
    "MessageDefinitions",
    "ReaderCheck",
    "RecordSelection",
    "RepairResult",
    "TopicHandle",
    "UnreadableChannel",
    "WriteStats",
]
