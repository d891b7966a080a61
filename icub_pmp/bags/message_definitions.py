"""MessageDefinitions: the schema texts and type hashes of ROS interface types, for MCAP.

A bag stores, per channel, the "complete message definition" of its type (rosbag2
``docs/message_definition_encoding.md``), which readers without the ROS interface packages
(rosbags, the official ``mcap-ros2-support`` decoder, Foxglove) build their deserialisers from,
and the type's RIHS01 hash (REP-2011), which rosbags checks against the definition.

- Messages (``pkg/msg/Type``): encoding ``ros2msg``, the ``.msg`` text then every nested type's
  text after a line of 80 ``=`` and ``MSG: pkg/Type``, as rosbag2's
  ``LocalMessageDefinitionSource`` writes it.
- Action parts (``pkg/action/Name_FeedbackMessage``, ``_Goal``, ``_Result``, ``_Feedback``),
  recorded from ``<action>/_action/feedback``: ``ros2msg``, the sections of the ``.action``
  file, the action-part blocks named in full (``MSG: pkg/action/Name_Feedback``) so that
  rosbags resolves them and computes the published hash (rosbag2 Jazzy leaves these schemas
  empty).
- Service events (``pkg/srv/Name_Event``), recorded from ``<service>/_service_event``:
  encoding ``ros2idl``, the event structure as rosidl generates it (``info``, ``request`` and
  ``response`` as sequences of at most one element), then the installed ``.idl`` files it
  needs, each after ``IDL: pkg/kind/Type``. rosbag2 Jazzy writes the raw ``.srv`` text there,
  which no reader decodes (ros2/rosbag2 issue 2365); rosbags normalises every ``ros2msg`` name
  to ``pkg/msg/Type``, so only the IDL form keeps ``pkg/srv/Name_Event`` resolvable. The
  ``#include`` lines are left out of the IDL blocks (every included file is its own block;
  rosbags' IDL grammar has no preprocessor).

Texts come from the installed interface files found on ``AMENT_PREFIX_PATH``
(``share/<pkg>/{msg,srv,action}/``), hashes from rosidl's type description files
(``share/<pkg>/<kind>/<Name>.json``); a type without files falls back to the rosbags Jazzy type
store. No ROS import.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path
from typing import Iterable, Sequence

from icub_pmp.errors import BagError

__all__ = ["MessageDefinitions", "split_type_name", "schema_encoding", "DELIMITER"]

_PRIMITIVES = frozenset(
    "bool byte char float32 float64 int8 uint8 int16 uint16 int32 uint32 int64 uint64 "
    "string wstring".split()
)
DELIMITER = "=" * 80
# The type token of a field line: "pkg/Type[] name", "Type[<=3] name", "string<=5 name".
_FIELD_TYPE = re.compile(r"^\s*([A-Za-z][A-Za-z0-9_/]*)(?:<=\d+)?(?:\[[^\]]*\])?\s+\S")
_SRV_PART = {"_Request": 0, "_Response": 1}
_ACTION_PART = {"_Goal": 0, "_Result": 1, "_Feedback": 2}
_IDL_INCLUDE = re.compile(r'^\s*#include\s+[<"]([A-Za-z0-9_/]+)\.idl[>"]\s*$', re.MULTILINE)


def split_type_name(name: str) -> tuple[str, str, str]:
    """('pkg', 'msg'|'srv'|'action', 'Type') of 'pkg/kind/Type' or 'pkg/Type' (raises BagError)."""
    parts = name.strip().split("/")
    if len(parts) == 2:
        parts = [parts[0], "msg", parts[1]]
    if len(parts) != 3 or not all(parts) or parts[1] not in ("msg", "srv", "action"):
        raise BagError(f"bad message type name {name!r}: expected pkg/msg/Type")
    return parts[0], parts[1], parts[2]


def schema_encoding(definition: str) -> str:
    """'ros2idl' for a definition in rosbag2's IDL layout, else 'ros2msg'."""
    return "ros2idl" if definition.startswith(f"{DELIMITER}\nIDL: ") else "ros2msg"


class MessageDefinitions:
    """Complete schema texts and RIHS01 hashes of interface types, cached.

    ``prefixes`` are install prefixes searched for ``share/<pkg>/`` (default: the entries of
    ``AMENT_PREFIX_PATH``).
    """

    def __init__(self, prefixes: Sequence[str | Path] | None = None):
        if prefixes is None:
            prefixes = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
        self.prefixes = tuple(Path(p) for p in prefixes)
        self._texts: dict[str, str] = {}
        self._full: dict[str, str] = {}
        self._hashes: dict[str, str] = {}
        self._typestore = None

    # ------------------------------------------------------------------ public
    def definition(self, type_name: str) -> str:
        """The complete definition of ``type_name`` ('pkg/kind/Type'): ``ros2msg`` text, or
        for a service event the ``ros2idl`` text (see :func:`schema_encoding`).

        Raises :class:`BagError` when the type or one of its nested types is unknown.
        """
        if type_name not in self._full:
            pkg, kind, name = split_type_name(type_name)
            try:
                if kind == "srv" and name.endswith("_Event"):
                    self._full[type_name] = self._service_event_idl(pkg, name[: -len("_Event")])
                else:
                    self._full[type_name] = self._assemble(type_name)
            except BagError:
                self._full[type_name] = self._from_typestore(type_name)
        return self._full[type_name]

    def type_hash(self, type_name: str) -> str:
        """The RIHS01 hash of ``type_name`` ('RIHS01_<64 hex>') from the installed type
        description files, else from the rosbags Jazzy type store; '' when neither knows it."""
        if type_name not in self._hashes:
            self._hashes[type_name] = self._hash_from_files(type_name) or self._typestore_hash(
                type_name)
        return self._hashes[type_name]

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

    # ------------------------------------------------------------------ ros2msg
    def _assemble(self, root: str) -> str:
        seen: set[str] = {root}
        blocks = [self._text(root).rstrip("\n")]

        def visit(name: str) -> None:
            for dep in self._dependencies(self._text(name), split_type_name(name)[0]):
                dep = self._qualify(dep)
                if dep not in seen:
                    seen.add(dep)
                    blocks.append(f"{DELIMITER}\nMSG: {dep}\n{self._text(dep).rstrip()}")
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
        if kind == "srv" or (kind == "msg" and text is None):
            text = self._service_part(pkg, name)  # 'pkg/Srv_Request' as nested srv parts appear
        if kind == "action":
            text = self._action_part(pkg, name)
        if text is None:
            raise BagError(f"no interface definition found for {type_name!r}")
        self._texts[type_name] = text
        return text

    def _service_part(self, pkg: str, name: str) -> str | None:
        return self._section(pkg, "srv", name, _SRV_PART)

    def _action_part(self, pkg: str, name: str) -> str | None:
        if name.endswith("_FeedbackMessage"):
            base = name[: -len("_FeedbackMessage")]
            if self._read(pkg, "action", f"{base}.action") is None:
                return None
            # The message rosidl generates for <action>/_action/feedback.
            return f"unique_identifier_msgs/UUID goal_id\n{base}_Feedback feedback\n"
        return self._section(pkg, "action", name, _ACTION_PART)

    def _section(self, pkg: str, kind: str, name: str, parts: dict[str, int]) -> str | None:
        """The part of ``<Base>.<kind>`` that ``name`` = ``<Base><suffix>`` names (the
        sections are separated by '---' lines), or None."""
        for suffix, index in parts.items():
            if name.endswith(suffix):
                text = self._read(pkg, kind, f"{name[: -len(suffix)]}.{kind}")
                if text is None:
                    return None
                sections = re.split(r"^---\s*$", text, flags=re.MULTILINE)
                return sections[index].lstrip("\n") if index < len(sections) else ""
        return None

    def _read(self, pkg: str, kind: str, filename: str) -> str | None:
        for prefix in self.prefixes:
            path = prefix / "share" / pkg / kind / filename
            if path.is_file():
                return path.read_text(encoding="utf-8")
        return None

    def _qualify(self, dep: str) -> str:
        """'pkg/Name_Feedback' -> 'pkg/action/Name_Feedback' when it is an action part and no
        message of that name exists (rosbags resolves the unqualified field type next to its
        parent 'pkg/action/Name_FeedbackMessage', and names the block it reads after it)."""
        if dep.count("/") != 1:
            return dep
        pkg, name = dep.split("/")
        if self._read(pkg, "msg", f"{name}.msg") is None and self._action_part(pkg, name):
            return f"{pkg}/action/{name}"
        return dep

    @staticmethod
    def _dependencies(text: str, context: str) -> list[str]:
        """Nested (non-primitive) types of a .msg text, as 'pkg/Type' or 'pkg/kind/Type'."""
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

    # ------------------------------------------------------------------ ros2idl
    def _service_event_idl(self, pkg: str, srv: str) -> str:
        """The ``ros2idl`` definition of ``pkg/srv/<srv>_Event`` (layout of rosidl_parser's
        ``Service.event_message``), then every ``.idl`` file it includes."""
        if self._read(pkg, "srv", f"{srv}.idl") is None:
            raise BagError(f"no interface definition found for '{pkg}/srv/{srv}'")
        root = (
            f'#include "{pkg}/srv/{srv}.idl"\n'
            '#include "service_msgs/msg/ServiceEventInfo.idl"\n\n'
            f"module {pkg} {{\n"
            "  module srv {\n"
            f"    struct {srv}_Event {{\n"
            "      service_msgs::msg::ServiceEventInfo info;\n\n"
            f"      sequence<{pkg}::srv::{srv}_Request, 1> request;\n\n"
            f"      sequence<{pkg}::srv::{srv}_Response, 1> response;\n"
            "    };\n"
            "  };\n"
            "};\n"
        )
        blocks: list[str] = []
        seen: set[str] = set()

        def add(name: str, text: str) -> None:
            seen.add(name)
            blocks.append(f"{DELIMITER}\nIDL: {name}\n{_IDL_INCLUDE.sub('', text).lstrip()}")
            for inc in _IDL_INCLUDE.findall(text):
                if inc not in seen:
                    dep_pkg, dep_kind, dep_name = split_type_name(inc)
                    dep = self._read(dep_pkg, dep_kind, f"{dep_name}.idl")
                    if dep is None:
                        raise BagError(f"no interface definition found for {inc!r}")
                    add(inc, dep)

        add(f"{pkg}/srv/{srv}_Event", root)
        return "\n".join(b.rstrip("\n") for b in blocks) + "\n"

    # ------------------------------------------------------------------ hashes
    def _hash_from_files(self, type_name: str) -> str:
        pkg, kind, name = split_type_name(type_name)
        full = f"{pkg}/{kind}/{name}"
        # the file is named after the interface: Reach.json holds Reach_Event, Reach_Request...
        stem = name
        while True:
            text = self._read(pkg, kind, f"{stem}.json")
            if text is not None:
                try:
                    hashes = json.loads(text).get("type_hashes", [])
                except ValueError:
                    hashes = []
                for h in hashes:
                    if h.get("type_name") == full:
                        return str(h.get("hash_string", ""))
            if "_" not in stem:
                return ""
            stem = stem.rsplit("_", 1)[0]

    def _typestore_hash(self, type_name: str) -> str:
        try:
            return self._store().hash_rihs01(type_name)
        except Exception:  # rosbags raises TypesysError/KeyError for unknown types
            return ""

    # ------------------------------------------------------------------ fallback
    def _store(self):  # noqa: ANN202 - rosbags Typestore
        from rosbags.typesys import Stores, get_typestore

        if self._typestore is None:
            self._typestore = get_typestore(Stores.ROS2_JAZZY)
        return self._typestore

    def _from_typestore(self, type_name: str) -> str:
        from rosbags.typesys.base import TypesysError

        pkg, kind, name = split_type_name(type_name)
        try:
            text, _ = self._store().generate_msgdef(f"{pkg}/{kind}/{name}", ros_version=2)
        except TypesysError:
            raise BagError(
                f"no definition for message type {type_name!r}: not installed "
                f"(searched {len(self.prefixes)} prefixes of AMENT_PREFIX_PATH) and not a "
                "standard Jazzy type"
            ) from None
        return text
