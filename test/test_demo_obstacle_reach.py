"""The demo's reach around the cylinder over DDS in the lockstep simulator
(icub_pmp/demo/scenario.py phase 5), judged in the physics: no link of the robot, the fingers
included, touches the cylinder."""

from __future__ import annotations

import pytest

from icub_pmp.demo import scenario
from icub_pmp.graph import NodeGraph, ros_environment
from icub_pmp.ros.probe import RosProbe

pytestmark = [pytest.mark.integration, pytest.mark.slow]

GRAPH = ["sim_bridge", "wrench_estimator", "impedance_controller", "pmp_planner"]


@pytest.fixture(scope="module")
def runner(ros_domain_id):
    params = scenario.graph_parameters(None)
    params["sim_bridge"]["cameras_enabled"] = False  # no camera in these phases
    with NodeGraph(GRAPH, {n: params[n] for n in GRAPH},
                   env=ros_environment(ros_domain_id)) as graph:
        probe = RosProbe(ros_domain_id, "test_obstacle_reach")
        try:
            r = scenario.DemoRunner(probe)
            try:
                r.wait_ready(services=("/pmp/reach", "/sim/set_object_pose"))
                r.wait_sim(0.5)
            except Exception:
                print(graph.outputs()[-6000:])
                raise
            yield r
        finally:
            probe.close()


def test_obstacle_reach_keeps_the_fingers_off_the_cylinder(runner):
    """The right hand goes from one side of the cylinder to the other over it: it arrives
    within 1 cm, no link touches the cylinder in the physics (/ground_truth/object_contacts:
    the fingers, up to 10 cm from the hand frame, are what touched it when only the hand frame
    was kept clear) and the cylinder does not move; the plan kept its hulls 2 cm away."""
    r = scenario.obstacle_reach(runner)
    assert r.extra["obstacle_contact_links"] == 0.0, r.message
    assert r.extra["obstacle_moved_m"] < scenario.OBSTACLE_MOVE_TOLERANCE, r.message
    assert r.extra["arrival_m"] <= scenario.OBSTACLE_ARRIVAL_TOLERANCE, r.message
    assert r.extra["planned_clearance_m"] >= scenario.OBSTACLE_CLEARANCE, r.message
    assert r.success, r.message
