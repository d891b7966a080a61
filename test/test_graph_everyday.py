"""The everyday graph exactly as the README starts it: ``scripts/graph.sh`` (the simulator
free-running with its cameras, every node, simulated time), in the session's own domain.

Goals go through the actions and the CLI and are judged in the physics: the hands' positions
computed from the simulator's /joint_states, not the planners' answers. A simulator killed in
the middle of a motion ends the goal "aborted" with the reason.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess

import numpy as np
import pytest

from icub_pmp.kinematics import IcubModel
from icub_pmp.ros.reach_goal_message import reach_goal_message
from icub_pmp.testing import NodeProcess, repo_root

pytestmark = pytest.mark.integration


class Robot:
    """The measured robot, seen by the probe: hand positions from /joint_states."""

    def __init__(self, probe):
        from rclpy.qos import qos_profile_sensor_data
        from sensor_msgs.msg import JointState

        self.model = IcubModel()
        self.js = None
        probe.node.create_subscription(JointState, "/joint_states", self._on_js,
                                       qos_profile_sensor_data)

    def _on_js(self, m) -> None:
        self.js = m

    def hand(self, hand: str) -> np.ndarray:
        q = self.model.q_from_dict(dict(zip(self.js.name, self.js.position)))
        return self.model.frame_position(q, self.model.spec.hand_frame(hand))


@pytest.fixture(scope="module")
def everyday(ros_domain_id, ros_probe_module):
    """scripts/graph.sh with its defaults, stopped with SIGTERM at the end (it must stop every
    node it started)."""
    proc = NodeProcess(command=[str(repo_root() / "scripts/graph.sh")], env=dict(os.environ))
    probe = ros_probe_module
    robot = Robot(probe)
    try:
        from icub_interfaces.action import Reach

        client = probe.action_client("/pmp/reach_action", Reach, timeout=180.0)
        assert probe.wait_for(lambda: robot.js is not None, 60.0), proc.output()[-3000:]
        yield proc, probe, robot, client
    finally:
        pids = [int(p) for p in re.findall(r"started \w+ \(pid (\d+)\)", proc.output())]
        if proc.alive():
            os.kill(proc.pid, signal.SIGTERM)
            try:
                proc.proc.wait(30.0)
            except subprocess.TimeoutExpired:
                pass
        alive = [p for p in pids if _alive(p)]
        proc.stop()
        assert not alive, f"graph.sh left nodes running after SIGTERM: {alive}"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def _goal(targets: dict[str, list[float]], tau: float = 2.0, torso: bool = False):
    return reach_goal_message(targets, tau, use_torso=torso)


def test_reach_action_arrives_within_1cm_in_the_physics(everyday):
    """A bimanual reach through /pmp/reach_action: feedback arrives (planning, executing,
    measured hand errors), the result says reached, and the hands computed from the
    simulator's joint states are within 1 cm of their targets."""
    proc, probe, robot, client = everyday
    targets = {"left": [-0.30, -0.15, 0.05], "right": [-0.28, 0.18, 0.08]}
    fb: list = []
    res = probe.send_goal(client, _goal(targets, tau=1.5, torso=True), 120.0, feedback=fb)
    r = res.result
    assert r.success and r.outcome == "reached", (r.message, proc.output()[-3000:])
    phases = {f.phase for f in fb}
    assert {"planning", "executing"} <= phases, phases
    for h, p in targets.items():
        err = np.linalg.norm(robot.hand(h) - np.asarray(p))
        assert err < 0.01, f"{h} hand {err * 1e3:.1f} mm from its target"
        k = list(r.hands).index(h)
        assert abs(r.arrival_errors[k] - err) < 0.005  # the result is the measured error


def test_cli_reach_waits_and_prints_the_measured_error(everyday):
    """``icub reach`` (the README's everyday call) executes, waits and prints the arrival
    error; the hand is within 1 cm of the target in the physics."""
    proc, probe, robot, _ = everyday
    out = subprocess.run([str(repo_root() / "scripts/env.sh"), "icub", "reach",
                          "right=-0.25,0.20,0.10", "--tau", "2"],
                         capture_output=True, text=True, timeout=180, env=dict(os.environ))
    assert out.returncode == 0, out.stdout + out.stderr
    assert "outcome: reached" in out.stdout and "arrival error" in out.stdout
    probe.wait_for(lambda: False, 0.5)  # let the latest joint state arrive
    assert np.linalg.norm(robot.hand("right") - [-0.25, 0.20, 0.10]) < 0.01


def test_a_too_fast_goal_is_slowed_down_to_the_joint_limits(everyday):
    """tau = 0.01 s asks the joints for far more than 100 deg/s: the planner stretches the
    plan to the limits, says so, and the goal is still reached."""
    proc, probe, robot, client = everyday
    res = probe.send_goal(client, _goal({"right": [-0.30, 0.12, 0.02]}, tau=0.01), 120.0)
    r = res.result
    assert r.success, r.message
    assert "slowed down to the joint limits" in r.message
    assert r.tau_used > 0.1


def test_cartesian_go_to_pose_action_arrives_within_1cm(everyday):
    from icub_interfaces.action import GoToPose

    proc, probe, robot, _ = everyday
    client = probe.action_client("/cartesian/go_to_pose_action", GoToPose, timeout=120.0)
    try:
        g = GoToPose.Goal()
        g.chain = "right_arm"
        g.target.pose.position.x, g.target.pose.position.y = -0.28, 0.16
        g.target.pose.position.z = 0.06
        g.trajectory_time = 1.5
        res = probe.send_goal(client, g, 120.0)
        r = res.result
        assert r.success and r.outcome == "reached", r.message
        assert np.linalg.norm(robot.hand("right") - [-0.28, 0.16, 0.06]) < 0.01
    finally:
        probe.destroy(client)


def test_simulator_killed_mid_motion_aborts_the_goal_with_the_reason(everyday):
    """SIGKILL of sim_bridge while a reach executes: the goal ends aborted (never "reached")
    and the message says that joint states stopped. Runs last: the simulator is gone."""
    proc, probe, robot, client = everyday
    # the simulator's process: sim_bridge, or robot_loop (ROBOT_LOOP=1 scripts/graph.sh)
    sim_pid = int(re.search(r"started (?:sim_bridge|robot_loop) \(pid (\d+)\)",
                            proc.output()).group(1))

    def kill_when_moving(handle) -> None:
        probe.wait_for(lambda: False, 1.0)
        os.kill(sim_pid, signal.SIGKILL)

    res = probe.send_goal(client, _goal({"right": [-0.30, 0.20, 0.12]}, tau=4.0), 120.0,
                          on_accepted=kill_when_moving)
    r = res.result
    assert not r.success and r.outcome == "aborted", (res.status, r.message, proc.output()[-4000:])
    assert "simulator" in r.message and ("paused or gone" in r.message), r.message


def test_the_foxglove_layout_shows_topics_the_graph_publishes(everyday):
    """config/foxglove/demo.json names only topics the everyday graph publishes (the
    peripersonal maps come from a node started on its own)."""
    from icub_pmp.bags.foxglove_layout import layout_topics

    _, probe, _, _ = everyday
    wanted = layout_topics() - {"/peripersonal/maps"}
    assert {"/robot_description", "/cam/left/image_raw", "/ft/r_arm_ft",
            "/pmp/predicted_path/right_hand"} <= wanted

    def published() -> set[str]:
        return {name for name, _ in probe.node.get_topic_names_and_types()
                if probe.node.count_publishers(name) > 0}

    probe.wait_for(lambda: wanted <= published(), 60.0)
    assert wanted <= published(), sorted(wanted - published())
