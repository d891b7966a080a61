"""ConfigParameters: a node's configuration dataclasses declared as its ROS parameters.

Every field of each :class:`~icub_pmp.config.ConfigBase` class becomes a parameter of the same
name (the class default as its default; tuples as lists), described from the class docstring's
``Attributes:`` section where it has one. The configurations are built from the parameters
(``from_dict``: types checked, ranges validated), and a change at run time is validated the
same way before it is accepted: a bad value is refused with the configuration's message and
the node keeps its configuration; a field declared read-only cannot change. The node reacts to
an accepted change in ``on_change`` (rebuild a core, restart a timer), which may itself refuse
it by raising an :class:`~icub_pmp.errors.IcubPmpError`.
"""

from __future__ import annotations

import dataclasses
import re
from typing import Any, Callable, Collection, Generic, Mapping, Sequence, TypeVar

from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.node import Node

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError, IcubPmpError

__all__ = ["ConfigParameters", "attribute_descriptions"]

C = TypeVar("C", bound=ConfigBase)


def attribute_descriptions(cls: type) -> dict[str, str]:
    """{field: text} from the ``Attributes:`` section of ``cls``'s docstring (Google style:
    ``name: text`` entries, continuation lines indented deeper)."""
    doc = cls.__doc__ or ""
    head = re.search(r"^(\s*)Attributes:\s*$", doc, re.M)
    if head is None:
        return {}
    out: dict[str, str] = {}
    entry = re.compile(r"^(\s*)(\w+(?:, \w+)*): (.*)$")
    indent: int | None = None
    names: list[str] = []
    for line in doc[head.end():].splitlines():
        m = entry.match(line)
        if m and (indent is None or len(m.group(1)) == indent):
            indent = len(m.group(1))
            names = m.group(2).split(", ")
            for name in names:
                out[name] = m.group(3).strip()
        elif line.strip() and indent is not None and len(line) - len(line.lstrip()) > indent:
            for name in names:
                out[name] += " " + line.strip()
        elif line.strip():
            break
    return out


class ConfigParameters(Generic[C]):
    """Declare the fields of ``configs`` as parameters of ``node`` and keep them validated.

    Args:
        node: the node (parameters are declared at once).
        configs: one configuration class, or several (their field names must differ).
        read_only: fields that cannot change once the node runs (they shape a model).
        check: a cross-check of the built configurations (raise ``IcubPmpError``), run at
            start-up and on every change.
        on_change: ``on_change(old, new, changed)`` after a change is validated and before it
            is committed; raise ``IcubPmpError`` to refuse it. ``old`` and ``new`` are the
            configuration (one class) or the tuple of configurations (several), ``changed``
            the names of the changed fields.
        reject: ``reject({name: value})`` of every parameter in a set request (also the ones
            that are not fields, e.g. ``use_sim_time``): a reason to refuse it, or None.

    Raises:
        ConfigError: the node was started with parameters the configurations refuse.
    """

    def __init__(
        self,
        node: Node,
        configs: type[C] | Sequence[type[ConfigBase]],
        *,
        read_only: Collection[str] = (),
        check: Callable[[Any], None] | None = None,
        on_change: Callable[[Any, Any, frozenset[str]], None] | None = None,
        reject: Callable[[Mapping[str, Any]], str | None] | None = None,
    ) -> None:
        self._single = isinstance(configs, type)
        self.classes: tuple[type[ConfigBase], ...] = (
            (configs,) if isinstance(configs, type) else tuple(configs))
        self.names: dict[str, type[ConfigBase]] = {}
        for cls in self.classes:
            for name in cls.field_names():
                if name in self.names:
                    raise ConfigError(f"parameter {name!r} is a field of both "
                                      f"{self.names[name].__name__} and {cls.__name__}")
                self.names[name] = cls
        unknown = sorted(set(read_only) - set(self.names))
        if unknown:
            raise ConfigError(f"read_only: {unknown} are not fields of "
                              f"{[c.__name__ for c in self.classes]}")
        self.read_only = frozenset(read_only)
        self._node = node
        self._check = check
        self._on_change = on_change
        self._reject = reject
        for cls in self.classes:
            text = attribute_descriptions(cls)
            for name, value in cls().to_dict().items():
                node.declare_parameter(name, value, ParameterDescriptor(
                    description=text.get(
                        name, f"{cls.__name__}.{name} (see config/{node.get_name()}.yaml)"),
                    read_only=name in self.read_only))
        values = {n: node.get_parameter(n).value for n in self.names}
        try:
            self._configs = self._build(values)
        except IcubPmpError as exc:
            raise ConfigError(f"bad parameters: {exc}") from exc
        node.add_on_set_parameters_callback(self._on_set)

    # ------------------------------------------------------------------ access
    @property
    def config(self) -> C:
        """The configuration (a node with one configuration class)."""
        if not self._single:
            raise ConfigError("several configurations: use get(cls) or configs")
        return self._configs[0]  # type: ignore[return-value]

    @property
    def configs(self) -> tuple[ConfigBase, ...]:
        """The configurations, in the order of the classes."""
        return self._configs

    def get(self, cls: type[C]) -> C:
        """The current configuration of class ``cls``."""
        return self._configs[self.classes.index(cls)]  # type: ignore[return-value]

    # ------------------------------------------------------------------ changes
    def _build(self, values: Mapping[str, Any]) -> tuple[ConfigBase, ...]:
        configs = tuple(cls.from_dict(values, ignore_unknown=True) for cls in self.classes)
        if self._check is not None:
            self._check(configs[0] if self._single else configs)
        return configs

    def _on_set(self, params: list) -> SetParametersResult:
        if self._reject is not None:
            reason = self._reject({p.name: p.value for p in params})
            if reason:
                return SetParametersResult(successful=False, reason=reason)
        changes = {p.name: p.value for p in params if p.name in self.names}
        if not changes:
            return SetParametersResult(successful=True)
        fixed = sorted(set(changes) & self.read_only)
        if fixed:
            return SetParametersResult(
                successful=False, reason=f"{', '.join(fixed)} cannot change at run time: "
                                         "restart the node")
        values = {k: v for c in self._configs for k, v in c.to_dict().items()}
        try:
            new = self._build({**values, **changes})
            if self._on_change is not None:
                old_arg = self._configs[0] if self._single else self._configs
                new_arg = new[0] if self._single else new
                changed = frozenset(n for n in changes if values[n] != _plain(new, n))
                self._on_change(old_arg, new_arg, changed)
        except IcubPmpError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        self._configs = new
        return SetParametersResult(successful=True)


def _plain(configs: tuple[ConfigBase, ...], name: str) -> Any:
    """Value of field ``name`` in ``configs`` as ``to_dict`` gives it (tuples as lists)."""
    for c in configs:
        if any(f.name == name for f in dataclasses.fields(c)):
            return c.to_dict()[name]
    raise KeyError(name)
