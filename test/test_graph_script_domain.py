"""``scripts/graph.sh`` holds its ROS_DOMAIN_ID's lock while it runs: a test session that
reserves a domain then never picks the domain of a graph started by hand (a test there talked
to that graph: a restarted simulator's estimates came with the other graph's stamps)."""

from __future__ import annotations

import os
import random

import pytest

from icub_pmp.graph import NodeProcess, reserve_domain_id, ros_environment
from icub_pmp.testing import repo_root

pytestmark = pytest.mark.integration


def test_a_running_graph_keeps_its_domain_from_the_tests(monkeypatch):
    with reserve_domain_id() as domain:
        pass  # a free domain, released: graph.sh takes it as a user's shell would
    env = ros_environment(domain)
    env["GRAPH_NODES"] = "robot_state_publisher"
    graph = NodeProcess(command=[str(repo_root() / "scripts/graph.sh")], env=env)
    try:
        assert graph.wait_for_output("running (ROS_DOMAIN_ID=", 60.0), graph.output()
        # the search starts right before the graph's domain: it must step over it
        monkeypatch.setattr(random, "randrange", lambda n: (domain - 2) % 100)
        monkeypatch.delenv("ROS_DOMAIN_ID", raising=False)
        assert graph.wait_for_output("started robot_state_publisher", 30.0)
        with reserve_domain_id() as other:
            assert other != domain, graph.output()
    finally:
        graph.stop()
    with reserve_domain_id() as again:  # the lock goes with the graph
        assert again == domain
    assert "is held by another process" not in graph.output()
    assert os.path.exists(repo_root() / "scripts/hold_domain_lock.py")
