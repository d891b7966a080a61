"""pytest fixtures shared by the whole suite.

Every test session reserves its own ROS_DOMAIN_ID (domain_coordinator) and sets
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST in os.environ before any rclpy context exists, so the
nodes it starts as subprocesses inherit both and no DDS traffic leaves this machine.
"""

from __future__ import annotations

import os

import pytest

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("MUJOCO_GL", "egl")


@pytest.fixture(scope="session")
def ros_domain_id():
    """A ROS_DOMAIN_ID private to this test session (also exported to subprocesses)."""
    from icub_pmp.testing import reserve_domain_id

    with reserve_domain_id() as did:
        old = os.environ.get("ROS_DOMAIN_ID")
        os.environ["ROS_DOMAIN_ID"] = str(did)
        try:
            yield did
        finally:
            if old is None:
                os.environ.pop("ROS_DOMAIN_ID", None)
            else:
                os.environ["ROS_DOMAIN_ID"] = old


@pytest.fixture
def ros_probe(ros_domain_id):
    """An in-process rclpy node in the session's domain (see icub_pmp.testing.RosProbe)."""
    from icub_pmp.testing import RosProbe

    probe = RosProbe(ros_domain_id)
    try:
        yield probe
    finally:
        probe.close()


@pytest.fixture(scope="module")
def ros_probe_module(ros_domain_id):
    """A probe shared by the tests of one module (for module-scoped graphs)."""
    from icub_pmp.testing import RosProbe

    probe = RosProbe(ros_domain_id, "module_probe")
    try:
        yield probe
    finally:
        probe.close()
