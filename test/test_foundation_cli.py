"""The `icub` command line and scripts/run_node.sh over real DDS."""

from __future__ import annotations

import sys
import time

import pytest
import yaml

from icub_pmp.kinematics import RobotSpec
from icub_pmp.testing import NodeProcess, repo_root, run_icub

icub = run_icub  # `scripts/env.sh icub ARGS` in the session's domain


@pytest.fixture(scope="module")
def posture_node(ros_domain_id):
    """posture_publisher at 100 Hz, started the way a user starts it."""
    with NodeProcess("posture_publisher", parameters={"rate_hz": 100.0}) as proc:
        assert proc.wait_for_output("publishing posture", 30), proc.output()
        yield proc


def test_graph_lists_node_started_by_run_node(posture_node, ros_probe):
    """A node started with scripts/run_node.sh shows up in `icub graph` with its topic."""
    assert ros_probe.wait_for_topic("/joint_states", 20)
    for _ in range(3):  # discovery time varies (12 ms .. 2.6 s measured)
        out = icub("graph", "--wait", "3")
        if "/posture_publisher" in out.stdout:
            break
    assert out.returncode == 0, out.stderr
    assert "/posture_publisher" in out.stdout
    assert "/joint_states [sensor_msgs/msg/JointState]" in out.stdout


def test_echo_receives_real_messages(posture_node, ros_probe):
    """`icub echo --count 2` prints two JointState documents with the rest posture."""
    assert ros_probe.wait_for_topic("/joint_states", 20)
    out = icub("echo", "/joint_states", "--count", "2", "--timeout", "20")
    assert out.returncode == 0, out.stderr
    docs = [d for d in yaml.safe_load_all(out.stdout) if d]
    assert len(docs) == 2
    rest = RobotSpec.load().posture("rest")
    msg = docs[0]
    got = dict(zip(msg["name"], msg["position"]))
    assert got["r_elbow"] == pytest.approx(rest["r_elbow"])
    assert got["l_shoulder_roll"] == pytest.approx(rest["l_shoulder_roll"])


def test_hz_within_ten_percent_of_publisher_rate(posture_node, ros_probe):
    """`icub hz` reports the rate the publisher achieved (its 100 Hz timer, fewer on a loaded
    machine: measured from the message stamps over the same window) within 10 %."""
    from sensor_msgs.msg import JointState

    assert ros_probe.wait_for_topic("/joint_states", 20)
    seen: list[tuple[float, float]] = []  # (arrival [s, wall], stamp [s])
    sub = ros_probe.node.create_subscription(
        JointState, "/joint_states",
        lambda m: seen.append((time.monotonic(),
                               m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec)), 10)
    try:
        out = icub("hz", "/joint_states", "--duration", "3")
        t_end = time.monotonic()
    finally:
        ros_probe.destroy(sub)
    assert out.returncode == 0, out.stderr
    rate = float(out.stdout.split("average rate:")[1].split("Hz")[0])
    window = [stamp for arrival, stamp in seen if arrival >= t_end - 3.0]
    assert len(window) > 10, f"{len(seen)} messages seen by the probe"
    achieved = (len(window) - 1) / (window[-1] - window[0])
    assert abs(rate - achieved) <= 0.1 * achieved, (out.stdout, achieved)


@pytest.fixture(scope="module")
def reach_server(ros_domain_id):
    """A Reach server in another process that logs each request it receives."""
    cmd = [str(repo_root() / "scripts/env.sh"), sys.executable, "-m",
           "icub_pmp.testing.reach_echo_server"]
    with NodeProcess(command=cmd) as proc:
        assert proc.wait_for_output("READY", 30), proc.output()
        yield proc


@pytest.mark.parametrize(
    "args, expected",
    [
        (["right=nan,0.1,0.0"], "NaN"),
        (["head=-0.3,0.1,0.0"], "unknown hand 'head'"),
        (["right=-0.3,0.1,0.0", "--tau", "-1"], "--tau"),
        (["right=-0.3,0.1"], "expected 3"),
        (["right=-0.3,0.1,0.0", "right=-0.3,0.1,0.0"], "given twice"),
    ],
)
def test_reach_bad_input_exits_with_one_line_and_sends_nothing(reach_server, args, expected):
    """Bad goals: non-zero exit, one-line error (no traceback), and the server got nothing."""
    before = reach_server.output().count("REQUEST")
    out = icub("reach", *args)
    assert out.returncode != 0
    err = out.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("icub: error:") and expected in err[0], out.stderr
    assert "Traceback" not in out.stderr
    # a good goal after it is the next request the server logs: the bad one sent nothing
    tau = 100.0 + before  # names this request in the server's log
    ok = icub("reach", "right=-0.3,0.1,0.0", "--no-wait", "--tau", str(tau))
    assert ok.returncode == 0, ok.stderr
    assert reach_server.wait_for_output(f"tau={tau}", 30), reach_server.output()
    assert reach_server.output().count("REQUEST") == before + 1


def test_reach_round_trip_between_processes(reach_server, ros_probe):
    """A Reach request/response crosses two processes with every field intact."""
    from icub_interfaces.srv import Reach

    assert ros_probe.wait_for_service("/pmp/reach", Reach, 20)
    req = Reach.Request()
    req.hands = ["left", "right"]
    req.left_target.pose.position.x = 0.3
    req.left_target.pose.position.y = 0.4
    req.right_target.header.frame_id = "root_link"
    req.right_target.pose.position.z = -1.0
    req.tau = 2.0
    res = ros_probe.call("/pmp/reach", Reach, req)
    assert res.success
    assert list(res.hands) == ["left", "right"]
    assert res.residuals[0] == pytest.approx(0.5)
    assert res.residuals[1] == pytest.approx(1.0)
    assert res.message == "frame=root_link"
    assert res.trajectory.points[0].time_from_start.sec == 2
    # the CLI prints the residuals the server computed
    out = icub("reach", "right=-0.3,0.4,0.0", "--simulate", "--tau", "1.5")
    assert out.returncode == 0, out.stderr
    assert "residual right: 500.00 mm" in out.stdout


def test_reach_missing_service_gives_clear_timeout(ros_domain_id):
    """Without a server the CLI says which service or action is missing and that no node
    offers it, exits non-zero, no traceback."""
    out = icub("reach", "right=-0.3,0.1,0.0", "--simulate", "--service", "/no_such/reach",
               "--timeout", "1")
    assert out.returncode != 0
    assert "service /no_such/reach not available after 1 s: no node offers it" in out.stderr
    assert "Traceback" not in out.stderr
    out = icub("reach", "right=-0.3,0.1,0.0", "--action", "/no_such/reach", "--timeout", "1")
    assert out.returncode != 0
    assert "action /no_such/reach not available after 1 s: no node offers it" in out.stderr
    assert "Traceback" not in out.stderr


def test_cli_usage_errors_are_one_line():
    """Unknown topics/options never print a traceback."""
    out = icub("echo", "/definitely_not_a_topic", "--count", "1", "--timeout", "0.5")
    assert out.returncode != 0 and "Traceback" not in out.stderr
    assert "has no publisher" in out.stderr
