"""End to end over DDS: sim_bridge (lockstep) + wrench_estimator + impedance_controller as
subprocesses started through their scripts, in a private domain; the test talks to them as a
user would (topics, services), in simulated time. Every test runs twice: with the estimator
and the controller in their own processes, and composed in the torque_loop process
(docs/decisions/0067)."""

from __future__ import annotations

import math
import threading
import time

import numpy as np
import pytest
from geometry_msgs.msg import Wrench, WrenchStamped
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import SetParameters
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from icub_interfaces.srv import ApplyWrench
from icub_pmp.kinematics.robot_spec import RobotSpec
from icub_pmp.ros.conversions import arrays_to_trajectory, sec_to_duration
from icub_pmp.testing import (
    NodeGraph,
    NodeProcess,
    RosProbe,
    repo_root,
    reserve_domain_id,
    ros_environment,
    with_realism,
)

#: the two ways to run the torque loop: separate processes, one composed process
GRAPHS = {"separate": ["sim_bridge", "wrench_estimator", "impedance_controller"],
          "torque_loop": ["sim_bridge", "torque_loop"]}


class _Recorder:
    """Messages of some topics, keyed by header stamp [ns] (thread-safe)."""

    def __init__(self, probe: RosProbe, topics: dict[str, type]):
        self.probe = probe
        self.lock = threading.Lock()
        self.data: dict[str, dict[int, object]] = {t: {} for t in topics}
        self.subs = [probe.node.create_subscription(
            cls, topic, lambda m, t=topic: self._cb(t, m), qos_profile_sensor_data)
            for topic, cls in topics.items()]
        # a new subscription is matched by the publishers after a discovery round that takes
        # a while on a loaded machine: record only once every topic delivers
        assert probe.wait_for(lambda: all(self.data[t] for t in topics), 30.0), \
            {t: len(self.data[t]) for t in topics}

    def _cb(self, topic: str, msg) -> None:
        ns = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        with self.lock:
            self.data[topic][ns] = msg

    def get(self, topic: str) -> dict[int, object]:
        with self.lock:
            return dict(self.data[topic])

    def close(self) -> None:
        """Unsubscribe (a 1 kHz subscription left behind would load the probe's thread)."""
        for sub in self.subs:
            self.probe.destroy(sub)
        self.subs = []


@pytest.fixture(scope="module", params=list(GRAPHS))
def graph(ros_domain_id, request):
    env = ros_environment(ros_domain_id)
    # the ideal simulator: these tests check the loop and the estimator against exact
    # sensors and model (test_control_realism.py and test_dynamics_calibration_node.py: icub)
    params = with_realism("ideal", {
        "sim_bridge": {"mode": "lockstep", "cameras_enabled": False, "imu_decimation": 10},
        "wrench_estimator": {},
        "impedance_controller": {"use_sim_time": True},
    })
    with NodeGraph(GRAPHS[request.param], params, env=env) as g:
        yield g


@pytest.fixture(scope="module")
def probe(graph, ros_domain_id):
    p = RosProbe(ros_domain_id, "control_e2e_probe")
    try:
        assert p.wait_for_topic("/effort_command", 90), graph.outputs()
        assert p.wait_for_topic("/estimated_joint_torques", 90), graph.outputs()
        # discovery between the nodes can take seconds: wait for the data to flow
        assert p.collect("/estimated_joint_torques", JointState, 1, 90.0), graph.outputs()
        assert p.collect("/effort_command", JointState, 1, 90.0), graph.outputs()
        yield p
    finally:
        p.close()


def _sim_time(probe: RosProbe, graph: NodeGraph) -> float:
    c = probe.collect("/clock", Clock, 1, 30.0)
    assert c, "no /clock within 30 s\n" + graph.outputs()
    return c[0].clock.sec + c[0].clock.nanosec * 1e-9


def _wait_sim(probe: RosProbe, graph: NodeGraph, dt: float, timeout: float = 120.0) -> float:
    """Wait until simulated time advanced by ``dt`` [s]; returns the new time."""
    t0 = _sim_time(probe, graph)
    deadline = time.monotonic() + timeout
    t = t0
    while t - t0 < dt and time.monotonic() < deadline:
        time.sleep(0.2)
        t = _sim_time(probe, graph)
    assert t - t0 >= dt, f"simulated time advanced only {t - t0:.3f} s in {timeout} s\n" + \
        graph.outputs()
    return t


def test_lockstep_loop_answers_every_joint_state_and_holds(graph, probe):
    """/effort_command messages carry the stamps of the /joint_states they answer (lockstep),
    the estimator publishes torques stamped like the samples, and the robot holds its rest
    posture within 0.5 deg against gravity."""
    rec = _Recorder(probe, {"/joint_states": JointState, "/effort_command": JointState,
                            "/estimated_joint_torques": JointState})
    _wait_sim(probe, graph, 0.5)
    js, eff, est = (rec.get(t) for t in ("/joint_states", "/effort_command",
                                         "/estimated_joint_torques"))
    rec.close()
    # the probe itself may drop best-effort messages on a loaded machine: check overlaps,
    # not completeness
    assert len(js) > 20 and len(eff) > 20 and len(est) > 5
    common = set(js) & set(eff)
    assert len(common) > 0.5 * min(len(js), len(eff))
    for ns in list(eff) + list(est):  # answers carry simulator step stamps (1 ms grid)
        assert ns % 1_000_000 == 0
    spec = RobotSpec.load()
    rest = spec.posture("rest")
    for msg in list(js.values())[-50:]:
        q = dict(zip(msg.name, msg.position))
        for j in spec.upper_body_joints:
            assert abs(math.degrees(q[j] - rest[j])) < 0.5, j


def test_trajectory_is_followed_and_bad_ones_are_rejected(graph, probe):
    """A /joint_trajectory (r_elbow +0.3 rad in 0.5 s) is followed to within 0.5 deg; a NaN
    point, an unknown joint and non-increasing times are rejected with a logged reason
    while the loop keeps running."""
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    pub = probe.node.create_publisher(JointTrajectory, "/joint_trajectory", qos)
    probe.wait_for(lambda: pub.get_subscription_count() > 0, 20.0)
    js = probe.collect("/joint_states", JointState, 1, 20.0)[0]
    q0 = dict(zip(js.name, js.position))["r_elbow"]
    target = q0 + 0.3
    bad_nan = arrays_to_trajectory(["r_elbow"], [0.5], np.array([[math.nan]]))
    bad_name = arrays_to_trajectory(["r_knee"], [0.5], np.array([[0.1]]))
    bad_time = JointTrajectory(joint_names=["r_elbow"], points=[
        JointTrajectoryPoint(positions=[q0], time_from_start=sec_to_duration(0.5)),
        JointTrajectoryPoint(positions=[q0], time_from_start=sec_to_duration(0.2))])
    for m in (bad_nan, bad_name, bad_time):
        pub.publish(m)
    pub.publish(arrays_to_trajectory(["r_elbow"], [0.5], np.array([[target]])))
    _wait_sim(probe, graph, 0.8)
    js = probe.collect("/joint_states", JointState, 1, 20.0)[0]
    q = dict(zip(js.name, js.position))["r_elbow"]
    assert abs(math.degrees(q - target)) < 0.5
    out = graph.procs[graph.host("impedance_controller")].output()
    assert out.count("/joint_trajectory rejected") >= 3, out[-3000:]
    assert "NaN" in out and "r_knee" in out and "strictly increasing" in out
    probe.destroy(pub)


def test_external_wrench_and_contact_over_dds(graph, probe):
    """A 3 N push on the left hand through /sim/apply_wrench: once the compliant arm has
    settled (0.8 s after the push starts), the estimator's root_link wrench matches
    /ground_truth/contact_wrench/left_hand (same stamps) within 5 % or 0.1 N and the contact
    flag is on."""
    rec = _Recorder(probe, {"/ground_truth/contact_wrench/left_hand": WrenchStamped,
                            "/wrench_estimator/external_wrench_root/left_hand": WrenchStamped})
    contact: list[bool] = []
    sub = probe.node.create_subscription(Bool, "/wrench_estimator/contact/left_hand",
                                         lambda m: contact.append(m.data),
                                         qos_profile_sensor_data)
    # as a user does before pushing (wholeBodyDynamics' calib): the estimator calibrated on
    # the still, free arm; otherwise its start-up calibration could find its still window
    # under the push (the earlier tests moved the arm) and take the push for an offset
    for _ in range(20):
        _wait_sim(probe, graph, 0.6)
        cal = probe.call("/wrench_estimator/calibrate", Trigger, Trigger.Request(), timeout=60.0)
        if cal.success:
            break
    assert cal.success, cal.message
    req = ApplyWrench.Request(target="l_hand_dh_frame", duration=2.0)
    req.wrench = Wrench()
    req.wrench.force.y, req.wrench.force.z = -1.5, 2.6
    resp = probe.call("/sim/apply_wrench", ApplyWrench, req)
    assert resp.success, resp.message
    _wait_sim(probe, graph, 1.2)
    gt = rec.get("/ground_truth/contact_wrench/left_hand")
    est = rec.get("/wrench_estimator/external_wrench_root/left_hand")
    rec.close()

    def force(m) -> np.ndarray:
        return np.array([m.wrench.force.x, m.wrench.force.y, m.wrench.force.z])

    pushed = [ns for ns in sorted(gt) if np.linalg.norm(force(gt[ns])) > 2.9]
    assert pushed
    settled = [ns for ns in sorted(set(gt) & set(est)) if ns >= pushed[0] + 800_000_000]
    assert len(settled) >= 5, (len(gt), len(est))
    errs = [(ns, np.linalg.norm(force(est[ns]) - force(gt[ns])), np.linalg.norm(force(gt[ns])))
            for ns in settled]
    bad = [(ns, e, g) for ns, e, g in errs if e > max(0.05 * g, 0.1)]
    assert not bad, (bad, [round(e, 3) for _, e, _ in errs], graph.outputs()[-4000:])
    probe.destroy(sub)
    assert contact and contact[-1]


def test_runtime_parameters_and_velocity_command(graph, probe):
    """Gains and mode change at run time with validation (an unknown mode and a wrong-length
    gain vector are refused, a valid mode accepted); a velocity command (eq 7) republished
    every 0.1 s at 0.2 rad/s moves r_shoulder_yaw by about 0.2 rad/s x its duration."""
    def set_param(name: str, value: ParameterValue) -> bool:
        req = SetParameters.Request(parameters=[Parameter(name=name, value=value)])
        return probe.call("/impedance_controller/set_parameters", SetParameters,
                          req).results[0].successful

    s = ParameterValue(type=ParameterType.PARAMETER_STRING)
    s.string_value = "admittance"
    assert not set_param("mode", s)
    bad = ParameterValue(type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=[1.0])
    assert not set_param("impedance_stiffness_arm", bad)
    s.string_value = "position"
    assert set_param("mode", s)
    ctl = graph.procs[graph.host("impedance_controller")]
    assert ctl.wait_for_output("mode impedance -> position", 20)

    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    pub = probe.node.create_publisher(JointState, "/impedance_controller/velocity_command", qos)
    probe.wait_for(lambda: pub.get_subscription_count() > 0, 20.0)

    def q_yaw() -> tuple[float, float]:
        m = probe.collect("/joint_states", JointState, 1, 20.0)[0]
        return (m.header.stamp.sec + m.header.stamp.nanosec * 1e-9,
                dict(zip(m.name, m.position))["r_shoulder_yaw"])

    t0, q0 = q_yaw()
    t, q = t0, q0
    deadline = time.monotonic() + 120.0
    while t - t0 < 0.4 and time.monotonic() < deadline:
        pub.publish(JointState(name=["r_shoulder_yaw"], velocity=[0.2]))
        time.sleep(0.05)
        t, q = q_yaw()
    rate = (q - q0) / (t - t0)
    assert 0.1 < rate < 0.3, (rate, t - t0)
    probe.destroy(pub)


def test_hold_service_and_estimate_watchdog(graph, probe):
    """/impedance_controller/hold answers success; killing the estimator (composed: its
    ``enabled`` set false) latches a safe hold within estimate_lost_timeout (0.5 s of
    simulated time), said in the log and on the latched status topic, while the controller
    keeps answering the simulator."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    from icub_interfaces.msg import ControllerStatus

    resp = probe.call("/impedance_controller/hold", Trigger, Trigger.Request())
    assert resp.success, resp.message
    if graph.host("wrench_estimator") == "wrench_estimator":
        graph.kill("wrench_estimator")
    else:  # composed: the estimator in the controller's process stops
        value = ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=False)
        req = SetParameters.Request(parameters=[Parameter(name="enabled", value=value)])
        res = probe.call("/wrench_estimator/set_parameters", SetParameters, req)
        assert res.results[0].successful, res.results[0].reason
    ctl = graph.procs[graph.host("impedance_controller")]
    assert ctl.wait_for_output("estimator lost", 60.0), ctl.output()[-3000:]
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    status = probe.collect("/impedance_controller/status", ControllerStatus, 1, 30.0, latched)
    assert status and status[0].status == "safe_hold", status
    assert "estimator lost" in status[0].safe_hold_reason
    n = len(probe.collect("/effort_command", JointState, 20, 30.0))
    assert n == 20


def test_joint_state_watchdog_trips_safe_hold():
    """A free-running controller alone (timer at 1 kHz, wall clock, own domain) publishes
    effort commands on the joint states it is fed; when they stop its watchdog trips to a
    safe hold with a warning, and it resumes when joint states come back."""
    with reserve_domain_id() as did:
        _watchdog(did)


def _watchdog(did: int) -> None:
    # wall clock: the probe feeds wall-stamped joint states and there is no /clock
    proc = NodeProcess(command=[str(repo_root() / "scripts/impedance_controller.sh"),
                                "--ros-args", "-p", "lockstep:=false", "-p",
                                "use_sim_time:=false"],
                       env=ros_environment(did))
    probe = RosProbe(did, "watchdog_probe")
    try:
        pub = probe.node.create_publisher(JointState, "/joint_states", qos_profile_sensor_data)
        assert probe.wait_for(lambda: pub.get_subscription_count() > 0, 60.0), proc.output()
        spec = RobotSpec.load()
        rest = spec.posture("rest")

        def send(n: int) -> None:
            for _ in range(n):
                m = JointState(name=list(spec.actuated_joints))
                m.header.stamp = probe.node.get_clock().now().to_msg()
                m.position = [rest[j] for j in m.name]
                m.velocity = [0.0] * len(m.name)
                pub.publish(m)
                time.sleep(0.005)

        got: list[JointState] = []
        sub = probe.node.create_subscription(JointState, "/effort_command", got.append,
                                             qos_profile_sensor_data)
        # discovery of the new subscription by the controller's publisher takes a while on a
        # loaded machine: feed joint states until the first answer arrives, then count
        assert probe.wait_for(lambda: send(5) or len(got) > 0, 30.0), proc.output()[-2000:]
        got.clear()
        trips, backs = (proc.output().count(t) for t in ("safe hold", "safe hold released"))
        send(40)
        assert probe.wait_for(lambda: proc.output().count("safe hold") > trips, 20.0), \
            proc.output()[-2000:]
        probe.destroy(sub)
        assert len(got) > 20 and len(got[-1].effort) == len(spec.actuated_joints)
        send(20)
        assert probe.wait_for(lambda: proc.output().count("safe hold released") > backs,
                              20.0), proc.output()[-2000:]
    finally:
        probe.close()
        proc.stop()
