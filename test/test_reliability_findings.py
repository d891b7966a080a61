"""Bugs the interface fuzzer found (issue 22), pinned on the cores: each was a hang of the
node's service or action (the executor busy for hours), now a clear rejection at once."""

from __future__ import annotations

import time

import numpy as np
import pytest

from icub_pmp.cartesian import CartesianController, MinJerkConfig
from icub_pmp.errors import ConfigError, InvalidInput
from icub_pmp.gaze.gaze_controller import GazeController
from icub_pmp.gaze.gaze_controller_config import GazeControllerConfig
from icub_pmp.kinematics.robot_spec import RobotSpec


@pytest.mark.parametrize("asked", [1e9, 1e300, 60.5])
def test_cartesian_goal_longer_than_max_trajectory_time_is_rejected(vm_ik_solver, asked):
    """A go-to-pose asking trajectory_time 1e9 s used to roll out 4e11 samples in the
    service call (no answer, every other request of the node stuck behind it)."""
    ctrl = CartesianController(vm_ik_solver, MinJerkConfig())
    with pytest.raises(InvalidInput, match="max_trajectory_time"):
        ctrl.trajectory_time(asked)
    assert ctrl.trajectory_time(60.0) == 60.0
    assert ctrl.trajectory_time(0.0) == MinJerkConfig().trajectory_time


def test_gaze_neck_time_longer_than_max_is_rejected_at_once(model):
    """A look_at asking duration 1e9 s used to roll out 3e11 samples in the service call."""
    gaze = GazeController(model=model)
    rest = dict(RobotSpec.load().posture("rest"))
    t0 = time.perf_counter()
    with pytest.raises(InvalidInput, match="max_neck_traj_time"):
        gaze.plan(np.array([-0.4, 0.0, 0.0]), rest, neck_traj_time=1e9)
    assert time.perf_counter() - t0 < 5.0
    plan = gaze.plan(np.array([-0.4, 0.0, 0.0]), rest, neck_traj_time=1.0)
    assert plan.duration > 0


def test_max_durations_are_validated():
    """The new bounds cannot be set below the default times."""
    with pytest.raises(ConfigError, match="max_trajectory_time"):
        MinJerkConfig(trajectory_time=2.0, max_trajectory_time=1.0).validate()
    with pytest.raises(ConfigError, match="max_neck_traj_time"):
        GazeControllerConfig(max_neck_traj_time=0.5).validate()


def test_goal_to_a_paused_simulators_controller_ends(ros_probe, ros_domain_id):
    """A case next to one the bench's fuzzer reported as a hang (2026-12-02: a
    FollowJointTrajectory goal not ended 15 s after its cancel, the simulator possibly left
    paused by the fuzzed /sim/set_paused): with the simulator paused and the controller in
    safe hold, a goal and its cancel end within 15 s (they do: the hang was not reproduced
    this way; goals and cancels are now sent on the probe's spin thread, see
    RosProbe.on_spin_thread)."""
    from std_srvs.srv import SetBool
    from trajectory_msgs.msg import JointTrajectoryPoint

    from icub_interfaces.action import FollowJointTrajectory
    from icub_interfaces.msg import ControllerStatus
    from icub_pmp.config import config_dir
    from icub_pmp.ros.qos import LATCHED_QOS
    from icub_pmp.testing import NodeProcess, ros_environment

    env = ros_environment(ros_domain_id)
    status: list = []
    ros_probe.node.create_subscription(ControllerStatus, "/impedance_controller/status",
                                       status.append, LATCHED_QOS)
    sim = NodeProcess("sim_bridge", env=env, params_file=config_dir() / "sim_bridge.yaml",
                      parameters={"cameras_enabled": False})
    ctrl = NodeProcess("impedance_controller", env=env,
                       params_file=config_dir() / "impedance_controller.yaml",
                       parameters={"mode": "position"})
    with sim, ctrl:
        client = ros_probe.action_client("/impedance_controller/follow_joint_trajectory",
                                          FollowJointTrajectory, timeout=120.0)
        req = SetBool.Request()
        req.data = True
        assert ros_probe.call("/sim/set_paused", SetBool, req, 60.0).success
        assert ros_probe.wait_for(lambda: status and status[-1].status == "safe_hold", 60.0)
        goal = FollowJointTrajectory.Goal()
        goal.trajectory.joint_names = ["r_elbow"]
        pt = JointTrajectoryPoint()
        pt.positions = [0.8]
        pt.time_from_start.sec = 2
        goal.trajectory.points = [pt]
        sent = ros_probe.on_spin_thread(lambda: client.send_goal_async(goal))
        assert ros_probe.wait_for(sent.done, 30.0)
        handle = sent.result()
        assert handle.accepted
        result = handle.get_result_async()
        ros_probe.on_spin_thread(handle.cancel_goal_async)
        assert ros_probe.wait_for(result.done, 15.0), ctrl.output()[-3000:]
        req.data = False
        ros_probe.call("/sim/set_paused", SetBool, req, 30.0)


@pytest.mark.integration
def test_a_malformed_parameter_request_is_refused_and_the_node_keeps_serving(ros_probe,
                                                                             ros_domain_id):
    """A ~/set_parameters request with a ParameterValue of an unknown type (254) made rclpy's
    parameter service raise and killed every node of the graph (fuzzer, 2026-12-03); now it
    is refused with the reason and the node answers the next request."""
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters

    from icub_pmp.testing import NodeGraph

    with NodeGraph(["posture_publisher"], {}) as graph:
        bad = SetParameters.Request(parameters=[Parameter(
            name="rate", value=ParameterValue(type=254, double_value=1.0))])
        res = ros_probe.call("/posture_publisher/set_parameters", SetParameters, bad, 60.0)
        assert len(res.results) == 1 and not res.results[0].successful
        assert "invalid request" in res.results[0].reason, res.results[0].reason
        assert graph.procs["posture_publisher"].alive(), graph.outputs()
        good = SetParameters.Request(parameters=[Parameter(
            name="no_such_parameter", value=ParameterValue(
                type=ParameterType.PARAMETER_DOUBLE, double_value=1.0))])
        res = ros_probe.call("/posture_publisher/set_parameters", SetParameters, good, 30.0)
        assert len(res.results) == 1 and not res.results[0].successful
        assert graph.procs["posture_publisher"].alive(), graph.outputs()


@pytest.mark.integration
def test_robot_state_publisher_drops_corrupt_joint_states(ros_probe, ros_domain_id):
    """Truncated CDR on /joint_states killed robot_state_publisher (its raw subscription
    deserialised without a guard; fuzzer, 2026-12-03): now it drops them with a warning and
    keeps publishing /tf for good ones."""
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import JointState
    from tf2_msgs.msg import TFMessage

    from icub_pmp.kinematics.robot_spec import RobotSpec
    from icub_pmp.testing import NodeGraph

    spec = RobotSpec.load()
    good = JointState(name=list(spec.upper_body_joints),
                      position=[0.0] * len(spec.upper_body_joints))
    raw = serialize_message(good)
    with NodeGraph(["robot_state_publisher"], {"robot_state_publisher":
                                                {"use_sim_time": False}}) as graph:
        pub = ros_probe.node.create_publisher(
            JointState, "/joint_states", QoSProfile(depth=50,
                                                    reliability=ReliabilityPolicy.RELIABLE))
        assert ros_probe.wait_for(lambda: pub.get_subscription_count() >= 1, 60.0)
        for i in range(1, 20):
            pub.publish(raw[: (len(raw) * i) // 20])  # truncated CDR
            time.sleep(0.12)  # past the /tf rate limit, so each one is read
        time.sleep(1.0)
        assert graph.procs["robot_state_publisher"].alive(), graph.outputs()
        got: list = []
        sub = ros_probe.node.create_subscription(TFMessage, "/tf", got.append, 10)
        ros_probe.wait_for(lambda: (pub.publish(good), time.sleep(0.1), bool(got))[-1], 30.0)
        assert got, graph.outputs()
        assert "cannot deserialise" in graph.procs["robot_state_publisher"].output()
        ros_probe.destroy(sub)
        ros_probe.destroy(pub)
