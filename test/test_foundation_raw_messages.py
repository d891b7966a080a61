"""Reading JointState and WrenchStamped from their serialised bytes (icub_pmp.nodes.
raw_messages) gives exactly what rclpy's deserialiser gives, for any frame_id and name
lengths and empty arrays; malformed bytes raise InvalidInput."""

from __future__ import annotations

import numpy as np
import pytest
from geometry_msgs.msg import WrenchStamped
from rclpy.serialization import serialize_message
from sensor_msgs.msg import JointState

from icub_pmp.errors import InvalidInput
from icub_pmp.ros.conversions import set_wrench
from icub_pmp.ros.raw_messages import RawJointStateReader, raw_wrench_stamped


@pytest.mark.parametrize("frame", ["", "a", "ab", "abc", "abcd", "l_arm_ft", "r_arm_ft_x"])
def test_wrench_stamped_read_raw_equals_the_message(frame):
    """Stamp and the six numbers match for frame_id lengths covering every alignment."""
    rng = np.random.default_rng(len(frame))
    m = WrenchStamped()
    m.header.stamp.sec, m.header.stamp.nanosec = 12, 345_678_901
    m.header.frame_id = frame
    w = rng.normal(size=6)
    set_wrench(m.wrench, w)
    ns, got = raw_wrench_stamped(serialize_message(m))
    assert ns == 12_345_678_901
    np.testing.assert_array_equal(got, w)


@pytest.mark.parametrize("frame", ["", "abc", "root_link"])
@pytest.mark.parametrize("sizes", [(3, 3, 3), (3, 0, 3), (3, 3, 0), (0, 0, 0), (5, 5, 5)])
def test_joint_state_read_raw_equals_the_message(frame, sizes):
    """Names, positions, velocities and efforts match, also with empty arrays; a second
    message with the same names reuses the decoded list, a changed name is decoded anew."""
    rng = np.random.default_rng(sum(sizes))
    names = ["torso_yaw", "l_elbow", "neck_pitchx", "r_wrist_prosup", "eyes_vergence"]
    n = sizes[0]
    reader = RawJointStateReader()
    for k in range(3):
        m = JointState()
        m.header.stamp.sec, m.header.stamp.nanosec = 3, k
        m.header.frame_id = frame
        m.name = names[:n] if k < 2 else ["x" * (j + 1) for j in range(n)]
        m.position = rng.normal(size=sizes[0]).tolist()
        m.velocity = rng.normal(size=sizes[1]).tolist()
        m.effort = rng.normal(size=sizes[2]).tolist()
        r = reader.read(serialize_message(m))
        assert r.stamp_ns == 3_000_000_000 + k
        assert r.name == list(m.name)
        np.testing.assert_array_equal(r.position, np.array(m.position))
        np.testing.assert_array_equal(r.velocity, np.array(m.velocity))
        np.testing.assert_array_equal(r.effort, np.array(m.effort))


def test_malformed_bytes_raise():
    """Truncated messages and big-endian data raise InvalidInput (the caller falls back to
    the deserialiser or drops the sample with a warning)."""
    m = JointState(name=["a", "b"], position=[1.0, 2.0])
    data = serialize_message(m)
    with pytest.raises(InvalidInput):  # cut inside the positions
        RawJointStateReader().read(data[:44])
    with pytest.raises(InvalidInput):
        RawJointStateReader().read(data[:10])
    w = serialize_message(WrenchStamped())
    with pytest.raises(InvalidInput):
        raw_wrench_stamped(w[:30])
    with pytest.raises(InvalidInput, match="big endian"):
        raw_wrench_stamped(bytes([0, 0, 0, 0]) + w[4:])


@pytest.mark.parametrize("frame", ["", "ab", "root_link"])
@pytest.mark.parametrize("present", [(True, True, True), (True, False, True), (False, False, True)])
def test_joint_state_writer_round_trips_through_rclpy(frame, present):
    """Bytes from RawJointStateWriter deserialise (rclpy) to the intended message, for any
    frame_id and name lengths and with empty fields; a wrong-length field raises."""
    from rclpy.serialization import deserialize_message

    from icub_pmp.ros.raw_messages import RawJointStateWriter

    names = ["torso_yaw", "l_elbow", "neck_pitchx", "a"]
    writer = RawJointStateWriter(names, frame)
    rng = np.random.default_rng(1)
    arrays = [rng.normal(size=4) if p else None for p in present]
    data = writer.write(7_000_000_123, *arrays)
    m = deserialize_message(data, JointState)
    assert (m.header.stamp.sec, m.header.stamp.nanosec) == (7, 123)
    assert m.header.frame_id == frame and list(m.name) == names
    for got, want in zip((m.position, m.velocity, m.effort), arrays):
        np.testing.assert_array_equal(np.array(got), want if want is not None else [])
    r = RawJointStateReader().read(data)
    assert r.name == names and r.stamp_ns == 7_000_000_123
    with pytest.raises(InvalidInput, match="3 values for 4"):
        writer.write(0, np.zeros(3))


@pytest.mark.parametrize("frame", ["", "a", "ab", "abc", "abcd", "l_arm_ft", "r_arm_ft_x"])
def test_wrench_stamped_writer_equals_rclpy_serialisation(frame):
    """Bytes from RawWrenchStampedWriter deserialise (rclpy) to the intended message for
    frame_id lengths covering every alignment, are as long as rclpy's own serialisation, and
    the raw reader reads them back; a wrench of the wrong shape raises."""
    from rclpy.serialization import deserialize_message

    from icub_pmp.ros.raw_messages import RawWrenchStampedWriter

    w = np.random.default_rng(len(frame)).normal(size=6)
    data = RawWrenchStampedWriter(frame).write(9_000_000_042, w)
    m = deserialize_message(data, WrenchStamped)
    assert (m.header.stamp.sec, m.header.stamp.nanosec) == (9, 42)
    assert m.header.frame_id == frame
    f, t = m.wrench.force, m.wrench.torque
    np.testing.assert_array_equal([f.x, f.y, f.z, t.x, t.y, t.z], w)
    ref = WrenchStamped()
    ref.header.frame_id = frame
    assert len(data) == len(serialize_message(ref))
    ns, got = raw_wrench_stamped(data)
    assert ns == 9_000_000_042
    np.testing.assert_array_equal(got, w)
    with pytest.raises(InvalidInput, match="shape"):
        RawWrenchStampedWriter(frame).write(0, np.zeros(5))
