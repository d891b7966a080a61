"""Faults of the wrench estimator found in the running graph, reproduced over DDS (sim_bridge
and wrench_estimator as subprocesses):

- simulated time going back (a restarted simulator) silenced the estimator until the new
  time passed the old maximum: it now says so and estimates the new timeline at once;
- a malformed /joint_states message from a second publisher, stamped like a real sample, cost
  that real sample: it is now dropped on arrival and the real sample is estimated.
"""

from __future__ import annotations

import threading

from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from sensor_msgs.msg import JointState

from icub_pmp.config import config_dir
from icub_pmp.ros.conversions import time_to_ns
from icub_pmp.testing import NodeProcess, ros_environment

MS = 1_000_000


def _sim(domain: int, **params) -> NodeProcess:
    return NodeProcess("sim_bridge", env=ros_environment(domain),
                       params_file=config_dir() / "sim_bridge.yaml",
                       parameters={"cameras_enabled": False, **params})


def _estimator(domain: int, **params) -> NodeProcess:
    return NodeProcess("wrench_estimator", env=ros_environment(domain),
                       params_file=config_dir() / "wrench_estimator.yaml", parameters=params)


class _Stamps:
    """Stamps [ns] of every message received on a JointState topic."""

    def __init__(self, probe, topic: str) -> None:
        self.lock = threading.Lock()
        self.stamps: list[int] = []
        # deep: a probe thread busy for a moment must not lose what the test counts
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.sub = probe.node.create_subscription(JointState, topic, self._cb, qos)

    def _cb(self, m: JointState) -> None:
        with self.lock:
            self.stamps.append(time_to_ns(m.header.stamp))

    def get(self) -> list[int]:
        with self.lock:
            return list(self.stamps)


def test_estimator_goes_on_at_once_when_simulated_time_goes_back(ros_domain_id, ros_probe):
    """The simulator runs past t = 3 s, is stopped and started again (its time starts at 0;
    started paused, then run once it is in the graph). The estimator logs that simulated time
    went back and publishes estimates of the new timeline within its first 1.5 s, not only
    once the new time passes the old maximum."""
    from std_srvs.srv import SetBool

    est = _estimator(ros_domain_id)
    sim = _sim(ros_domain_id)
    out = _Stamps(ros_probe, "/estimated_joint_torques")
    try:
        assert ros_probe.wait_for(lambda: out.get() and max(out.get()) > 3_000 * MS, 120.0), \
            sim.output()[-2000:] + est.output()[-2000:]
        assert sim.stop() == 0, sim.output()[-3000:]
        old_max = max(out.get())
        sim = _sim(ros_domain_id, start_paused=True)
        r = ros_probe.call("/sim/set_paused", SetBool, SetBool.Request(data=False), 60.0)
        assert r.success, r.message
        assert ros_probe.wait_for(lambda: any(s < 1_500 * MS for s in out.get()), 60.0), \
            (old_max, out.get()[-5:], est.output()[-3000:])
        assert est.wait_for_output("simulated time went back", 10.0), est.output()[-3000:]
        assert est.alive()
    finally:
        ros_probe.destroy(out.sub)
        sim.stop()
        assert est.stop() == 0, est.output()[-3000:]


def test_a_bad_joint_state_does_not_cost_the_real_sample_of_its_stamp(ros_domain_id,
                                                                      ros_probe):
    """Lockstep, estimator pairing each joint state with the latest FT (require_same_stamp
    false: each joint state is processed as it comes). Before every other step a second
    publisher sends a /joint_states message with one position missing, stamped like the real
    sample that follows. The bad ones are dropped on arrival with a warning, and the real
    samples they imitate are estimated as often as the others (the bad one used to claim the
    stamp and the real one was dropped: none of them was estimated). On a loaded machine the
    estimator's best-effort subscription loses some samples of both kinds alike."""
    est = _estimator(ros_domain_id, require_same_stamp=False)
    sim = _sim(ros_domain_id, mode="lockstep", lockstep_timeout=3.0)
    node = ros_probe.node
    effort = node.create_publisher(JointState, "/effort_command", qos_profile_sensor_data)
    rogue = node.create_publisher(JointState, "/joint_states", qos_profile_sensor_data)
    out = _Stamps(ros_probe, "/estimated_joint_torques")
    injected: list[int] = []
    clean: list[int] = []
    left = {"n": 0}

    def on_state(msg: JointState) -> None:
        if len(msg.position) != len(msg.name):
            return  # our own bad message
        if left["n"] > 0:
            left["n"] -= 1
            nxt = time_to_ns(msg.header.stamp) + MS
            if left["n"] % 2:
                bad = JointState(name=list(msg.name), position=list(msg.position)[:-1],
                                 velocity=list(msg.velocity))
                bad.header.stamp.sec, bad.header.stamp.nanosec = divmod(nxt, 1_000_000_000)
                rogue.publish(bad)
                injected.append(nxt)
            else:
                clean.append(nxt)
        answer = JointState(name=["torso_yaw"], effort=[0.0])
        answer.header.stamp = msg.header.stamp
        effort.publish(answer)

    sub = node.create_subscription(JointState, "/joint_states", on_state,
                                   qos_profile_sensor_data)
    try:
        assert ros_probe.wait_for(lambda: len(out.get()) > 20, 120.0), \
            sim.output()[-2000:] + est.output()[-2000:]
        # matched by the estimator (the probe's own subscription is the other one)
        assert ros_probe.wait_for(lambda: rogue.get_subscription_count() >= 2, 30.0)
        left["n"] = 200
        assert ros_probe.wait_for(lambda: left["n"] == 0, 120.0), sim.output()[-2000:]
        last = max(injected + clean)
        assert ros_probe.wait_for(lambda: max(out.get()) > last + 20 * MS, 60.0)
        got = set(out.get())
        estimated_injected = sum(s in got for s in injected)
        estimated_clean = sum(s in got for s in clean)
        assert estimated_injected >= len(injected) // 2, (estimated_injected, estimated_clean)
        assert estimated_injected >= estimated_clean - 10, (estimated_injected, estimated_clean)
        assert "a message dropped on arrival" in est.output(), est.output()[-3000:]
    finally:
        ros_probe.destroy(sub, effort, rogue, out.sub)
        assert sim.stop() == 0, sim.output()[-3000:]
        assert est.stop() == 0, est.output()[-3000:]
