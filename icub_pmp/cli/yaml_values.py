"""The values of ``icub call``, ``icub pub`` and ``icub send-goal``: ros2cli's YAML syntax for
a request, message or goal, and the short forms of names and types ros2cli accepts."""

from __future__ import annotations

import re

import yaml

__all__ = ["parse_values", "split_type_and_values", "full_name", "interface_name"]

_TYPE_RE = re.compile(r"^[A-Za-z_]\w*/(?:(?:msg|srv|action)/)?[A-Z]\w*$")


def split_type_and_values(args: list[str]) -> tuple[str | None, str]:
    """``[TYPE] [VALUES]`` -> (type or None, YAML text); a lone argument is a type when it
    looks like ``pkg/srv/Type``."""
    if len(args) > 2:
        raise ValueError(f"expected [TYPE] [VALUES], got {len(args)} arguments: {args} "
                         "(quote the YAML)")
    if len(args) == 2:
        return args[0], args[1]
    if len(args) == 1 and _TYPE_RE.match(args[0]):
        return args[0], "{}"
    return None, args[0] if args else "{}"


def parse_values(text: str) -> dict:
    """The YAML mapping of a request, goal or message (ros2cli syntax); raises ValueError."""
    try:
        values = yaml.safe_load(text) if text.strip() else {}
    except yaml.YAMLError as exc:
        where = getattr(exc, "problem_mark", None)
        at = f" at column {where.column + 1}" if where is not None else ""
        raise ValueError(f"values {text!r} are not valid YAML{at}: "
                         f"{getattr(exc, 'problem', exc)}") from None
    if values is None:
        return {}
    if not isinstance(values, dict):
        raise ValueError(f"values {text!r}: expected a YAML mapping such as "
                         "\"{field: value}\"")
    return values


def full_name(name: str) -> str:
    """``name`` with a leading slash (a CLI node has no namespace to resolve it in)."""
    return name if name.startswith("/") else "/" + name


def interface_name(tname: str, kind: str) -> str:
    """'pkg/Type' -> 'pkg/<kind>/Type' (the short form ros2cli also accepts)."""
    parts = tname.split("/")
    return f"{parts[0]}/{kind}/{parts[1]}" if len(parts) == 2 else tname
