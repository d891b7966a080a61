"""Test and benchmark support: private DDS domains, node subprocesses, graph waits.

Launch-free integration testing: nodes run as real subprocesses (through
``scripts/run_node.sh``, exactly as a user starts them), each test session in its own
``ROS_DOMAIN_ID`` with ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``; the test talks to them over
DDS through an in-process :class:`RosProbe`.

The launcher (:mod:`icub_pmp.graph`) and the probe (:mod:`icub_pmp.ros.probe`) are run-time
modules that the demo uses too; they are re-exported here for the tests. This package adds
what only tests and benchmarks use: :mod:`.bag_traffic` (the graph's traffic at known rates),
:mod:`.reach_echo_server` (a /pmp/reach server that echoes its requests) and
:func:`~.icub_cli.run_icub` (the ``icub`` command line as a user runs it).
"""

from icub_pmp.config import repo_root
from icub_pmp.graph import (
    NodeGraph,
    NodeProcess,
    reserve_domain_id,
    ros_environment,
    with_realism,
)
from icub_pmp.ros.probe import RosProbe
from icub_pmp.testing.icub_cli import run_icub

__all__ = [
    "NodeGraph",
    "NodeProcess",
    "RosProbe",
    "reserve_domain_id",
    "ros_environment",
    "repo_root",
    "run_icub",
    "with_realism",
]
