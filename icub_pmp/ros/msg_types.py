"""Resolve ROS interface type names ('sensor_msgs/msg/JointState') and turn messages into
plain dictionaries (what ros2cli's rosidl_runtime_py does; that package is not on PyPI)."""

from __future__ import annotations

import importlib
from typing import Any

from icub_pmp.errors import InvalidInput

__all__ = ["get_interface", "type_name", "message_to_dict"]


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
        raise InvalidInput(f"bad interface type {name!r}: expected pkg/msg/Type or pkg/srv/Type")
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
