"""Every bag the project writes opens in the readers roboticists use.

Bags are recorded from the running graph (simulator in lockstep without cameras, controller,
estimator, PMP planner, robot_state_publisher for /tf) while a /pmp/reach service call, a
/pmp/reach_action goal and a few camera images (published by the test) go through it; then
converted with ``icub bag convert`` and replayed with ``icub bag play`` into a new recording.
Each bag is read with rosbags' ``AnyReader`` (every message of every connection deserialised)
and with the official MCAP reader and ROS 2 decoder (``mcap_ros2.decoder.DecoderFactory``),
and the counts are compared with what the recorder says it wrote.
"""

from __future__ import annotations

import contextlib
import io
import json
import subprocess
import time
from pathlib import Path

import pytest

from icub_pmp.bags import BagReader, BagWriter, MessageDefinitions
from icub_pmp.testing import NodeGraph, NodeProcess, repo_root

pytestmark = [pytest.mark.integration, pytest.mark.slow]

SCRIPTS = repo_root() / "scripts"
GRAPH = ["sim_bridge", "wrench_estimator", "impedance_controller", "pmp_planner",
         "robot_state_publisher"]
PARAMS = {
    "sim_bridge": {"mode": "lockstep", "cameras_enabled": False},
    "wrench_estimator": {"use_sim_time": True},
    "impedance_controller": {"use_sim_time": True},
    "pmp_planner": {"use_sim_time": True},
    "robot_state_publisher": {"use_sim_time": True},
}
N_IMAGES = 5


def _record(bag: Path, *args: str, wait: bool = True) -> NodeProcess:
    """A recorder started as a user starts it; with ``wait``, once it says it records."""
    rec = NodeProcess(command=[str(SCRIPTS / "record.sh"), "-o", str(bag), "--json", *args])
    if wait:
        assert rec.wait_for_output("recording to", 60), rec.output()
    return rec


def _json_line(text: str, key: str) -> dict:
    for line in reversed(text.splitlines()):
        if line.startswith("{") and key in line:
            return json.loads(line)
    raise AssertionError(f"no JSON line with {key!r} in:\n{text[-3000:]}")


def _stop(rec: NodeProcess) -> dict[str, int]:
    """SIGINT the recorder; the per-topic counts it wrote."""
    assert rec.stop(60) == 0, rec.output()[-3000:]
    return _json_line(rec.output(), '"written"')["written"]


def _icub(*args: str) -> subprocess.CompletedProcess:
    """`icub ARGS` (bag info / convert: files only, no ROS graph) run in this process, as
    test_bag_readers.py runs them: the same code as the command without a new interpreter
    per call (seconds each on a loaded machine); `icub bag` as a command, through
    scripts/env.sh, is test_bag_core.py's and test_bag_record_replay.py's."""
    from icub_pmp.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(list(args))
    return subprocess.CompletedProcess(["icub", *args], rc, out.getvalue(), err.getvalue())


def _warned(bag: Path) -> set[str]:
    """Topics `icub bag info` warns about (one 'Warning: /topic [type]: ...' line each)."""
    out = _icub("bag", "info", str(bag))
    assert out.returncode == 0, out.stderr
    return {ln.split()[1] for ln in out.stdout.splitlines() if ln.startswith("Warning: ")}


def rosbags_read(bag: Path) -> tuple[dict[str, int], dict[str, list]]:
    """rosbags AnyReader: every message of every connection deserialised; counts per topic
    and the decoded messages."""
    from rosbags.highlevel import AnyReader

    counts: dict[str, int] = {}
    decoded: dict[str, list] = {}
    with AnyReader([bag]) as reader:
        for conn, _t, raw in reader.messages():
            decoded.setdefault(conn.topic, []).append(reader.deserialize(raw, conn.msgtype))
            counts[conn.topic] = counts.get(conn.topic, 0) + 1
    return counts, decoded


def mcap_read(bag: Path, topics: list[str] | None = None) -> dict[str, int]:
    """The official MCAP reader with the ROS 2 decoder: decoded messages per topic."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    counts: dict[str, int] = {}
    (path,) = bag.glob("*.mcap")
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _s, channel, _m, msg in reader.iter_decoded_messages(topics=topics):
            assert msg is not None
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    return counts


def mcap_fails_on(bag: Path, topic: str) -> bool:
    """True when the official decoder raises on the channel ``topic``."""
    try:
        mcap_read(bag, [topic])
    except Exception:
        return True
    return False


def _special(topic: str) -> bool:
    """Service events and action feedback: what the MCAP ROS 2 decoder cannot decode."""
    return topic.endswith("/_service_event") or topic.endswith("/_action/feedback")


def _check_both_readers(bag: Path, written: dict[str, int]) -> dict[str, list]:
    """rosbags decodes every message; the MCAP decoder every message except on exactly the
    channels `icub bag info` warns about (service events, action feedback), on which it
    raises. Counts equal ``written``. Returns the rosbags-decoded messages."""
    counts, decoded = rosbags_read(bag)
    assert counts == {t: n for t, n in written.items() if n}, (counts, written)
    warned = _warned(bag)
    assert warned == {t for t in written if _special(t)}, warned
    others = [t for t in written if t not in warned]
    assert mcap_read(bag, others) == {t: n for t, n in written.items()
                                      if n and t not in warned}
    for t in warned:
        if written[t]:
            assert mcap_fails_on(bag, t), t
    return decoded


@pytest.fixture(scope="module")
def recorded(ros_domain_id, ros_probe_module, tmp_path_factory):
    """Two recordings of the graph at once: `--all` (the default bag) and `--all
    --all-services --all-actions`, while a service call, an action goal and N_IMAGES images
    go through. The graph is stopped before the tests read the bags."""
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import Image

    from icub_interfaces.action import Reach as ReachAction
    from icub_interfaces.srv import Reach

    probe = ros_probe_module
    out = tmp_path_factory.mktemp("readers")
    with NodeGraph(GRAPH, PARAMS) as graph:
        assert probe.wait_for_service("/pmp/reach", Reach, 180), graph.outputs()
        client = probe.action_client("/pmp/reach_action", ReachAction, timeout=180)
        # both recorders start together: the default bag does not record the 1 kHz topics
        # through the second recorder's start-up (every message is decoded twice below)
        default = _record(out / "default", "--all", wait=False)
        full = _record(out / "full", "--all", "--all-services", "--all-actions", wait=False)
        for rec in (default, full):
            assert rec.wait_for_output("recording to", 60), rec.output()
            assert rec.wait_for_output("recording /tf ", 120), rec.output()
        for topic in ("/pmp/reach/_service_event", "/pmp/reach_action/_action/feedback",
                      "/pmp/reach_action/_action/status"):
            assert full.wait_for_output(f"recording {topic} ", 60), full.output()
        # camera images (the simulator's cameras are off in this graph)
        pub = probe.node.create_publisher(Image, "/cam/left/image_raw",
                                          QoSProfile(depth=10,
                                                     reliability=ReliabilityPolicy.RELIABLE))
        assert probe.wait_for(lambda: pub.get_subscription_count() >= 2, 60)
        for k in range(N_IMAGES):
            img = Image(height=240, width=320, encoding="rgb8", step=960)
            img.header.frame_id = "l_eye_optical"
            img.data = bytes([k]) * (240 * 960)
            pub.publish(img)
        # a quick service call (plan only) and an action goal executed by the controller
        req = Reach.Request(hands=["right"], tau=1.0, simulate_only=True)
        req.right_target.pose.position.x, req.right_target.pose.position.z = -0.30, 0.05
        req.right_target.pose.position.y = 0.15
        assert probe.call("/pmp/reach", Reach, req, timeout=120).success
        goal = ReachAction.Goal(hands=["right"], tau=1.0)
        goal.right_target.pose.position.x, goal.right_target.pose.position.z = -0.30, 0.05
        goal.right_target.pose.position.y = 0.15
        feedback: list = []
        result = probe.send_goal(client, goal, 400.0, feedback=feedback).result
        assert feedback, result.message
        # the goal's final status has reached the full recording (flushed every 0.5 s; read
        # at that pace: each read scans the growing bag, CPU the lockstep graph needs)
        assert probe.wait_for(lambda: _final_status_in(out / "full"), 60, period=0.5), \
            full.output()
        written = {"default": _stop(default), "full": _stop(full)}
        probe.destroy(pub)
        probe.destroy(client)
    return out, written, result


def test_default_bag_decodes_in_every_reader(recorded):
    """The default bag (`--all`) holds the graph's topics, /tf, images and the controller's
    custom status message, no service-event or action channel, and both rosbags and the
    official MCAP ROS 2 decoder decode every message: the counts are the recorder's."""
    out, written, _ = recorded
    bag, w = out / "default", written["default"]
    for topic in ("/joint_states", "/clock", "/tf", "/tf_static", "/robot_description",
                  "/impedance_controller/status", "/rosout"):
        assert w.get(topic, 0) > 0, (topic, w)
    assert w["/cam/left/image_raw"] == N_IMAGES
    assert not [t for t in w if "/_" in t], w  # nothing hidden
    assert _warned(bag) == set()
    counts, decoded = rosbags_read(bag)
    assert counts == {t: n for t, n in w.items() if n}
    assert mcap_read(bag) == counts
    images = decoded["/cam/left/image_raw"]
    assert [bytes(m.data[:1])[0] for m in images] == list(range(N_IMAGES))
    assert all(m.width == 320 and m.encoding == "rgb8" for m in images)
    assert {t.child_frame_id for m in decoded["/tf"] for t in m.transforms} >= {"r_hand"}


def test_services_and_actions_recorded_on_request(recorded):
    """`--all-services --all-actions` adds the service's events and the actions' status and
    feedback; rosbags decodes every message of them, the MCAP ROS 2 decoder every other
    message, and `icub bag info` warns about exactly the channels it cannot decode."""
    out, written, _ = recorded
    bag, w = out / "full", written["full"]
    assert w["/pmp/reach/_service_event"] == 2  # request received, response sent
    for action in ("/pmp/reach_action", "/impedance_controller/follow_joint_trajectory"):
        assert w[f"{action}/_action/status"] > 0 and w[f"{action}/_action/feedback"] > 0, w
    decoded = _check_both_readers(bag, w)
    events = decoded["/pmp/reach/_service_event"]
    assert [e.request[0].tau for e in events if len(e.request)] == [1.0]
    assert [e.response[0].success for e in events if len(e.response)] == [True]
    phases = {m.feedback.phase for m in decoded["/pmp/reach_action/_action/feedback"]}
    assert phases <= {"planning", "executing", "settling"} and "executing" in phases
    statuses = [s.status for m in decoded["/pmp/reach_action/_action/status"]
                for s in m.status_list]
    assert statuses[0] in (1, 2) and statuses[-1] in (4, 5, 6)  # accepted ... ended


def old_event_definition(defs: MessageDefinitions, service: str) -> str:
    """The service-event schema older versions of this project wrote: ros2msg, the request and
    response types named 'pkg/Srv_Request' (no srv part), which neither reader accepts."""
    pkg, _, srv = service.split("/")
    event = f"{pkg}/srv/{srv}_Event"
    defs._texts[event] = (f"service_msgs/ServiceEventInfo info\n{srv}_Request[<=1] request\n"
                          f"{srv}_Response[<=1] response\n")
    return defs._assemble(event)


def _old_format(src: Path, dst: Path) -> None:
    """A copy of ``src`` with the pre-issue-15 service-event schema (what a user of an
    older bag has)."""
    reader = BagReader(src)
    with BagWriter(dst) as w:
        handles = {}
        for t in reader.info().topics:
            msgdef = t.msgdef
            if t.name.endswith("/_service_event"):
                msgdef = old_event_definition(MessageDefinitions(), "icub_interfaces/srv/Reach")
            handles[t.name] = w.add_topic(t.name, t.msgtype, qos_profiles=t.qos_profiles,
                                          type_hash=t.type_hash, msgdef=msgdef)
        for m in reader.messages():
            w.write(handles[m.topic], m.log_time, m.data)


def test_convert_writes_bags_every_reader_decodes(recorded, tmp_path):
    """`icub bag convert` of an older bag (the pre-issue-15 service-event schema, which both
    readers reject) writes a bag both decode whole (service events left out by default),
    and with --all-services --all-actions one that rosbags decodes whole."""
    out, written, _ = recorded
    old = tmp_path / "old"
    _old_format(out / "full", old)
    assert "/pmp/reach/_service_event" in _warned(old)
    from rosbags.highlevel import AnyReader

    with pytest.raises(Exception, match="Reach_Event"):
        with AnyReader([old]):
            pass
    w = written["full"]
    res = _icub("bag", "convert", str(old), "-o", str(tmp_path / "conv"))
    assert res.returncode == 0, res.stderr
    assert "left out (not selected)" in res.stdout and "_service_event" in res.stdout
    kept = {t: n for t, n in w.items() if "/_" not in t}
    counts, _ = rosbags_read(tmp_path / "conv")
    assert counts == {t: n for t, n in kept.items() if n}
    assert mcap_read(tmp_path / "conv") == counts
    assert _warned(tmp_path / "conv") == set()
    res = _icub("bag", "convert", str(old), "-o", str(tmp_path / "conv_all"), "--all",
                "--all-services", "--all-actions")
    assert res.returncode == 0, res.stderr
    _check_both_readers(tmp_path / "conv_all", w)


def test_replayed_bag_recorded_again_decodes_in_every_reader(recorded, tmp_path):
    """`icub bag play` of the full bag, recorded again with the same options: the new bag
    holds every replayed channel (service events and action topics included) and both
    readers decode it as the original."""
    out, written, _ = recorded
    again = tmp_path / "again"
    rec = _record(again, "--all", "--all-services", "--all-actions",
                  "--exclude", "^/rosout$|^/parameter_events$")
    play = NodeProcess(command=[str(SCRIPTS / "replay.sh"), str(out / "full"), "--rate", "2",
                                "--wait-for-subscribers", "60", "--json"])
    assert play.proc.wait(600) == 0, play.output()[-3000:]
    published = _json_line(play.output(), "published")["published"]
    total = sum(n for t, n in published.items() if t not in ("/rosout", "/parameter_events"))
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and _count(again) < total:
        time.sleep(0.2)
    w = _stop(rec)
    assert {t for t, n in w.items() if n} == {
        t for t, n in published.items() if n and t not in ("/rosout", "/parameter_events")}
    _check_both_readers(again, w)


def _final_status_in(bag: Path) -> bool:
    """Whether the bag (being recorded) holds a reach goal status that ended the goal."""
    from action_msgs.msg import GoalStatusArray
    from rclpy.serialization import deserialize_message

    try:
        msgs = list(BagReader(bag).messages(["/pmp/reach_action/_action/status"]))
    except Exception:  # a chunk being written
        return False
    return any(s.status in (4, 5, 6) for m in msgs
               for s in deserialize_message(m.data, GoalStatusArray).status_list)


def _count(bag: Path) -> int:
    try:
        return BagReader(bag).info(check=True).message_count
    except Exception:
        return 0
