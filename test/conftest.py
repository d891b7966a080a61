"""pytest fixtures and markers shared by the whole suite.

Every test session reserves its own ROS_DOMAIN_ID (domain_coordinator) and sets
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST in os.environ before any rclpy context exists, so the
nodes it starts as subprocesses inherit both and no DDS traffic leaves this machine.

Marker ``integration``: tests that talk over DDS or start node subprocesses. Every test that
uses the session's domain (``ros_domain_id``, ``ros_probe``) gets it automatically; modules
that start processes otherwise set ``pytestmark = pytest.mark.integration``. The fast inner
loop is ``pytest -m "not integration"``.

Marker ``slow``: the few modules that each take a minute or more of a 2-core machine (the DDS
fuzzing, the node faults and soak, the babbling run, the bags of the running graph, the two
hosts). ``make test`` (and CI) runs them; ``make test-fast`` (``-m "not slow"``) leaves them
out for the inner loop. docs/decisions/0027-test-suite-time.md lists the figures.
"""

from __future__ import annotations

import os

import pytest

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("MUJOCO_GL", "egl")

#: fixtures that put a test on DDS (their users are integration tests)
DDS_FIXTURES = {"ros_domain_id", "ros_probe"}


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "integration: talks over DDS or starts node subprocesses (slow; deselect "
                   "with -m 'not integration')")
    config.addinivalue_line(
        "markers", "slow: a module of a minute or more on 2 cores; run by make test, left out "
                   "by make test-fast (-m 'not slow')")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        if DDS_FIXTURES & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.integration)


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


@pytest.fixture(scope="session")
def model():
    """The iCub model (pinocchio on the icub-models URDF), built once per session."""
    from icub_pmp.kinematics import IcubModel

    return IcubModel()


@pytest.fixture(scope="session")
def vm_ik_solver(model):
    """The eq 11 solver on the CasADi VM (no C compilation: fast to build) with a wall-time
    bound loose enough for a loaded machine (tests check answers, not speed)."""
    from icub_pmp.cartesian import IkConfig, IkSolver

    return IkSolver(model, IkConfig(codegen=False, max_solve_time=5.0))


@pytest.fixture(scope="module")
def sim():
    """A simulator without cameras, shared by the tests of one module (they step it)."""
    from icub_sim_bridge import SimConfig, Simulator

    return Simulator(SimConfig(cameras_enabled=False))


class FakeClock:
    """A settable clock for cores that take one (``clock()`` returns :attr:`t` [s])."""

    def __init__(self, t: float = 0.0) -> None:
        self.t = t

    def __call__(self) -> float:
        return self.t


@pytest.fixture
def fake_clock() -> FakeClock:
    """A :class:`FakeClock` at t = 100 s: advance it with ``fake_clock.t += dt``."""
    return FakeClock(100.0)


@pytest.fixture(scope="module")
def ros_probe_module(ros_domain_id):
    """A probe shared by the tests of one module (for module-scoped graphs)."""
    from icub_pmp.testing import RosProbe

    probe = RosProbe(ros_domain_id, "module_probe")
    try:
        yield probe
    finally:
        probe.close()
