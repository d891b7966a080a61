"""The cartesian_solver's go_to_pose action in closed loop (issue 17: the min-jerk Cartesian
controller closes the loop on the measured joints, the reaching paper's Fig 8): the generator
is fed back with /joint_states every 10 ms and its joint velocities go to the impedance
controller's velocity mode; the hand arrives within 1 cm, measured on the imperfect robot
(realism icub), and a cancel stops the arm where it is."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.testing import NodeGraph

pytestmark = pytest.mark.integration

GRAPH = ["sim_bridge", "wrench_estimator", "impedance_controller", "cartesian_solver"]
PARAMS = {
    "sim_bridge": {"cameras_enabled": False, "realism.preset": "icub"},
    "wrench_estimator": {"calibrate_at_startup": True},
    "cartesian_solver": {"execution": "closed_loop", "codegen": False},
}


@pytest.fixture(scope="module")
def closed_loop(ros_domain_id, ros_probe_module):
    from sensor_msgs.msg import JointState

    from icub_interfaces.action import GoToPose

    probe = ros_probe_module
    with NodeGraph(GRAPH, PARAMS) as graph:
        assert probe.collect("/joint_states", JointState, 1, 120.0), graph.outputs()
        client = probe.action_client("/cartesian/go_to_pose_action", GoToPose, timeout=180.0)
        assert client.server_is_ready(), graph.outputs()
        velocities: list = []
        probe.node.create_subscription(JointState, "/impedance_controller/velocity_command",
                                       velocities.append, 100)
        yield probe, graph, client, velocities
        probe.destroy(client)


def _goal(p: list[float], T: float = 1.5):
    from icub_interfaces.action import GoToPose

    g = GoToPose.Goal()
    g.chain = "right_arm"
    g.target.header.frame_id = "root_link"
    g.target.pose.position.x, g.target.pose.position.y, g.target.pose.position.z = p
    g.trajectory_time = T
    return g


def _hand(probe) -> np.ndarray:
    from sensor_msgs.msg import JointState

    from icub_pmp.kinematics.robot_model import IcubModel

    m = IcubModel()
    js = probe.collect("/joint_states", JointState, 1, 30.0)[-1]
    q = m.q_from_dict(dict(zip(js.name, js.position)), m.posture("rest"))
    return m.frame_position(q, m.spec.hand_frame("right"))


def test_the_hand_arrives_through_velocity_commands_on_the_measured_joints(closed_loop):
    probe, graph, client, velocities = closed_loop
    target = [-0.28, 0.16, 0.06]
    res = probe.send_goal(client, _goal(target), 180.0)
    r = res.result
    assert r.success and r.outcome == "reached", (r.message, graph.outputs())
    assert "closed loop" in r.message, r.message
    assert r.arrival_position_error < 0.01
    assert np.linalg.norm(_hand(probe) - target) < 0.01
    # one command every 10 ms of the motion (T = 1.5 s and the settling): at least 100
    assert len(velocities) >= 100, len(velocities)
    assert set(velocities[-1].name) == {f"r_{j}" for j in (
        "shoulder_pitch", "shoulder_roll", "shoulder_yaw", "elbow", "wrist_prosup",
        "wrist_pitch", "wrist_yaw")}
    assert np.allclose(velocities[-1].velocity, 0.0)  # the last one stops the arm


def test_a_canceled_goal_stops_the_velocity_commands(closed_loop):
    probe, graph, client, velocities = closed_loop

    def cancel_soon(handle) -> None:
        import threading
        threading.Timer(1.0, handle.cancel_goal_async).start()

    res = probe.send_goal(client, _goal([-0.30, 0.10, 0.12], T=3.0), 180.0,
                          on_accepted=cancel_soon)
    assert res.result.outcome == "canceled", res.result.message
    n = len(velocities)
    assert np.allclose(velocities[-1].velocity, 0.0)
    probe.wait_for(lambda: False, 1.0)
    assert len(velocities) == n  # nothing more was commanded
