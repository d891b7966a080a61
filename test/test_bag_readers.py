"""Schemas, type hashes and channel selection that every common bag reader accepts (no graph):
MessageDefinitions, ReaderCheck, RecordSelection, BagConverter and `icub bag info|convert`.
The same claims on bags recorded from the running graph: test_bag_graph_readers.py."""

from __future__ import annotations

from pathlib import Path

import pytest
from rclpy.serialization import serialize_message
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore
from sensor_msgs.msg import JointState

from icub_interfaces.action import Reach as ReachAction
from icub_interfaces.srv import Reach, Reach_Event
from icub_pmp.bags import (
    MCAP_ROS2,
    ROSBAGS,
    BagConverter,
    BagReader,
    BagTopic,
    BagWriter,
    MessageDefinitions,
    ReaderCheck,
    RecordSelection,
)
from icub_pmp.bags.message_definitions import schema_encoding
from icub_pmp.cli.main import main
from icub_pmp.errors import BagError, InvalidInput
from icub_pmp.ros.msg_types import get_interface, type_name

EVENT = "icub_interfaces/srv/Reach_Event"
FEEDBACK = "icub_interfaces/action/Reach_FeedbackMessage"
#: (topic, type) of every kind of channel the graph records
CHANNELS = [
    ("/joint_states", "sensor_msgs/msg/JointState"),
    ("/cam/left/image_raw", "sensor_msgs/msg/Image"),
    ("/tf", "tf2_msgs/msg/TFMessage"),
    ("/impedance_controller/status", "icub_interfaces/msg/ControllerStatus"),
    ("/motion/left/blobs", "icub_interfaces/msg/MotionBlobs"),
    ("/pmp/reach_action/_action/status", "action_msgs/msg/GoalStatusArray"),
    ("/pmp/reach_action/_action/feedback", FEEDBACK),
    ("/pmp/reach/_service_event", EVENT),
]


@pytest.fixture(scope="module")
def defs() -> MessageDefinitions:
    return MessageDefinitions()


def _topic(defs: MessageDefinitions, name: str, msgtype: str, **kw) -> BagTopic:
    text = kw.pop("msgdef", None) or defs.definition(msgtype)
    return BagTopic(name, msgtype, 1, text, schema_encoding(text),
                    type_hash=kw.pop("type_hash", defs.type_hash(msgtype)))


def old_event_definition(defs: MessageDefinitions, srv: str = "Reach") -> str:
    """The service-event schema of older versions of this project (ros2msg; request and
    response types named 'pkg/Srv_Request', without their srv part)."""
    event = f"icub_interfaces/srv/{srv}_Event"
    defs._texts[event] = (f"service_msgs/ServiceEventInfo info\n{srv}_Request[<=1] request\n"
                          f"{srv}_Response[<=1] response\n")
    return defs._assemble(event)


def _event(tau: float) -> Reach_Event:
    """A request event whose sequences all hold one element: rclpy's serialize_message sizes
    its buffer from Fast CDR's estimate, which counts alignment padding for empty sequences,
    and returns the whole buffer; the trailing slack (bytes DDS never sends) makes rosbags'
    strict size check fail. Recorded messages come off the wire with their exact length."""
    from icub_interfaces.msg import Obstacle

    ev = Reach_Event()
    ev.info.event_type = ev.info.REQUEST_RECEIVED
    start = JointState(name=["r_elbow"], position=[0.5], velocity=[0.0], effort=[0.0])
    ev.request.append(Reach.Request(
        hands=["right"], tau=tau, start_state=start,
        obstacles=[Obstacle(type="sphere", radius=0.05)], torque_limit_joints=["r_elbow"],
        torque_limits=[1.0], frozen_joints=["r_wrist_prosup"],
        admittance_scale_joints=["r_elbow"], admittance_scales=[1.0]))
    return ev


# ---------------------------------------------------------------------- definitions
def test_type_hashes_are_the_published_ones(defs):
    """type_hash reads rosidl's type descriptions: for standard types it equals the hash of
    the rosbags Jazzy store; service events and action parts have their own hashes."""
    store = get_typestore(Stores.ROS2_JAZZY)
    for t in ("sensor_msgs/msg/JointState", "sensor_msgs/msg/Image", "tf2_msgs/msg/TFMessage",
              "action_msgs/msg/GoalStatusArray", "rcl_interfaces/msg/Log"):
        assert defs.type_hash(t) == store.hash_rihs01(t), t
    hashes = {defs.type_hash(t) for t in (EVENT, FEEDBACK, "icub_interfaces/srv/Reach_Request",
                                          "icub_interfaces/action/Reach_Feedback")}
    assert len(hashes) == 4 and all(h.startswith("RIHS01_") for h in hashes)
    assert defs.type_hash("icub_interfaces/msg/NoSuchType") == ""


def test_rosbags_computes_the_published_hash_of_every_channel_type(defs):
    """rosbags, building its types from our definitions as AnyReader does, resolves every
    channel type under its own name and computes the hash rosidl published for it (which
    AnyReader checks), for all channels at once as for each alone."""
    topics = [_topic(defs, n, t) for n, t in CHANNELS]
    assert ReaderCheck(topics).rosbags() == []


def test_every_project_interface_is_read_as_expected(defs):
    """Every message, service event and action feedback type of icub_interfaces (today's and
    any added later): rosbags resolves each with the published hash; the MCAP ROS 2 decoder
    decodes every message type and rejects exactly the event and feedback types."""
    from icub_pmp.config import repo_root

    root = repo_root() / "icub_interfaces"
    types = [f"icub_interfaces/msg/{p.stem}" for p in sorted((root / "msg").glob("*.msg"))]
    types += [f"icub_interfaces/srv/{p.stem}_Event" for p in sorted((root / "srv").glob("*.srv"))]
    types += [f"icub_interfaces/action/{p.stem}_FeedbackMessage"
              for p in sorted((root / "action").glob("*.action"))]
    topics = [_topic(defs, f"/t{k}", t) for k, t in enumerate(types)]
    check = ReaderCheck(topics)
    assert check.rosbags() == []
    rejected = {u.msgtype for t in topics if (u := check.mcap_ros2(t)) is not None}
    assert rejected == {t for t in types if "/msg/" not in t}


def test_service_events_are_ros2idl_with_the_rosidl_event_layout(defs):
    """The service-event definition is rosbag2's IDL layout (one 'IDL: name' block per type,
    no preprocessor lines), and rosbags decodes a recorded event with it."""
    text = defs.definition(EVENT)
    assert schema_encoding(text) == "ros2idl"
    assert text.splitlines()[1] == f"IDL: {EVENT}"
    assert "IDL: icub_interfaces/srv/Reach\n" in text
    assert "IDL: service_msgs/msg/ServiceEventInfo\n" in text
    assert "#include" not in text
    assert "sequence<icub_interfaces::srv::Reach_Request, 1> request;" in text


def test_action_feedback_names_its_action_parts_in_full(defs):
    """The feedback message's own block is 'MSG: pkg/action/Name_Feedback' (rosbags resolves
    the field type next to its parent, in pkg/action/)."""
    text = defs.definition(FEEDBACK)
    assert text.startswith("unique_identifier_msgs/UUID goal_id\nReach_Feedback feedback\n")
    assert "MSG: icub_interfaces/action/Reach_Feedback\n" in text
    assert "string phase" in text


def test_feedback_schema_builds_the_official_decoder_apart_from_its_name(defs):
    """Only the type name keeps the MCAP ROS 2 decoder from the feedback channel: under a
    name its rosidl rules accept, the same text decodes a feedback message field by field."""
    from mcap_ros2._dynamic import generate_dynamic

    fb = ReachAction.Impl.FeedbackMessage()
    fb.goal_id.uuid = list(range(16))
    fb.feedback.phase = "executing"
    fb.feedback.hands = ["right"]
    fb.feedback.hand_errors = [0.012]
    decoders = generate_dynamic("icub_interfaces/action/ReachFeedbackMessage",
                                defs.definition(FEEDBACK))
    msg = decoders["icub_interfaces/action/ReachFeedbackMessage"](serialize_message(fb))
    assert list(msg.goal_id.uuid) == list(range(16))
    assert (msg.feedback.phase, msg.feedback.hands, list(msg.feedback.hand_errors)) == (
        "executing", ["right"], [0.012])


def test_unknown_type_is_a_bag_error(defs):
    """A type neither installed nor in the Jazzy store: BagError naming it."""
    with pytest.raises(BagError, match="icub_interfaces/srv/Nope_Event"):
        defs.definition("icub_interfaces/srv/Nope_Event")
    with pytest.raises(BagError, match="expected pkg/msg/Type"):
        defs.definition("JointState")


# ---------------------------------------------------------------------- reader check
def test_reader_check_names_what_the_mcap_decoder_rejects(defs):
    """Every channel type decodes in the official MCAP ROS 2 decoder except service events
    and action feedback, whose type names its rosidl rules reject."""
    topics = [_topic(defs, n, t) for n, t in CHANNELS]
    bad = ReaderCheck(topics).unreadable()
    assert {(u.topic, u.reader) for u in bad} == {
        ("/pmp/reach/_service_event", MCAP_ROS2), ("/pmp/reach_action/_action/feedback", MCAP_ROS2)}
    assert "FeedbackMessage" in [u for u in bad if "feedback" in u.topic][0].reason


def test_reader_check_flags_the_old_event_schema_for_both_readers(defs):
    """The pre-issue-15 event schema (ros2msg) is refused by both readers, as the issue saw:
    rosbags cannot resolve 'pkg/srv/...' names, the MCAP decoder rejects 'Reach_Event'."""
    t = _topic(defs, "/pmp/reach/_service_event", EVENT, msgdef=old_event_definition(defs))
    bad = ReaderCheck([t]).unreadable()
    assert [u.reader for u in bad] == [MCAP_ROS2, ROSBAGS]
    assert "Reach_Event" in bad[0].reason and "KeyError" in bad[1].reason


def test_reader_check_flags_a_hash_that_does_not_match(defs):
    """A stored type hash that is not the definition's ('unknown', another interface) makes
    AnyReader refuse the bag: the check says so."""
    t = _topic(defs, "/joint_states", "sensor_msgs/msg/JointState", type_hash="unknown")
    (u,) = ReaderCheck([t]).unreadable()
    assert u.reader == ROSBAGS and "differs" in u.reason


def test_anyreader_reads_service_events_written_with_the_new_schema(defs, tmp_path):
    """A bag with a service-event channel opens in rosbags' AnyReader, which decodes the
    request inside each event."""
    with BagWriter(tmp_path / "b") as w:
        h = w.add_topic("/pmp/reach/_service_event", EVENT)
        for k in range(3):
            w.write(h, 1_000 + k, serialize_message(_event(1.0 + k)))
    with AnyReader([tmp_path / "b"]) as r:
        taus = [r.deserialize(raw, c.msgtype).request[0].tau for c, _t, raw in r.messages()]
    assert taus == [1.0, 2.0, 3.0]


# ---------------------------------------------------------------------- selection
def test_default_selection_keeps_topics_only():
    """--all keeps every visible topic and no service event, action or hidden topic."""
    s = RecordSelection(all_topics=True)
    assert s.wants("/joint_states") and s.wants("/tf")
    assert not s.wants("/pmp/reach/_service_event")
    assert not s.wants("/pmp/reach_action/_action/feedback")
    assert not s.wants("/pmp/reach_action/_action/status")
    assert not s.wants("/_internal/thing")


def test_services_and_actions_are_selected_like_rosbag2():
    """Services by name or all (their _service_event topics), actions by name or all (status
    and feedback), hidden topics with --include-hidden-topics; exclude wins."""
    s = RecordSelection(services=("pmp/reach",), actions=("/pmp/reach_action",))
    assert s.wants("/pmp/reach/_service_event") and not s.wants("/sim/reset/_service_event")
    assert s.wants("/pmp/reach_action/_action/feedback")
    assert not s.wants("/cartesian/go_to_pose_action/_action/status")
    assert not s.wants("/joint_states")
    assert s.named_topics() == ["/pmp/reach/_service_event", "/pmp/reach_action/_action/feedback",
                                "/pmp/reach_action/_action/status"]
    s = RecordSelection(all_topics=True, all_services=True, all_actions=True, exclude="^/sim/")
    assert s.wants("/cartesian/go_to_pose_action/_action/status")
    assert s.wants("/pmp/reach/_service_event") and not s.wants("/sim/reset/_service_event")
    s = RecordSelection(all_topics=True, include_hidden_topics=True)
    assert s.wants("/_internal/thing") and s.wants("/x/_action/status")
    assert not s.wants("/pmp/reach/_service_event")
    assert RecordSelection(topics=("/pmp/reach/_service_event",)).wants(
        "/pmp/reach/_service_event")  # a topic named explicitly is recorded whatever it is


@pytest.mark.parametrize("kw, word", [
    ({}, "nothing to record"),
    ({"topics": "/joint_states"}, "topics"),
    ({"services": ("",)}, "services"),
    ({"all_topics": True, "exclude": "(["}, "exclude"),
])
def test_bad_selection_is_refused(kw, word):
    """An empty selection, a string for a list, an empty name or a bad regex: InvalidInput
    naming the argument."""
    with pytest.raises(InvalidInput, match=word):
        RecordSelection(**kw)


def test_action_message_types_resolve_for_subscriptions():
    """The recorder and player get the class of 'pkg/action/Name_FeedbackMessage' (and the
    goal/result/feedback parts), which rclpy nests inside the action class."""
    for t in (FEEDBACK, "icub_interfaces/action/Reach_Goal", "icub_interfaces/action/Reach_Result",
              "action_msgs/msg/GoalStatusArray", EVENT):
        assert type_name(get_interface(t)) == t
    with pytest.raises(InvalidInput, match="not installed"):
        get_interface("icub_interfaces/action/Reach_Nope")


# ---------------------------------------------------------------------- convert
def _old_bag(path: Path, defs: MessageDefinitions, with_changed: bool = False) -> None:
    """An older bag: joint states, and reach events with the pre-issue-15 schema."""
    with BagWriter(path) as w:
        js = w.add_topic("/joint_states", "sensor_msgs/msg/JointState")
        ev = w.add_topic("/pmp/reach/_service_event", EVENT, msgdef=old_event_definition(defs))
        if with_changed:  # an interface that changed since: recorded hash != installed hash
            ch = w.add_topic("/impedance_controller/status",
                             "icub_interfaces/msg/ControllerStatus",
                             msgdef="string state\n", type_hash="RIHS01_" + "0" * 64)
            w.write(ch, 500, b"\x00\x01\x00\x00\x03\x00\x00\x00ok\x00\x00")
        for k in range(5):
            m = JointState(name=["a"], position=[float(k)], velocity=[0.0], effort=[0.0])
            w.write(js, 1_000 + k, serialize_message(m))
        for k in range(2):
            w.write(ev, 2_000 + k, serialize_message(_event(float(k))))


def test_convert_drops_what_readers_reject_by_default(defs, tmp_path):
    """`convert` of an older bag keeps every topic and leaves the service events out: both
    readers decode the result whole; with --all-services the events come along in the new
    schema and rosbags decodes them."""
    _old_bag(tmp_path / "old", defs)
    res = BagConverter(tmp_path / "old", tmp_path / "new").run()
    assert res.dropped == ("/pmp/reach/_service_event",)
    assert dict(res.stats.counts) == {"/joint_states": 5}
    info = BagReader(tmp_path / "new").info()
    assert ReaderCheck(info.topics).unreadable() == ()
    res = BagConverter(tmp_path / "old", tmp_path / "all",
                       RecordSelection(all_topics=True, all_services=True)).run()
    assert res.stats.counts["/pmp/reach/_service_event"] == 2
    with AnyReader([tmp_path / "all"]) as r:
        events = [r.deserialize(raw, c.msgtype) for c, _t, raw in r.messages()
                  if c.topic.endswith("_service_event")]
    assert [e.request[0].tau for e in events] == [0.0, 1.0]


def test_convert_keeps_the_recorded_schema_of_a_changed_interface(defs, tmp_path):
    """A channel whose recorded type hash is not the installed type's keeps the schema it
    was recorded with (its bytes follow that one), and the conversion says why."""
    _old_bag(tmp_path / "old", defs, with_changed=True)
    res = BagConverter(tmp_path / "old", tmp_path / "new").run()
    assert "interface changed" in res.kept_recorded_schema["/impedance_controller/status"]
    t = BagReader(tmp_path / "new").info().topic("/impedance_controller/status")
    assert t.msgdef == "string state\n" and t.type_hash == "RIHS01_" + "0" * 64


def test_convert_refuses_to_overwrite_its_input(defs, tmp_path):
    """The output must be a new directory: BagError."""
    _old_bag(tmp_path / "old", defs)
    with pytest.raises(BagError, match="is the input"):
        BagConverter(tmp_path / "old", tmp_path / "old")


# ---------------------------------------------------------------------- CLI
def test_info_warns_one_line_per_unreadable_channel(defs, tmp_path, capsys):
    """`icub bag info` on an older bag: one Warning line for the service-event channel
    naming both readers, and how to get a readable copy; none for a converted bag. `convert
    --all-services` keeps every topic and the events."""
    _old_bag(tmp_path / "old", defs)
    assert main(["bag", "info", str(tmp_path / "old")]) == 0
    out = capsys.readouterr().out
    warnings = [ln for ln in out.splitlines() if ln.startswith("Warning:")]
    assert len(warnings) == 1 and "/pmp/reach/_service_event" in warnings[0]
    assert "mcap-ros2-support cannot decode it" in warnings[0]
    assert "rosbags cannot decode it" in warnings[0]
    assert f"icub bag convert {tmp_path / 'old'} -o NEW" in out
    assert main(["bag", "convert", str(tmp_path / "old"), "-o", str(tmp_path / "new")]) == 0
    assert "left out (not selected): /pmp/reach/_service_event" in capsys.readouterr().out
    assert main(["bag", "info", str(tmp_path / "new")]) == 0
    assert "Warning" not in capsys.readouterr().out
    assert main(["bag", "convert", str(tmp_path / "old"), "-o", str(tmp_path / "events"),
                 "--all-services"]) == 0  # every topic, and the events
    counts = {t.name: t.count for t in BagReader(tmp_path / "events").info().topics}
    assert counts == {"/joint_states": 5, "/pmp/reach/_service_event": 2}


def test_record_without_a_selection_is_a_one_line_error(capsys):
    """`icub bag record` with nothing selected fails before touching the graph."""
    assert main(["bag", "record", "-o", "/nonexistent/x"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("icub: error: nothing to record") and "--all" in err


def test_record_help_says_what_is_recorded_by_default(capsys):
    """`icub bag record --help` says --all records no service events, and why."""
    with pytest.raises(SystemExit):
        main(["bag", "record", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "--all records no service events" in out and "--all-services" in out
    assert "mcap-ros2-support" in out
