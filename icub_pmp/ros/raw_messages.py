"""Reading the 1 kHz messages straight from their serialised (CDR) bytes.

In the lockstep loop every node takes several messages per millisecond; rclpy's deserialiser
builds a Python object per field (a WrenchStamped is six objects, a JointState carries 23
fresh strings), which costs more than the estimator's dynamics. A subscriber created with
``raw=True`` gets the bytes; these readers take the numbers out with ``numpy.frombuffer``.

Layout (XCDR1 / plain CDR, what Fast DDS and rmw use for ROS 2 messages): a 4-byte
encapsulation header (byte 1 odd = little endian), then the fields in order, each aligned to
its own size relative to the end of the encapsulation header; a string is a uint32 length
(including the NUL) and its bytes; a sequence is a uint32 count and its elements (float64
aligned to 8). Only little-endian data is read here; anything unexpected raises
:class:`~icub_pmp.errors.InvalidInput` and the caller falls back to ``deserialize_message``.
:class:`RawJointStateWriter` and :class:`RawWrenchStampedWriter` are the other direction
(``Publisher.publish`` takes bytes): the names and frame ids are encoded once, not converted
from Python objects on every publication.
"""

from __future__ import annotations

import struct
from typing import NamedTuple

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = [
    "RawJointState",
    "RawJointStateReader",
    "RawJointStateWriter",
    "RawWrenchStampedWriter",
    "raw_header_stamp_ns",
    "raw_wrench_stamped",
    "read_joint_state",
]

_ENCAPSULATION = 4
_U32 = struct.Struct("<I")
_STAMP = struct.Struct("<iI")


def raw_header_stamp_ns(data: bytes) -> int:
    """``header.stamp`` [ns] of a serialised (CDR) message whose first field is a
    std_msgs/Header (JointState, WrenchStamped, ...), read without deserialising it: a
    subscriber with ``raw=True`` can drop the samples it does not need for free."""
    if len(data) < 12:
        raise InvalidInput(f"serialised message too short ({len(data)} bytes) for a header")
    fmt = "<iI" if data[1] & 1 else ">iI"  # CDR encapsulation: odd id = little endian
    sec, nanosec = struct.unpack_from(fmt, data, 4)
    return sec * 1_000_000_000 + nanosec


def _check_little_endian(data: bytes, minimum: int) -> None:
    if len(data) < minimum:
        raise InvalidInput(f"serialised message too short ({len(data)} bytes)")
    if not data[1] & 1:
        raise InvalidInput("serialised message is big endian (not read raw)")


def _after_header(data: bytes) -> tuple[int, int]:
    """(stamp [ns], offset just after the header's frame_id) of a message starting with a
    std_msgs/Header."""
    _check_little_endian(data, _ENCAPSULATION + 12)
    sec, nanosec = _STAMP.unpack_from(data, _ENCAPSULATION)
    (n,) = _U32.unpack_from(data, _ENCAPSULATION + 8)
    end = _ENCAPSULATION + 12 + n
    if end > len(data):
        raise InvalidInput("serialised header: frame_id runs past the end of the message")
    return sec * 1_000_000_000 + nanosec, end


def _align(offset: int, size: int) -> int:
    rel = offset - _ENCAPSULATION
    return offset + (-rel) % size


def raw_wrench_stamped(data: bytes) -> tuple[int, np.ndarray]:
    """(stamp [ns], wrench (6,) [fx, fy, fz, tx, ty, tz]) of a serialised
    geometry_msgs/WrenchStamped."""
    ns, off = _after_header(data)
    off = _align(off, 8)
    if off + 48 > len(data):
        raise InvalidInput("serialised WrenchStamped too short for its wrench")
    return ns, np.frombuffer(data, "<f8", 6, off).astype(float)


class RawJointState(NamedTuple):
    """A sensor_msgs/JointState read raw, with the message's field names (so
    :func:`~icub_pmp.ros.conversions.joint_state_arrays` takes it): ``stamp_ns``, ``name``
    (a list shared between the samples that carry the same names: do not modify it) and
    ``position``, ``velocity``, ``effort`` (n,) arrays (possibly empty)."""

    stamp_ns: int
    name: list[str]
    position: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray


class RawJointStateReader:
    """Reads serialised JointStates; the name list is decoded once and reused while the bytes
    of the name sequence do not change (a robot publishes the same names every sample)."""

    def __init__(self) -> None:
        self._name_bytes: bytes | None = None
        self._names: list[str] = []

    def read(self, data: bytes) -> RawJointState:
        """Read one serialised JointState (raises InvalidInput on a malformed one)."""
        ns, off = _after_header(data)
        start = off = _align(off, 4)
        cached = self._name_bytes
        if cached is not None and data[start:start + len(cached)] == cached:
            off = start + len(cached)
            names = self._names
        else:
            (count,) = _U32.unpack_from(data, off)
            off += 4
            names = []
            for _ in range(count):
                off = _align(off, 4)
                if off + 4 > len(data):
                    raise InvalidInput("serialised JointState: name sequence truncated")
                (n,) = _U32.unpack_from(data, off)
                if n == 0 or off + 4 + n > len(data):
                    raise InvalidInput("serialised JointState: malformed name")
                names.append(data[off + 4:off + 3 + n].decode())
                off += 4 + n
            self._name_bytes = bytes(data[start:off])
            self._names = names
        arrays = []
        for field in ("position", "velocity", "effort"):
            off = _align(off, 4)
            if off + 4 > len(data):
                raise InvalidInput(f"serialised JointState: {field} truncated")
            (count,) = _U32.unpack_from(data, off)
            off += 4
            if count:
                off = _align(off, 8)
            if off + 8 * count > len(data):
                raise InvalidInput(f"serialised JointState: {field} truncated")
            arrays.append(np.frombuffer(data, "<f8", count, off).astype(float))
            off += 8 * count
        return RawJointState(ns, names, *arrays)


def read_joint_state(reader: RawJointStateReader, data: bytes) -> RawJointState:
    """A serialised JointState read from its bytes with ``reader``, or through rclpy's
    deserialiser when it cannot be read raw (e.g. big-endian data); raises InvalidInput on a
    corrupt one."""
    try:
        return reader.read(data)
    except InvalidInput:
        from rclpy.serialization import deserialize_message
        from sensor_msgs.msg import JointState

        try:
            m = deserialize_message(data, JointState)
        except Exception as exc:  # a corrupt serialised message
            raise InvalidInput(f"cannot deserialise the JointState: {exc}") from exc
        st = m.header.stamp
        return RawJointState(st.sec * 1_000_000_000 + st.nanosec, list(m.name),
                             np.asarray(m.position, dtype=float),
                             np.asarray(m.velocity, dtype=float),
                             np.asarray(m.effort, dtype=float))


class RawJointStateWriter:
    """Serialises JointStates with fixed ``names`` and ``frame_id`` (little-endian CDR, what
    ``serialize_message`` produces, up to the padding bytes): the header's frame_id and the
    name sequence are encoded once."""

    def __init__(self, names: list[str] | tuple[str, ...], frame_id: str = ""):
        self.n = len(names)
        body = bytearray()

        def pad(size: int) -> None:
            body.extend(b"\0" * ((-len(body)) % size))  # body starts at the payload start

        def string(text: str) -> None:
            raw = text.encode() + b"\0"
            pad(4)
            body.extend(_U32.pack(len(raw)))
            body.extend(raw)

        body.extend(b"\0" * 8)  # the stamp, written per message
        string(frame_id)
        pad(4)
        body.extend(_U32.pack(self.n))
        for name in names:
            string(name)
        self._prefix = bytes(body)

    def write(self, stamp_ns: int, position: np.ndarray | None = None,
              velocity: np.ndarray | None = None, effort: np.ndarray | None = None) -> bytes:
        """The serialised message: stamp [ns] and the three arrays (n,) (None = empty)."""
        parts = [b"\0\1\0\0", self._prefix]
        size = len(self._prefix)
        for values in (position, velocity, effort):
            pad = (-size) % 4
            if values is None or len(values) == 0:
                parts.append(b"\0" * pad + _U32.pack(0))
                size += pad + 4
                continue
            if len(values) != self.n:
                raise InvalidInput(f"JointState field has {len(values)} values for {self.n} "
                                   "names")
            size += pad + 4
            pad8 = (-size) % 8
            data = np.asarray(values, dtype="<f8").tobytes()
            parts.append(b"\0" * pad + _U32.pack(self.n) + b"\0" * pad8 + data)
            size += pad8 + len(data)
        out = b"".join(parts)
        sec, nanosec = divmod(stamp_ns, 1_000_000_000)
        return out[:4] + _STAMP.pack(sec, nanosec) + out[12:]


class RawWrenchStampedWriter:
    """Serialises geometry_msgs/WrenchStamped with a fixed ``frame_id`` (little-endian CDR,
    what ``serialize_message`` produces, up to the padding bytes): the simulator's FT sensors
    publish two of them every 1 kHz step, and filling the six nested Python objects of a
    WrenchStamped cost more than the rest of its publication."""

    def __init__(self, frame_id: str = ""):
        raw = frame_id.encode() + b"\0"
        body = b"\0" * 8 + _U32.pack(len(raw)) + raw  # stamp (written per message), frame_id
        self._head = b"\0\1\0\0"
        self._frame = body[8:] + b"\0" * ((-len(body)) % 8)  # the wrench is 8-aligned

    def write(self, stamp_ns: int, wrench: np.ndarray) -> bytes:
        """The serialised message: stamp [ns] and ``wrench`` (6,) [fx, fy, fz, tx, ty, tz]
        ([N], [N m])."""
        w = np.asarray(wrench, dtype="<f8")
        if w.shape != (6,):
            raise InvalidInput(f"wrench: expected shape (6,), got {w.shape}")
        sec, nanosec = divmod(stamp_ns, 1_000_000_000)
        return self._head + _STAMP.pack(sec, nanosec) + self._frame + w.tobytes()
