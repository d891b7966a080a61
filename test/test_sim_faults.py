"""Faults of the simulator found in the running graph, reproduced over DDS (sim_bridge as a
subprocess; the probe plays the user and, in lockstep, the controller):

- unphysical requests (a 1e6 N push, a 1e9 s duration, an object 1e6 m away) are refused;
- a push that does make the physics diverge (bounds raised on purpose) is detected, reported
  once on /sim/status and in the log, recovered from, and simulated time never goes back
  (MuJoCo's own auto-reset rewound it to 0 again and again);
- a controller that stops answering in lockstep leaves the robot on the simulator's hold, not
  on its last torques; said on /sim/status and once in the log; commands take over again.
"""

from __future__ import annotations

import threading

import numpy as np
from geometry_msgs.msg import Pose, PoseStamped
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import JointState

from icub_interfaces.msg import SimStatus
from icub_interfaces.srv import ApplyWrench, SetObjectPose
from icub_pmp.config import config_dir
from icub_pmp.kinematics import IcubModel
from icub_pmp.ros.conversions import time_to_ns
from icub_pmp.ros.qos import LATCHED_QOS
from icub_pmp.testing import NodeProcess, ros_environment


def _start(domain: int, **params) -> NodeProcess:
    return NodeProcess("sim_bridge", env=ros_environment(domain),
                       params_file=config_dir() / "sim_bridge.yaml",
                       parameters={"cameras_enabled": False, **params})


class _Status:
    """The latest /sim/status (latched: the current one arrives at once)."""

    def __init__(self, probe) -> None:
        self.msgs: list[SimStatus] = []
        self.sub = probe.node.create_subscription(SimStatus, "/sim/status", self.msgs.append,
                                                  LATCHED_QOS)

    @property
    def last(self) -> SimStatus | None:
        return self.msgs[-1] if self.msgs else None


class _States:
    """Every /joint_states message: (stamp [ns], name -> position)."""

    def __init__(self, probe) -> None:
        self.lock = threading.Lock()
        self.items: list[tuple[int, dict[str, float]]] = []
        self.sub = probe.node.create_subscription(JointState, "/joint_states", self._cb,
                                                  qos_profile_sensor_data)

    def _cb(self, m: JointState) -> None:
        with self.lock:
            self.items.append((time_to_ns(m.header.stamp), dict(zip(m.name, m.position))))

    def since(self, k: int) -> list[tuple[int, dict[str, float]]]:
        with self.lock:
            return list(self.items[k:])

    def __len__(self) -> int:
        with self.lock:
            return len(self.items)


def _call(probe, service: str, srv_type, request):
    return probe.call(service, srv_type, request, timeout=60.0)


def test_unphysical_requests_are_refused(ros_domain_id, ros_probe):
    """/sim/apply_wrench with the issue's {target: box, force: {x: 1e6}, duration: 0.2}, a
    1e9 s duration, and /sim/set_object_pose 1e6 m away answer success=false with the bound
    that was exceeded; the box stays on the table and the simulator keeps running."""
    proc = _start(ros_domain_id)
    try:
        assert ros_probe.wait_for_topic("/joint_states", 60.0), proc.output()[-3000:]
        req = ApplyWrench.Request(target="box", duration=0.2)
        req.wrench.force.x = 1e6
        r = _call(ros_probe, "/sim/apply_wrench", ApplyWrench, req)
        assert not r.success and "max_wrench_force 100 N" in r.message, r.message
        req = ApplyWrench.Request(target="box", duration=1e9)
        req.wrench.force.z = 1.0
        r = _call(ros_probe, "/sim/apply_wrench", ApplyWrench, req)
        assert not r.success and "max_wrench_duration" in r.message, r.message
        pose = Pose()
        pose.position.x, pose.orientation.w = 1e6, 1.0
        r = _call(ros_probe, "/sim/set_object_pose", SetObjectPose,
                  SetObjectPose.Request(name="box", pose=pose))
        assert not r.success and "object_workspace_radius" in r.message, r.message
        box = ros_probe.collect("/ground_truth/objects/box", PoseStamped, 3)
        assert box and abs(box[-1].pose.position.x - (-0.33)) < 0.01
        assert proc.alive()
    finally:
        assert proc.stop() == 0, proc.output()[-3000:]


def test_divergence_is_reported_once_and_time_never_goes_back(ros_domain_id, ros_probe):
    """With the force bound raised on purpose, a 1e6 N push on the right hand makes the physics
    diverge. The simulator recovers once (not a reset loop): /sim/status counts one divergence
    and says what was done, the log says it once, /joint_states stamps never go back, and the
    robot is back within its joint limits."""
    proc = _start(ros_domain_id, max_wrench_force=1e7)
    status = _Status(ros_probe)
    states = _States(ros_probe)
    try:
        assert ros_probe.wait_for(lambda: len(states) > 50, 60.0), proc.output()[-3000:]
        assert ros_probe.wait_for(lambda: status.last is not None, 30.0)
        assert status.last.divergences == 0 and status.last.status == "running"
        k = len(states)
        req = ApplyWrench.Request(target="r_hand_dh_frame", duration=0.2)
        req.wrench.force.x = 1e6
        r = _call(ros_probe, "/sim/apply_wrench", ApplyWrench, req)
        assert r.success, r.message
        assert ros_probe.wait_for(lambda: status.last.divergences >= 1, 30.0), \
            proc.output()[-3000:]
        n = len(states)
        assert ros_probe.wait_for(lambda: len(states) > n + 500, 60.0)  # 0.5 s more
        assert status.last.divergences == 1, status.last
        assert "divergence_speed" in status.last.last_divergence
        assert "restored the state" in status.last.last_divergence
        assert proc.output().count("the physics diverged") == 1, proc.output()[-3000:]
        stamps = np.array([s for s, _ in states.since(k)])
        assert np.all(np.diff(stamps) > 0), "simulated time went back"
        model = IcubModel()
        q = model.q_from_dict(states.since(len(states) - 1)[0][1])
        assert np.all(q >= model.lower - 0.02) and np.all(q <= model.upper + 0.02), q
        assert proc.alive()
    finally:
        ros_probe.destroy(status.sub, states.sub)
        assert proc.stop() == 0, proc.output()[-3000:]


def test_lockstep_without_answers_holds_the_robot_not_its_last_torques(ros_domain_id,
                                                                        ros_probe):
    """A lockstep 'controller' (the probe) drives l_elbow with +3 N m, then stops answering.
    The simulator then holds every joint where it was (the elbow stays within 0.03 rad over
    60+ further steps; with the last torque kept it would move about 0.1 rad), says so once in
    the log and as 'holding' on /sim/status; when answers come back it says so and the
    commanded torque drives the elbow again."""
    proc = _start(ros_domain_id, mode="lockstep", lockstep_timeout=0.05)
    status = _Status(ros_probe)
    states = _States(ros_probe)
    node = ros_probe.node
    pub = node.create_publisher(JointState, "/effort_command", qos_profile_sensor_data)
    answering = threading.Event()
    answering.set()

    def answer(msg: JointState) -> None:
        if answering.is_set():
            out = JointState(name=["l_elbow"], effort=[3.0])
            out.header.stamp = msg.header.stamp
            pub.publish(out)

    sub = node.create_subscription(JointState, "/joint_states", answer,
                                   qos_profile_sensor_data)
    try:
        assert ros_probe.wait_for(lambda: pub.get_subscription_count() > 0, 60.0), \
            proc.output()[-3000:]
        # answered steps run at the probe's pace; 100 steps of +3 N m move the elbow
        k0 = len(states)
        assert ros_probe.wait_for(lambda: len(states) > k0 + 100, 60.0), proc.output()[-3000:]
        assert ros_probe.wait_for(
            lambda: status.last is not None and status.last.status == "running", 30.0)
        mark = len(proc.output())  # (a loaded machine may have missed a 50 ms answer before)
        answering.clear()
        assert ros_probe.wait_for(lambda: status.last.status == "holding", 30.0), \
            proc.output()[-3000:]
        assert "lockstep_timeout" in status.last.message
        k = len(states)
        assert ros_probe.wait_for(lambda: len(states) > k + 60, 60.0)  # one step per 0.05 s
        held = [q["l_elbow"] for _, q in states.since(k)]
        assert max(held) - min(held) < 0.03, (min(held), max(held))
        out = proc.output()[mark:]
        assert out.count("every joint on the simulator's hold") == 1, out[-3000:]
        assert "stepping with the last command" not in out
        answering.set()
        assert ros_probe.wait_for(lambda: status.last.status == "running", 30.0), \
            proc.output()[-3000:]
        assert proc.wait_for_output("/effort_command is back", 10.0)
        k = len(states)
        assert ros_probe.wait_for(lambda: len(states) > k + 100, 60.0)
        moved = [q["l_elbow"] for _, q in states.since(k)]
        assert moved[-1] - moved[0] > 0.03  # driven by the torque again
    finally:
        ros_probe.destroy(sub, pub, status.sub, states.sub)
        assert proc.stop() == 0, proc.output()[-3000:]


def test_free_run_without_commands_holds_the_robot(ros_domain_id, ros_probe):
    """Free run: a 'controller' (the probe) drives l_elbow with +3 N m, then falls silent.
    After command_timeout (0.3 s of wall time) the simulator holds every joint where it was
    ('holding' on /sim/status, 'command_timeout' in the message); the elbow stays put while
    simulated time runs on (with the torque kept it would run into its limit)."""
    proc = _start(ros_domain_id, command_timeout=0.3)
    status = _Status(ros_probe)
    states = _States(ros_probe)
    pub = ros_probe.node.create_publisher(JointState, "/effort_command",
                                          qos_profile_sensor_data)
    try:
        assert ros_probe.wait_for(lambda: pub.get_subscription_count() > 0, 60.0), \
            proc.output()[-3000:]
        assert ros_probe.wait_for(lambda: status.last is not None, 30.0)
        cmd = JointState(name=["l_elbow"], effort=[3.0])
        assert ros_probe.wait_for(lambda: pub.publish(cmd) or status.last.command_wall_age
                                  >= 0.0, 30.0)  # a command was accepted
        assert status.last.status == "running"
        assert ros_probe.wait_for(lambda: status.last.status == "holding", 30.0), \
            proc.output()[-3000:]
        assert "command_timeout" in status.last.message
        k = len(states)
        assert ros_probe.wait_for(lambda: len(states) > k + 300, 60.0)  # 0.3 s simulated
        held = [q["l_elbow"] for _, q in states.since(k)]
        assert max(held) - min(held) < 0.03, (min(held), max(held))
    finally:
        ros_probe.destroy(pub, status.sub, states.sub)
        assert proc.stop() == 0, proc.output()[-3000:]


def test_pause_is_reported_on_the_status(ros_domain_id, ros_probe):
    """/sim/set_paused shows on /sim/status ('paused', with the reason) and back."""
    from std_srvs.srv import SetBool

    proc = _start(ros_domain_id)
    status = _Status(ros_probe)
    try:
        assert ros_probe.wait_for(lambda: status.last is not None, 60.0), proc.output()[-3000:]
        r = _call(ros_probe, "/sim/set_paused", SetBool, SetBool.Request(data=True))
        assert r.success, r.message
        assert ros_probe.wait_for(lambda: status.last.status == "paused", 30.0)
        assert "/sim/set_paused" in status.last.message
        r = _call(ros_probe, "/sim/set_paused", SetBool, SetBool.Request(data=False))
        assert ros_probe.wait_for(lambda: status.last.status == "running", 30.0)
    finally:
        ros_probe.destroy(status.sub)
        assert proc.stop() == 0, proc.output()[-3000:]
