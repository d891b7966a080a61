"""MessageDefinitions: complete ``ros2msg`` schema texts of ROS interface types, for MCAP.

A bag stores, per channel, the "complete message definition" of its type (rosbag2
``docs/message_definition_encoding.md``): the type's ``.msg`` text, then every nested type's
text preceded by a line of 80 ``=`` and ``MSG: pkg/Type``. Foxglove and the official
``mcap-ros2-support`` decoder build their deserialisers from it. The texts come from the
installed interface files (``share/<pkg>/msg/<Type>.msg``, ``share/<pkg>/srv/<Srv>.srv``) found
on ``AMENT_PREFIX_PATH``, like rosbag2's own ``LocalMessageDefinitionSource``; service event
types (``pkg/srv/Srv_Event``, recorded from ``<service>/_service_event``) are assembled from
the ``.srv`` file the way rosidl generates them. When a file is missing, the definition comes
from the rosbags Jazzy type store. No ROS import.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Iterable, Sequence

from icub_pmp.errors import BagError

__all__ = ["MessageDefinitions", "split_type_name"]

_PRIMITIVES = frozenset(
    "bool byte char float32 float64 int8 uint8 int16 uint16 int32 uint32 int64 uint64 "
    "string wstring".split()
)
_DELIMITER = "=" * 80
# The type token of a field line: "pkg/Type[] name", "Type[<=3] name", "string<=5 name".
_FIELD_TYPE = re.compile(r"^\s*([A-Za-z][A-Za-z0-9_/]*)(?:<=\d+)?(?:\[[^\]]*\])?\s+\S")
_SRV_PART = {"_Request": 0, "_Response": 1}


def split_type_name(name: str) -> tuple[str, str, str]:
    """('pkg', 'msg'|'srv', 'Type') of 'pkg/msg/Type' or 'pkg/Type' (raises BagError)."""
    parts = name.strip().split("/")
    if len(parts) == 2:
        parts = [parts[0], "msg", parts[1]]
    if len(parts) != 3 or not all(parts) or parts[1] not in ("msg", "srv", "action"):
        raise BagError(f"bad message type name {name!r}: expected pkg/msg/Type")
    return parts[0], parts[1], parts[2]


class MessageDefinitions:
    """Complete ``ros2msg`` definitions of message types, cached.

    ``prefixes`` are install prefixes searched for ``share/<pkg>/`` (default: the entries of
    ``AMENT_PREFIX_PATH``).
    """

    def __init__(self, prefixes: Sequence[str | Path] | None = None):
        if prefixes is None:
            prefixes = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
        self.prefixes = tuple(Path(p) for p in prefixes)
        self._texts: dict[str, str] = {}
        self._full: dict[str, str] = {}
        self._typestore = None

    # ------------------------------------------------------------------ public
    def definition(self, type_name: str) -> str:
        """The complete ``ros2msg`` definition of ``type_name`` ('pkg/msg/Type').

        Raises :class:`BagError` when the type or one of its nested types is unknown.
        """
        if type_name not in self._full:
            try:
                self._full[type_name] = self._assemble(type_name)
            except BagError:
                self._full[type_name] = self._from_typestore(type_name)
        return self._full[type_name]

    # ------------------------------------------------------------------ assembly
    def _assemble(self, root: str) -> str:
        seen: set[str] = {root}
        blocks = [self._text(root).rstrip("\n")]

        def visit(name: str) -> None:
            for dep in self._dependencies(self._text(name), split_type_name(name)[0]):
                if dep not in seen:
                    seen.add(dep)
                    blocks.append(f"{_DELIMITER}\nMSG: {dep}\n{self._text(dep).rstrip()}")
                    visit(dep)

        visit(root)
        return "\n".join(blocks) + "\n"

    def _text(self, type_name: str) -> str:
        if type_name in self._texts:
            return self._texts[type_name]
        pkg, kind, name = split_type_name(type_name)
        text: str | None = None
        if kind == "msg":
            text = self._read(pkg, "msg", f"{name}.msg")
        if kind == "srv" or text is None:  # 'pkg/Srv_Request' is how nested srv parts appear
            text = self._service_part(pkg, name)
        if text is None:
            raise BagError(f"no interface definition found for {type_name!r}")
        self._texts[type_name] = text
        return text

    def _service_part(self, pkg: str, name: str) -> str | None:
        for suffix, index in _SRV_PART.items():
            if name.endswith(suffix):
                srv = self._read(pkg, "srv", f"{name[: -len(suffix)]}.srv")
                if srv is None:
                    return None
                parts = re.split(r"^---\s*$", srv, maxsplit=1, flags=re.MULTILINE)
                return parts[index] if index < len(parts) else ""
        if name.endswith("_Event"):
            base = name[: -len("_Event")]
            if self._read(pkg, "srv", f"{base}.srv") is None:
                return None
            # The layout rosidl generates for service introspection events.
            return (
                "service_msgs/ServiceEventInfo info\n"
                f"{base}_Request[<=1] request\n"
                f"{base}_Response[<=1] response\n"
            )
        return None

    def _read(self, pkg: str, kind: str, filename: str) -> str | None:
        for prefix in self.prefixes:
            path = prefix / "share" / pkg / kind / filename
            if path.is_file():
                return path.read_text(encoding="utf-8")
        return None

    @staticmethod
    def _dependencies(text: str, context: str) -> list[str]:
        """Nested (non-primitive) types of a .msg text, as 'pkg/Type' or 'pkg/srv/Type'."""
        deps: list[str] = []
        for line in text.splitlines():
            line = line.split("#", 1)[0]
            m = _FIELD_TYPE.match(line)
            if not m:
                continue
            token = m.group(1)
            if token in _PRIMITIVES:
                continue  # includes every constant ("uint8 NAME = 1")
            if "/" not in token:
                token = f"{context}/{token}"
            if token not in deps:
                deps.append(token)
        return deps

    # ------------------------------------------------------------------ fallback
    def _from_typestore(self, type_name: str) -> str:
        from rosbags.typesys import Stores, get_typestore
        from rosbags.typesys.base import TypesysError

        if self._typestore is None:
            self._typestore = get_typestore(Stores.ROS2_JAZZY)
        pkg, kind, name = split_type_name(type_name)
        try:
            text, _ = self._typestore.generate_msgdef(f"{pkg}/{kind}/{name}", ros_version=2)
        except TypesysError:
            raise BagError(
                f"no definition for message type {type_name!r}: not installed "
                f"(searched {len(self.prefixes)} prefixes of AMENT_PREFIX_PATH) and not a "
                "standard Jazzy type"
            ) from None
        return text

    def known(self, type_names: Iterable[str]) -> list[str]:
        """The subset of ``type_names`` whose definition can be built."""
        ok = []
        for t in type_names:
            try:
                self.definition(t)
                ok.append(t)
            except BagError:
                pass
        return ok
