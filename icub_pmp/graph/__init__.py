"""Starting the node graph as a user does: one subprocess per node through its script
(``scripts/<node>.sh``), in a private DDS domain kept on this machine. No rclpy import: used
by the demo, the tests and the benchmarks."""

from icub_pmp.graph.node_graph import COMPOSED, NodeGraph
from icub_pmp.graph.node_process import NodeProcess, param_text
from icub_pmp.graph.realism_parameters import (
    ICUB_EYE_CALIBRATION,
    realism_parameters,
    with_realism,
)
from icub_pmp.graph.ros_domain import reserve_domain_id, ros_environment
from icub_pmp.graph.veth_link import Host, VethLink, VethLinkError

__all__ = ["COMPOSED", "ICUB_EYE_CALIBRATION", "Host", "NodeGraph", "NodeProcess", "VethLink",
           "VethLinkError", "param_text", "realism_parameters", "reserve_domain_id",
           "ros_environment", "with_realism"]
