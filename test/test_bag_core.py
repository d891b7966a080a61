"""Bag files without a ROS graph: rosbag2 layout, official readers, crash recovery, damage,
repair of an interrupted recording, a write the file system refuses."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from geometry_msgs.msg import WrenchStamped
from mcap.reader import make_reader
from rclpy.serialization import deserialize_message, serialize_message
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability
from rosbags.interfaces import QosTime as T
from sensor_msgs.msg import Image, JointState
from std_msgs.msg import String

from icub_pmp.bags import BagReader, BagRepair, BagStatus, BagWriter, MessageDefinitions
from icub_pmp.errors import BagError
from icub_pmp.testing import repo_root

BEST_EFFORT = Qos(QosHistory.KEEP_LAST, 5, QosReliability.BEST_EFFORT, QosDurability.VOLATILE,
                  T(0, 0), T(0, 0), QosLiveliness.AUTOMATIC, T(0, 0), False)
LATCHED = Qos(QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL,
              T(0, 0), T(0, 0), QosLiveliness.AUTOMATIC, T(0, 0), False)
TYPES = {"/joint_states": JointState, "/ft/r_arm_ft": WrenchStamped, "/cam/left/image_raw": Image,
         "/robot_description": String}


def _messages(n: int):
    """(topic, log_time_ns, msg) of a small synthetic run: 1 kHz joints+FT, images, a URDF."""
    out = [("/robot_description", 1_000_000_000, String(data="<robot name='x'/>"))]
    for k in range(n):
        t = 1_000_000_000 + (k + 1) * 1_000_000
        js = JointState(name=["a", "b"], position=[k * 1e-3, -1.0])
        js.header.stamp.sec, js.header.stamp.nanosec = divmod(k * 1_000_000, 1_000_000_000)
        out.append(("/joint_states", t, js))
        w = WrenchStamped()
        w.header.frame_id = "r_arm_ft"
        w.wrench.force.x = float(k)
        out.append(("/ft/r_arm_ft", t + 1000, w))
        if k % 33 == 0:
            im = Image(height=4, width=4, encoding="rgb8", step=12)
            im.data = bytes([k % 256]) * 48
            out.append(("/cam/left/image_raw", t + 2000, im))
    return out


def _write(path: Path, msgs, close: bool = True) -> BagWriter:
    w = BagWriter(path)
    handles = {}
    for topic, cls in TYPES.items():
        qos = [LATCHED] if topic == "/robot_description" else [BEST_EFFORT]
        handles[topic] = w.add_topic(topic, f"{cls.__module__.split('.')[0]}/msg/{cls.__name__}",
                                     qos_profiles=qos)
    for topic, t, m in msgs:
        w.write(handles[topic], t, serialize_message(m))
    if close:
        w.close()
    return w


@pytest.fixture(scope="module")
def sample(tmp_path_factory):
    """A finalised bag of 3000 joint states, 3000 wrenches, 91 images and one URDF."""
    path = tmp_path_factory.mktemp("bags") / "sample"
    msgs = _messages(3000)
    _write(path, msgs)
    return path, msgs


def _decoded(topic, data):
    return deserialize_message(data, TYPES[topic])


def test_roundtrip_same_messages_same_order(sample):
    """Every message comes back, decoded equal, in the written order, with its log time."""
    path, msgs = sample
    got = list(BagReader(path).messages())
    assert [(m.topic, m.log_time) for m in got] == [(t, ts) for t, ts, _ in msgs]
    for m, (_, _, orig) in zip(got, msgs):
        assert _decoded(m.topic, m.data) == orig


def test_rosbag2_layout_and_qos_in_metadata(sample):
    """metadata.yaml is rosbag2 version 9 with mcap storage, counts and offered QoS profiles."""
    path, _ = sample
    meta = yaml.safe_load((path / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["version"] == 9 and meta["storage_identifier"] == "mcap"
    assert meta["relative_file_paths"] == ["sample.mcap"]
    topics = {t["topic_metadata"]["name"]: t for t in meta["topics_with_message_count"]}
    assert topics["/joint_states"]["message_count"] == 3000
    latched = topics["/robot_description"]["topic_metadata"]["offered_qos_profiles"]
    assert latched[0]["durability"] == "transient_local" and latched[0]["reliability"] == "reliable"
    assert topics["/joint_states"]["topic_metadata"]["type_description_hash"].startswith("RIHS01_")
    info = BagReader(path).info()
    assert info.status == BagStatus.CLOSED and info.message_count == 1 + 3000 + 3000 + 91
    latched = info.topic("/robot_description").qos_profiles[0]
    assert latched.durability == QosDurability.TRANSIENT_LOCAL


def test_official_mcap_readers_decode_every_message(sample):
    """The official mcap + mcap-ros2-support readers decode the bag from its index."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    path, msgs = sample
    with open(path / "sample.mcap", "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        assert summary.statistics.message_count == len(msgs)
        decoded = [(ch.topic, d)
                   for _, ch, _, d in reader.iter_decoded_messages(log_time_order=False)]
    assert len(decoded) == len(msgs)
    js = [d for t, d in decoded if t == "/joint_states"]
    assert [d.position[0] for d in js] == [k * 1e-3 for k in range(3000)]
    images = [d for t, d in decoded if t == "/cam/left/image_raw"]
    assert bytes(images[1].data) == bytes([33]) * 48


def test_rosbags_rosbag2_reader_opens_it(sample):
    """rosbags' rosbag2 Reader (metadata.yaml + mcap, as ros2 bag does) reads all counts."""
    from rosbags.rosbag2 import Reader

    path, msgs = sample
    with Reader(path) as r:
        assert r.message_count == len(msgs)
        assert {c.topic for c in r.connections} == set(TYPES)


def test_unclosed_bag_readable_up_to_last_flush(tmp_path):
    """A recording that never closed (as after SIGKILL) keeps every flushed message: no
    metadata.yaml, no footer, status 'unclosed', and the messages of flushed chunks decode."""
    path = tmp_path / "rec"
    msgs = _messages(2000)
    w = _write(path, msgs[:3000], close=False)
    w.flush()
    for topic, t, m in msgs[3000:]:  # written after the last flush: may be lost
        w.write(w.topics[topic], t, serialize_message(m))
    crashed = tmp_path / "crashed"
    shutil.copytree(path, crashed)  # the files as a SIGKILL would leave them
    w.close()
    assert not (crashed / "metadata.yaml").exists()
    reader = BagReader(crashed)
    info = reader.info()
    assert info.status == BagStatus.UNCLOSED and not info.closed_cleanly
    assert "not closed cleanly" in info.notes[0]
    got = list(reader.messages())
    assert len(got) >= 3000
    for m, (topic, ts, orig) in zip(got, msgs):
        assert (m.topic, m.log_time) == (topic, ts) and _decoded(m.topic, m.data) == orig


@pytest.mark.parametrize("keep", [0.999, 0.6, 0.05, 30, 9, 3])
def test_truncated_bag_clear_error_never_traceback(sample, tmp_path, keep):
    """A finalised bag cut anywhere is reported as truncated (or not MCAP): a BagError or a
    'truncated' status, never another exception; the readable prefix decodes."""
    src, msgs = sample
    dst = tmp_path / "cut"
    shutil.copytree(src, dst)
    f = dst / "sample.mcap"
    size = f.stat().st_size
    with open(f, "r+b") as fh:
        fh.truncate(int(size * keep) if keep < 1 else int(keep))
    try:
        reader = BagReader(dst)
        info = reader.info()
    except BagError as exc:
        assert "truncated" in str(exc) or "not an MCAP file" in str(exc)
        return
    assert info.status == BagStatus.TRUNCATED and "truncated" in info.notes[0]
    got = list(reader.messages())
    assert len(got) == info.message_count <= len(msgs)
    for m, (topic, _, orig) in zip(got, msgs):
        assert _decoded(topic, m.data) == orig


def test_corrupt_chunk_gives_bag_error(sample, tmp_path):
    """Garbage written over record headers of a chunk raises BagError naming file and byte."""
    src, _ = sample
    dst = tmp_path / "corrupt"
    shutil.copytree(src, dst)
    f = dst / "sample.mcap"
    data = bytearray(f.read_bytes())
    start = data.index(b"\x06", 8 + 9)  # inside the first chunk: break its length fields
    data[start + 9:start + 9 + 40] = b"\xff" * 40
    f.write_bytes(bytes(data))
    with pytest.raises(BagError, match=r"corrupt .*byte \d+|truncated"):
        reader = BagReader(dst)
        reader.info(check=True)
        list(reader.messages())


@pytest.mark.parametrize("case", ["missing", "empty_dir", "not_mcap", "bad_yaml", "no_file"])
def test_not_a_bag_gives_bag_error(tmp_path, sample, case):
    """Missing paths, empty directories, non-MCAP files and broken metadata.yaml: BagError."""
    p = tmp_path / "b"
    if case != "missing":
        p.mkdir()
    if case == "not_mcap":
        (p / "b.mcap").write_bytes(b"this is not mcap at all")
    if case in ("bad_yaml", "no_file"):
        shutil.copy(sample[0] / "sample.mcap", p / "sample.mcap")
        text = "rosbag2_bagfile_information: [unclosed" if case == "bad_yaml" else (
            "rosbag2_bagfile_information:\n  relative_file_paths: [gone.mcap]\n")
        (p / "metadata.yaml").write_text(text)
    with pytest.raises(BagError):
        BagReader(p).info()


def test_cli_info_one_line_error_no_traceback(tmp_path):
    """`icub bag info` on a damaged bag prints one 'icub: error:' line and exits 1."""
    p = tmp_path / "junk"
    p.mkdir()
    (p / "junk.mcap").write_bytes(b"\x89MCAP0\r\n" + b"\x06" + b"\xff" * 200)
    (p / "metadata.yaml").write_text("rosbag2_bagfile_information:\n  relative_file_paths: "
                                     "[junk.mcap]\n  storage_identifier: mcap\n")
    r = subprocess.run([sys.executable, "-m", "icub_pmp.cli.main", "bag", "info", str(p)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1
    assert "Traceback" not in r.stderr + r.stdout
    lines = [x for x in (r.stderr + r.stdout).splitlines() if "error" in x.lower()
             or "truncated" in x.lower()]
    assert lines, r.stdout + r.stderr


def test_writer_refuses_existing_directory(sample):
    """BagWriter never overwrites: an existing path is a BagError."""
    with pytest.raises(BagError, match="exists"):
        BagWriter(sample[0])


def test_message_definitions_parse_with_official_decoder():
    """The ros2msg definitions assembled from the installed .msg files build decoders in
    mcap-ros2-support for every type the graph records."""
    from mcap_ros2._dynamic import generate_dynamic

    md = MessageDefinitions()
    for t in ["sensor_msgs/msg/JointState", "sensor_msgs/msg/Image", "sensor_msgs/msg/Imu",
              "geometry_msgs/msg/WrenchStamped", "trajectory_msgs/msg/JointTrajectory",
              "rosgraph_msgs/msg/Clock", "tf2_msgs/msg/TFMessage", "std_msgs/msg/String",
              "nav_msgs/msg/Path", "sensor_msgs/msg/CameraInfo"]:
        assert t in generate_dynamic(t, md.definition(t))


def test_tf2_msgs_type_hash_equals_the_official_one():
    """The TFMessage built from interfaces/tf2_msgs has the official Jazzy type hash, so
    /tf recorded here is the standard type for ros2 bag, Foxglove and stock Jazzy nodes."""
    import os

    from rosbags.typesys import Stores, get_typestore

    official = get_typestore(Stores.ROS2_JAZZY).hash_rihs01("tf2_msgs/msg/TFMessage")
    found = []
    for prefix in os.environ["AMENT_PREFIX_PATH"].split(os.pathsep):
        j = Path(prefix) / "share/tf2_msgs/msg/TFMessage.json"
        if j.is_file():
            found.append(j.read_text())
    assert found, "tf2_msgs is not installed (make env builds interfaces/tf2_msgs)"
    assert official in found[0]


def test_bag_core_imports_no_ros():
    """icub_pmp.bags (and the link-transform core) load without rclpy or message modules."""
    code = ("import sys, icub_pmp.bags, icub_pmp.bags.bag_reader, icub_pmp.bags.bag_writer, "
            "icub_pmp.bags.message_definitions, icub_pmp.bags.reader_check, "
            "icub_pmp.bags.record_selection, icub_pmp.bags.bag_converter, "
            "icub_pmp.kinematics.link_transforms, "
            "icub_pmp.ros.robot_state_publisher_config\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'rclpy' "
            "or m.split('.')[0].endswith(('_msgs', '_srvs', '_interfaces'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


# -------------------------------------------------------------------- repair
def _unclosed(tmp_path, n_flushed: int = 3000, n_after: int = 500):
    """A bag as SIGKILL leaves it: ``n_flushed`` messages flushed, more in memory, no end."""
    msgs = _messages(2000)
    w = _write(tmp_path / "rec", msgs[:n_flushed], close=False)
    w.flush()
    for topic, t, m in msgs[n_flushed:n_flushed + n_after]:
        w.write(w.topics[topic], t, serialize_message(m))
    crashed = tmp_path / "crashed"
    shutil.copytree(tmp_path / "rec", crashed)
    w.close()
    return crashed, msgs


def _rosbag2_count(path) -> int:
    from rosbags.rosbag2 import Reader

    with Reader(path) as r:
        return sum(1 for _ in r.messages())


def test_repair_in_place_finalises_an_unclosed_bag(tmp_path):
    """Every flushed message survives, in order and decodable; rosbags' rosbag2 Reader (which
    refuses the unclosed bag) and the official MCAP reader's summary open the repaired one; the
    original is kept beside it."""
    crashed, msgs = _unclosed(tmp_path)
    before = list(BagReader(crashed).messages())
    assert len(before) >= 3000
    with pytest.raises(FileNotFoundError, match="metadata"):  # rosbag2 readers refuse it
        _rosbag2_count(crashed)
    result = BagRepair(crashed).run()
    assert result.repaired and result.status_before == BagStatus.UNCLOSED
    assert result.path == crashed and result.damaged_kept_at == tmp_path / "crashed.damaged"
    assert (result.damaged_kept_at).is_dir()
    reader = BagReader(crashed)
    assert reader.status == BagStatus.CLOSED
    after = list(reader.messages())
    assert [(m.topic, m.log_time, m.data) for m in after] == \
        [(m.topic, m.log_time, m.data) for m in before]
    assert _rosbag2_count(crashed) == len(after)
    with open(next(crashed.glob("*.mcap")), "rb") as fh:
        stats = make_reader(fh).get_summary().statistics
    assert stats.message_count == len(after)
    for m, (topic, ts, orig) in zip(after, msgs):
        assert (m.topic, m.log_time) == (topic, ts)
        assert deserialize_message(m.data, TYPES[topic]) == orig


def test_repair_of_a_cut_file_names_the_cut_and_keeps_the_readable_prefix(tmp_path):
    crashed, _ = _unclosed(tmp_path)
    f = next(crashed.glob("*.mcap"))
    with open(f, "r+b") as fh:  # cut inside the last chunk
        fh.truncate(f.stat().st_size - 777)
    readable = sum(1 for _ in BagReader(crashed).messages())
    out = tmp_path / "fixed"
    result = BagRepair(crashed, out).run()
    assert result.cut and "at byte" in result.cut[0]
    assert result.damaged_kept_at is None and crashed.exists()  # -o leaves the input alone
    assert _rosbag2_count(out) == readable == result.stats.total


def test_repair_leaves_a_clean_bag_alone_and_refuses_bad_paths(tmp_path):
    crashed, _ = _unclosed(tmp_path)
    BagRepair(crashed).run()
    again = BagRepair(crashed).run()
    assert not again.repaired and again.status_before == BagStatus.CLOSED
    with pytest.raises(BagError, match="does not exist"):
        BagRepair(tmp_path / "nope")
    with pytest.raises(BagError, match="exists already"):
        BagRepair(crashed, tmp_path / "crashed.damaged")
    junk = tmp_path / "junk"
    junk.mkdir()
    (junk / "x.mcap").write_bytes(b"not an mcap file at all")
    with pytest.raises(BagError):
        BagRepair(junk).run()
    assert (junk / "x.mcap").exists()  # nothing moved when the repair cannot start


def test_cli_repair_then_info_says_closed(tmp_path):
    crashed, _ = _unclosed(tmp_path)
    env_sh = str(repo_root() / "scripts" / "env.sh")
    run = subprocess.run([env_sh, "icub", "bag", "repair", str(crashed)], capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert "repaired (unclosed)" in run.stdout and "crashed.damaged" in run.stdout
    info = subprocess.run([env_sh, "icub", "bag", "info", str(crashed)], capture_output=True,
                          text=True, timeout=120)
    assert info.returncode == 0 and "closed cleanly" in info.stdout
    bad = subprocess.run([env_sh, "icub", "bag", "repair", str(tmp_path / "missing")],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode != 0 and "icub: error:" in bad.stderr
    assert "Traceback" not in bad.stderr


WRITE_UNDER_LIMIT = r"""
import resource, sys
from icub_pmp.bags import BagWriter
from icub_pmp.errors import BagError
resource.setrlimit(resource.RLIMIT_FSIZE, (3_000_000, 3_000_000))  # Python ignores SIGXFSZ
w = BagWriter(sys.argv[1])
h = w.add_topic("/blob", "std_msgs/msg/String")
cdr = bytes([0, 1, 0, 0, 101, 0, 0, 0]) + b"x" * 100 + bytes(1)  # a String of 100 'x'
try:
    for k in range(60000):
        w.write(h, 1_000_000_000 + k * 1_000_000, cdr)
except BagError as exc:
    print("BagError:", exc)
    sys.exit(3)
sys.exit(0)
"""


def test_a_refused_write_is_a_clear_error_and_the_bag_repairs(tmp_path):
    """A file size limit (what a full disk does to a write) stops the writer with a BagError
    naming the file and the cause; the chunks written before it are repaired into a bag."""
    bag = tmp_path / "full"
    run = subprocess.run([sys.executable, "-c", WRITE_UNDER_LIMIT, str(bag)],
                         capture_output=True, text=True, timeout=120, cwd=repo_root())
    assert run.returncode == 3, run.stdout + run.stderr
    assert "cannot write to" in run.stdout and "File too large" in run.stdout
    assert "readable up to its last complete chunk" in run.stdout
    assert "Traceback" not in run.stderr
    result = BagRepair(bag).run()
    assert result.repaired and result.stats.total > 1000
    assert all(m.data == bytes([0, 1, 0, 0, 101, 0, 0, 0]) + b"x" * 100 + bytes(1)
               for m in BagReader(bag).messages())
    assert _rosbag2_count(bag) == result.stats.total
