"""Resolve ROS interface type names ('sensor_msgs/msg/JointState'), turn messages into plain
dictionaries and fill them from dictionaries (what ros2cli's rosidl_runtime_py does with
``message_to_ordereddict`` / ``set_message_fields``; that package is not on PyPI)."""

from __future__ import annotations

import importlib
from typing import Any

from icub_pmp.errors import InvalidInput

__all__ = ["get_interface", "type_name", "message_to_dict", "set_message_fields"]


# Message types generated inside an action, as rclpy exposes them on the action class.
_ACTION_PARTS = {"_FeedbackMessage": ("Impl", "FeedbackMessage"), "_Goal": ("Goal",),
                 "_Result": ("Result",), "_Feedback": ("Feedback",)}


def get_interface(name: str) -> Any:
    """Import the class for 'pkg/msg/Type', 'pkg/srv/Type', 'pkg/action/Type' or 'pkg/Type'
    (msg assumed); action parts such as 'pkg/action/Name_FeedbackMessage' (the type of
    ``<action>/_action/feedback``) included."""
    parts = name.strip().split("/")
    if len(parts) == 2:
        parts = [parts[0], "msg", parts[1]]
    if len(parts) != 3 or not all(parts) or parts[1] not in ("msg", "srv", "action"):
        raise InvalidInput(f"bad interface type {name!r}: expected pkg/msg/Type, pkg/srv/Type "
                           "or pkg/action/Type")
    pkg, kind, cls = parts
    try:
        module = importlib.import_module(f"{pkg}.{kind}")
    except ImportError:
        raise InvalidInput(f"interface type {name!r} is not installed") from None
    if hasattr(module, cls):
        return getattr(module, cls)
    if kind == "action":
        for suffix, path in _ACTION_PARTS.items():
            if cls.endswith(suffix) and hasattr(module, cls[: -len(suffix)]):
                obj = getattr(module, cls[: -len(suffix)])
                for attr in path:
                    obj = getattr(obj, attr)
                return obj
    raise InvalidInput(f"interface type {name!r} is not installed")


def type_name(msg_or_cls: Any) -> str:
    """'pkg/msg/Type' of a message instance or class."""
    cls = msg_or_cls if isinstance(msg_or_cls, type) else type(msg_or_cls)
    pkg, kind = cls.__module__.split(".")[:2]
    return f"{pkg}/{kind}/{cls.__name__}"


def message_to_dict(msg: Any, max_array: int | None = 64) -> Any:
    """A message as nested dicts/lists (long arrays cut to ``max_array`` with '...')."""
    if hasattr(msg, "get_fields_and_field_types"):
        fields = msg.get_fields_and_field_types()
        return {f: message_to_dict(getattr(msg, f), max_array) for f in fields}
    if isinstance(msg, (bytes, bytearray)) or (
        hasattr(msg, "tolist") and not isinstance(msg, (int, float, bool, str))
    ):
        msg = list(msg.tolist() if hasattr(msg, "tolist") else msg)
    if isinstance(msg, (list, tuple)):
        items = [message_to_dict(x, max_array) for x in msg]
        if max_array is not None and len(items) > max_array:
            return items[:max_array] + [f"... ({len(items)} items)"]
        return items
    return msg


_INT_RANGES = {
    "int8": (-2**7, 2**7 - 1), "uint8": (0, 2**8 - 1), "octet": (0, 2**8 - 1),
    "int16": (-2**15, 2**15 - 1), "uint16": (0, 2**16 - 1),
    "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1),
    "int64": (-2**63, 2**63 - 1), "uint64": (0, 2**64 - 1),
    "char": (0, 2**8 - 1),
}


def set_message_fields(msg: Any, values: Any, path: str = "") -> Any:
    """Fill ``msg`` (a message instance) from ``values``, a dict as parsed from ros2cli's YAML
    syntax (``{wrench: {force: {x: 1.0}}, duration: 0.2}``); fields not named keep their
    defaults. Returns ``msg``.

    Raises :class:`InvalidInput` naming the field path (``wrench.force.x``), the value and
    what was expected: unknown field names (with the valid ones), wrong types, integers out of
    range, fixed-size arrays of the wrong length. Numbers may come as strings (``1e6``, which
    YAML 1.1 reads as a string), as ros2cli accepts them. On error ``msg`` may be partly
    filled: fill a fresh message.
    """
    if values is None:
        return msg
    if not isinstance(values, dict):
        raise InvalidInput(f"{path or type(msg).__name__}: expected a mapping of field names "
                           f"({', '.join(msg.get_fields_and_field_types())}), got "
                           f"{values!r}")
    fields = list(msg.get_fields_and_field_types())
    slots = dict(zip(fields, msg.SLOT_TYPES))
    for key, value in values.items():
        where = f"{path}.{key}" if path else str(key)
        if key not in slots:
            raise InvalidInput(f"{where}: no such field in {type_name(msg)}; valid: "
                               f"{', '.join(fields) or '(none)'}")
        setattr(msg, key, _field_value(getattr(msg, key), slots[key], value, where))
    return msg


def _field_value(current: Any, slot: Any, value: Any, where: str) -> Any:
    """The value to assign to a field of rosidl type ``slot`` from ``value`` (YAML)."""
    from rosidl_parser import definition as d

    if isinstance(slot, d.NamespacedType):
        return set_message_fields(type(current)(), value, where)
    if isinstance(slot, (d.AbstractSequence, d.Array)):
        if isinstance(value, (bytes, bytearray)):
            value = list(value)
        if not isinstance(value, (list, tuple)):
            raise InvalidInput(f"{where}: expected a list, got {value!r}")
        if isinstance(slot, d.Array) and len(value) != slot.size:
            raise InvalidInput(f"{where}: expected exactly {slot.size} items, got "
                               f"{len(value)}")
        if isinstance(slot, d.BoundedSequence) and len(value) > slot.maximum_size:
            raise InvalidInput(f"{where}: expected at most {slot.maximum_size} items, got "
                               f"{len(value)}")
        item = slot.value_type
        if isinstance(item, d.NamespacedType):
            cls = _message_class(item)
            return [set_message_fields(cls(), v, f"{where}[{i}]") for i, v in enumerate(value)]
        out = [_scalar(item, v, f"{where}[{i}]") for i, v in enumerate(value)]
        if isinstance(item, d.BasicType) and item.typename in ("octet", "uint8"):
            return bytes(out) if isinstance(current, bytes) else out
        return out
    return _scalar(slot, value, where)


def _scalar(slot: Any, value: Any, where: str) -> Any:
    from rosidl_parser import definition as d

    if isinstance(slot, d.AbstractGenericString):
        if not isinstance(value, str):
            raise InvalidInput(f"{where}: expected a string, got {value!r} (quote it in YAML)")
        if isinstance(slot, (d.BoundedString, d.BoundedWString)) and \
                len(value) > slot.maximum_size:
            raise InvalidInput(f"{where}: expected at most {slot.maximum_size} characters, got "
                               f"{len(value)}")
        return value
    t = slot.typename
    if t == "boolean":
        if not isinstance(value, bool):
            raise InvalidInput(f"{where}: expected true or false, got {value!r}")
        return value
    if t in ("float", "double"):
        if isinstance(value, str):  # YAML 1.1 reads 1e6 (no dot) as a string, as ros2cli
            value = _parse(float, value, where, "a number")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InvalidInput(f"{where}: expected a number, got {value!r}")
        return float(value)
    if t == "char" and isinstance(value, str) and len(value) == 1:
        value = ord(value)
    if t == "octet" and isinstance(value, (bytes, bytearray)) and len(value) == 1:
        return bytes(value)
    if t in _INT_RANGES:
        if isinstance(value, str):
            value = _parse(int, value, where, f"an integer ({t})")
        if isinstance(value, bool) or not isinstance(value, int):
            raise InvalidInput(f"{where}: expected an integer ({t}), got {value!r}")
        lo, hi = _INT_RANGES[t]
        if not lo <= value <= hi:
            raise InvalidInput(f"{where}: {value} is out of the {t} range [{lo}, {hi}]")
        return bytes([value]) if t == "octet" else value
    raise InvalidInput(f"{where}: unsupported field type {t!r}")  # pragma: no cover


def _parse(kind: type, text: str, where: str, expected: str) -> Any:
    try:
        return kind(text)
    except ValueError:
        raise InvalidInput(f"{where}: expected {expected}, got {text!r}") from None


def _message_class(slot: Any) -> Any:
    """The Python class of a rosidl NamespacedType ('geometry_msgs', 'msg', 'Point')."""
    return get_interface("/".join([*slot.namespaces, slot.name]))
