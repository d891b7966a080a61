"""The ros2cli verbs of ``icub``: call, pub, send-goal, param (ros2cli's YAML syntax), and the
discovery waits of every verb (defaults that hold under load, errors that say whether the
thing exists in the graph). Unit tests of the YAML -> message conversion first, then the verbs
against a real simulator and controller over DDS, run as a user runs them."""

from __future__ import annotations

import pytest
import yaml
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import CameraInfo, JointState
from trajectory_msgs.msg import JointTrajectory

from icub_interfaces.srv import ApplyWrench
from icub_pmp.cli.param import to_parameter_value
from icub_pmp.cli.yaml_values import parse_values, split_type_and_values
from icub_pmp.config import config_dir
from icub_pmp.errors import InvalidInput
from icub_pmp.ros.msg_types import set_message_fields
from icub_pmp.testing import NodeProcess, ros_environment, run_icub


# ---------------------------------------------------------------------- YAML -> message
def test_yaml_fills_nested_fields_and_sequences():
    """ros2cli's syntax: nested messages, sequences of messages, numbers written 1e6 (a string
    to YAML 1.1) and integers for floats; fields not named keep their defaults."""
    req = set_message_fields(ApplyWrench.Request(), parse_values(
        "{target: box, wrench: {force: {x: 1e6, z: 2}}, duration: 0.2}"))
    assert req.target == "box" and req.wrench.force.x == 1e6 and req.wrench.force.z == 2.0
    assert req.wrench.torque.x == 0.0 and req.duration == 0.2
    traj = set_message_fields(JointTrajectory(), parse_values(
        "{joint_names: [r_elbow], points: [{positions: [1.2], time_from_start: {sec: 2}}]}"))
    assert traj.points[0].time_from_start.sec == 2 and list(traj.points[0].positions) == [1.2]


@pytest.mark.parametrize("cls, values, match", [
    (ApplyWrench.Request, "{wrench: {force: {q: 1}}}",
     r"wrench.force.q: no such field in geometry_msgs/msg/Vector3; valid: x, y, z"),
    (ApplyWrench.Request, "{duration: fast}", r"duration: expected a number, got 'fast'"),
    (ApplyWrench.Request, "{target: 3}", r"target: expected a string, got 3"),
    (ApplyWrench.Request, "{wrench: 5}", r"wrench: expected a mapping of field names"),
    (CameraInfo, "{k: [1, 2]}", r"k: expected exactly 9 items, got 2"),
    (CameraInfo, "{height: -1}", r"height: -1 is out of the uint32 range"),
    (JointState, "{header: {stamp: {sec: 1.5}}}", r"header.stamp.sec: expected an integer"),
    (JointState, "{name: joint}", r"name: expected a list"),
])
def test_yaml_errors_name_the_field_the_value_and_what_was_expected(cls, values, match):
    with pytest.raises(InvalidInput, match=match):
        set_message_fields(cls(), parse_values(values))


def test_type_and_values_arguments_and_bad_yaml():
    """[TYPE] [VALUES]: a lone argument is a type when it looks like one; bad YAML and a
    non-mapping are one-line errors."""
    assert split_type_and_values([]) == (None, "{}")
    assert split_type_and_values(["std_srvs/srv/Trigger"]) == ("std_srvs/srv/Trigger", "{}")
    assert split_type_and_values(["{data: true}"]) == (None, "{data: true}")
    with pytest.raises(ValueError, match="not valid YAML"):
        parse_values("{data: [1}")
    with pytest.raises(ValueError, match="expected a YAML mapping"):
        parse_values("[1, 2]")


def test_parameter_values_follow_the_declared_type():
    """An integer for a double parameter becomes a double (ros2 param set would refuse the
    type change), mixed numbers for a double array become doubles, text stays text."""
    from rcl_interfaces.msg import ParameterType as T

    pv = to_parameter_value("2", T.PARAMETER_DOUBLE)
    assert pv.type == T.PARAMETER_DOUBLE and pv.double_value == 2.0
    pv = to_parameter_value("[-0.4, 0, 1]", T.PARAMETER_DOUBLE_ARRAY)
    assert pv.type == T.PARAMETER_DOUBLE_ARRAY and list(pv.double_array_value) == [-0.4, 0, 1]
    pv = to_parameter_value("1.0", T.PARAMETER_STRING)
    assert pv.type == T.PARAMETER_STRING and pv.string_value == "1.0"
    assert to_parameter_value("true").type == T.PARAMETER_BOOL  # guessed as ros2param does


def test_values_may_follow_options(ros_domain_id, capsys):
    """`icub send-goal ACTION -f VALUES` (values after an option, as ros2cli allows) is
    parsed: the command goes on to discovery instead of 'unrecognized arguments'."""
    from icub_pmp.cli.main import main

    rc = main(["send-goal", "/no_such/action", "-f", "{a: 1}", "--timeout", "0.5"])
    assert rc == 1
    assert "action /no_such/action not available after 0.5 s" in capsys.readouterr().err


# ---------------------------------------------------------------------- over DDS
@pytest.fixture(scope="module")
def graph(ros_domain_id):
    """The simulator (lockstep, no cameras) and the impedance controller."""
    env = ros_environment(ros_domain_id)
    sim = NodeProcess("sim_bridge", env=env, params_file=config_dir() / "sim_bridge.yaml",
                      parameters={"cameras_enabled": False, "mode": "lockstep"})
    ctl = NodeProcess("impedance_controller", env=env,
                      params_file=config_dir() / "impedance_controller.yaml")
    try:
        yield sim, ctl
    finally:
        ctl.stop()
        sim.stop()


def _one_line_error(out, expected: str) -> None:
    err = out.stderr.strip().splitlines()
    assert out.returncode == 1, (out.stdout, out.stderr)
    assert err and err[-1].startswith("icub: error:") and expected in err[-1], out.stderr
    assert "Traceback" not in out.stderr


def test_call_answers_in_yaml_and_the_issue_push_is_refused(graph):
    """`icub call` with the issue's request: the answer is printed as YAML (success false,
    the bound named); without a type the type comes from the graph."""
    out = run_icub("call", "/sim/apply_wrench",
                   "{target: box, wrench: {force: {x: 1e6}}, duration: 0.2}")
    assert out.returncode == 0, out.stderr
    resp = yaml.safe_load(out.stdout)["response"]
    assert resp["success"] is False and "max_wrench_force" in resp["message"]


def test_call_moves_an_object(graph, ros_probe):
    """`icub call /sim/set_object_pose TYPE VALUES` moves the box (ground truth follows)."""
    out = run_icub("call", "/sim/set_object_pose", "icub_interfaces/srv/SetObjectPose",
                   "{name: box, pose: {position: {x: -0.42, y: -0.12, z: -0.05}, "
                   "orientation: {w: 1.0}}}")
    assert out.returncode == 0, out.stderr
    assert yaml.safe_load(out.stdout)["response"]["success"] is True
    box = ros_probe.collect("/ground_truth/objects/box", PoseStamped, 3)[-1]
    assert (box.pose.position.x, box.pose.position.y) == pytest.approx((-0.42, -0.12), abs=0.01)


def test_call_errors_are_one_line_and_send_nothing(graph):
    """A misspelt field, a wrong type and a missing service: one line each, exit 1."""
    _one_line_error(run_icub("call", "/sim/reset", "{postur: rest}"),
                    "postur: no such field in icub_interfaces/srv/ResetSim_Request; "
                    "valid: posture")
    _one_line_error(run_icub("call", "/sim/reset", "std_srvs/srv/Trigger"),
                    "service /sim/reset has type icub_interfaces/srv/ResetSim, not "
                    "std_srvs/srv/Trigger")
    _one_line_error(run_icub("call", "/no_such/service", "--timeout", "2"),
                    "service /no_such/service not available after 2 s: no node offers it")


def test_send_goal_executes_a_trajectory_and_prints_the_result(graph, ros_probe):
    """`icub send-goal` to the controller's FollowJointTrajectory: feedback and the result are
    printed, exit 0 on SUCCEEDED, and the elbow is where the goal said."""
    out = run_icub("send-goal", "/impedance_controller/follow_joint_trajectory",
                   "{trajectory: {joint_names: [r_elbow], points: [{positions: [1.1], "
                   "time_from_start: {sec: 1}}]}}", "--feedback")
    assert out.returncode == 0, out.stdout + out.stderr
    assert "Goal finished with status: SUCCEEDED" in out.stdout
    assert "Feedback:" in out.stdout and "error_code: 0" in out.stdout
    js = ros_probe.collect("/joint_states", JointState, 1)[0]
    assert dict(zip(js.name, js.position))["r_elbow"] == pytest.approx(1.1, abs=0.03)
    out = run_icub("send-goal", "/impedance_controller/follow_joint_trajectory",
                   "{trajectory: {joint_names: [r_elbo], points: [{positions: [1.1], "
                   "time_from_start: {sec: 1}}]}}")
    assert out.returncode == 1 and "error_code: -2" in out.stdout, out.stdout  # INVALID_JOINTS
    assert "Goal finished with status: ABORTED" in out.stdout


def test_posture_brings_the_torso_back_and_leaves_the_other_joints(graph, ros_probe):
    """`icub posture rest --parts torso` after a trajectory leaned the torso and bent the
    elbow: the torso is upright again (the rest posture's 0), the elbow (not in --parts) stays
    where it was; the answer prints the duration chosen within the joints' rate limits and the
    largest error. Bad input is one line, and nothing moves."""
    out = run_icub("send-goal", "/impedance_controller/follow_joint_trajectory",
                   "{trajectory: {joint_names: [torso_roll, torso_yaw, r_elbow], points: "
                   "[{positions: [0.3, -0.2, 1.2], time_from_start: {sec: 2}}]}}")
    assert out.returncode == 0, out.stdout + out.stderr

    def joints() -> dict[str, float]:
        js = ros_probe.collect("/joint_states", JointState, 1)[0]
        return dict(zip(js.name, js.position))

    before = joints()
    assert before["torso_roll"] == pytest.approx(0.3, abs=0.05)
    out = run_icub("posture", "rest", "--parts", "torso")
    assert out.returncode == 0, out.stdout + out.stderr
    assert "posture rest: reached" in out.stdout and "3 joints (torso) in" in out.stderr
    after = joints()
    for j in ("torso_pitch", "torso_roll", "torso_yaw"):
        assert after[j] == pytest.approx(0.0, abs=0.03), (j, after[j])
    assert after["r_elbow"] == pytest.approx(before["r_elbow"], abs=0.03)
    _one_line_error(run_icub("posture", "rets"), "unknown posture 'rets'")
    _one_line_error(run_icub("posture", "rest", "--parts", "torso,tail"), "unknown part 'tail'")
    _one_line_error(run_icub("posture", "rest", "--duration", "nan"), "--duration")
    assert joints()["torso_roll"] == pytest.approx(after["torso_roll"], abs=0.01)
    out = run_icub("posture", "--list")
    assert out.returncode == 0 and "rest: " in out.stdout and "park: " in out.stdout


def test_pub_once_reaches_the_controller(graph):
    """`icub pub --once` waits for the controller's subscription, publishes one trajectory
    and the controller takes it."""
    sim, ctl = graph
    out = run_icub("pub", "/joint_trajectory", "trajectory_msgs/msg/JointTrajectory",
                   "{joint_names: [r_elbow], points: [{positions: [0.9], "
                   "time_from_start: {sec: 1}}]}", "--once")
    assert out.returncode == 0, out.stderr
    assert ctl.wait_for_output("trajectory: 1 joints, 1 points", 30.0), ctl.output()[-2000:]


def test_param_list_get_set(graph):
    """`icub param`: list shows the simulator's bounds, set converts 2 to 2.0 for a double,
    get reads it back, a read-only parameter is refused with the node's reason (exit 1)."""
    out = run_icub("param", "list", "/sim_bridge")
    assert out.returncode == 0 and "  max_wrench_force" in out.stdout, out.stderr
    out = run_icub("param", "set", "/sim_bridge", "command_timeout", "1")
    assert out.returncode == 0 and "Set parameter successful" in out.stdout, out.stdout
    out = run_icub("param", "get", "/sim_bridge", "command_timeout")
    assert out.stdout.strip() == "Double value is: 1.0", out.stdout
    out = run_icub("param", "set", "/sim_bridge", "box_mass", "3.0")
    assert out.returncode == 1 and "read-only" in out.stdout, out.stdout


def test_waits_say_whether_the_thing_exists_in_the_graph(graph):
    """A topic the controller subscribes to but nobody publishes: the error says it has no
    publisher and that a subscriber waits for it (not just 'not found')."""
    # 10 s: long enough to discover the controller's subscription on a loaded machine
    out = run_icub("echo", "/impedance_controller/velocity_command", "--count", "1",
                   "--timeout", "10")
    _one_line_error(out, "topic /impedance_controller/velocity_command has no publisher "
                         "after 10 s")
    assert "subscriber(s) wait for it" in out.stderr


def test_a_goal_right_after_a_node_restart_succeeds_with_the_defaults(graph, ros_domain_id):
    """The issue's `--timeout 2` right after a restart failed under load: with the defaults a
    goal sent while the controller is still starting waits for it and succeeds."""
    sim, ctl = graph
    ctl.stop()
    new = NodeProcess("impedance_controller", env=ros_environment(ros_domain_id),
                      params_file=config_dir() / "impedance_controller.yaml")
    try:
        out = run_icub("send-goal", "/impedance_controller/follow_joint_trajectory",
                       "{trajectory: {joint_names: [r_elbow], points: [{positions: [1.0], "
                       "time_from_start: {sec: 1}}]}}")
        assert out.returncode == 0, out.stdout + out.stderr
    finally:
        new.stop()


@pytest.mark.parametrize("verb, example", [
    ("call", "icub call /sim/reset"), ("pub", "icub pub /effort_command"),
    ("send-goal", "icub send-goal /pmp/reach_action"), ("param", "icub param set"),
    ("posture", "icub posture rest --parts torso"),
])
def test_help_shows_examples(verb, example, capsys):
    """`icub VERB --help` shows an example (argparse's help, run in this process: the text
    needs no graph; the verbs above run as commands)."""
    from icub_pmp.cli.main import main

    with pytest.raises(SystemExit) as done:
        main([verb, "--help"])
    out = capsys.readouterr().out
    assert done.value.code == 0 and example in out, out
