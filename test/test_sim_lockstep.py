"""The sim_bridge node in lockstep over real DDS: each step waits for the /effort_command
stamped like the state it answers (its own module: no other sim_bridge in the domain)."""

from __future__ import annotations

import numpy as np
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import JointState

from icub_interfaces.srv import ResetSim
from icub_pmp.config import config_dir
from icub_pmp.testing import NodeProcess, ros_environment


def _ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def _start(domain: int, **params) -> NodeProcess:
    return NodeProcess("sim_bridge", env=ros_environment(domain),
                       params_file=config_dir() / "sim_bridge.yaml", parameters=params)


def _wait_up(probe, proc: NodeProcess) -> None:
    assert probe.wait_for_topic("/joint_states", timeout=60.0), proc.output()[-3000:]


def test_lockstep_waits_for_the_answer(ros_domain_id, ros_probe):
    """In lockstep each state is followed by the next one (1 ms later) only after an
    /effort_command stamped like it arrives: 30 answered states give 30 consecutive steps,
    and without an answer the simulation waits."""
    proc = _start(ros_domain_id, cameras_enabled=False, mode="lockstep",
                  lockstep_timeout=3.0)
    try:
        _wait_up(ros_probe, proc)
        node = ros_probe.node
        pub = node.create_publisher(JointState, "/effort_command", qos_profile_sensor_data)
        assert ros_probe.wait_for(lambda: pub.get_subscription_count() > 0, 30.0)
        seen: list[int] = []
        answered: list[int] = []
        answer = {"left": 30}

        def cb(msg: JointState) -> None:
            seen.append(_ns(msg.header.stamp))
            if answer["left"] > 0:
                answer["left"] -= 1
                answered.append(seen[-1])
                out = JointState(name=["torso_yaw"], effort=[0.0])
                out.header.stamp = msg.header.stamp
                pub.publish(out)

        # the states published before we subscribed go unanswered: the node steps on after
        # each timeout (3 s) until our answers take over
        sub = node.create_subscription(JointState, "/joint_states", cb, qos_profile_sensor_data)
        assert ros_probe.wait_for(lambda: answer["left"] == 0 and len(seen) >= 30, 30.0), \
            proc.output()[-2000:]
        # no answer, no step: the state after our last answer waits the whole timeout (and
        # then the simulator holds the robot, saying so once)
        last = max(answered) + 1_000_000
        assert proc.wait_for_output(f"stamped t = {last * 1e-9:.3f} s within", 30.0), \
            proc.output()[-2000:]
        d = np.diff(sorted(set(seen)))
        assert np.all(d == 1_000_000)
        # services are served while the loop waits (it spins the executor itself)
        for attempt in range(3):  # reset is idempotent: retry a response lost by a new client
            try:
                r = ros_probe.call("/sim/reset", ResetSim, ResetSim.Request(posture="rest"),
                                   timeout=15.0)
                break
            except TimeoutError:
                if attempt == 2:
                    raise
        assert r.success, r.message
        ros_probe.destroy(sub, pub)
    finally:
        rc = proc.stop()
        assert rc == 0, proc.output()[-3000:]
