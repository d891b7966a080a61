"""Test and benchmark support: private DDS domains, node subprocesses, graph waits.

Launch-free integration testing: nodes run as real subprocesses (through
``scripts/run_node.sh``, exactly as a user starts them), each test session in its own
``ROS_DOMAIN_ID`` with ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``; the test talks to them over
DDS through an in-process :class:`RosProbe`.
"""

from icub_pmp.testing.node_graph import NodeGraph
from icub_pmp.testing.node_process import NodeProcess, repo_root
from icub_pmp.testing.probe import RosProbe
from icub_pmp.testing.ros_domain import reserve_domain_id, ros_environment

__all__ = [
    "NodeGraph",
    "NodeProcess",
    "RosProbe",
    "reserve_domain_id",
    "ros_environment",
    "repo_root",
]
