"""Configuration dataclasses built from ROS parameters or YAML parameter files.

Every algorithm has one frozen dataclass whose field names equal its ROS parameter names, so a
node builds it straight from its parameters (``Config.from_dict(params)``) and a test loads the
shipped ``config/<node>.yaml`` into it (``load_params_file``).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any, Mapping, TypeVar

import yaml

from icub_pmp.errors import ConfigError

__all__ = ["ConfigBase", "load_params_file", "repo_root", "config_dir"]

T = TypeVar("T", bound="ConfigBase")


def repo_root() -> Path:
    """Return the source tree root (the folder holding ``package.xml``)."""
    return Path(__file__).resolve().parent.parent


def config_dir() -> Path:
    """Return the folder of the shipped YAML parameter files.

    The source tree's ``config/`` when running from a checkout, else the installed
    ``share/icub_pmp/config`` (found through ament_index when available).
    """
    src = repo_root() / "config"
    if src.is_dir():
        return src
    try:  # installed package without the source tree
        from ament_index_python.packages import get_package_share_directory

        return Path(get_package_share_directory("icub_pmp")) / "config"
    except Exception as exc:  # pragma: no cover - only without a source tree
        raise ConfigError(f"cannot find the icub_pmp config folder: {exc}") from exc


def load_params_file(path: str | Path, node_name: str) -> dict[str, Any]:
    """Read the ``ros__parameters`` of ``node_name`` from a ROS ``--params-file`` YAML.

    Accepts the keys ``node_name``, ``/node_name``, ``/**/node_name`` and ``/**``. Nested
    dictionaries are flattened with dots, as ROS does.
    """
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text()) or {}
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError(f"cannot read parameter file {path}: {exc}") from exc
    out: dict[str, Any] = {}
    for key in ("/**", node_name, f"/{node_name}", f"/**/{node_name}"):
        block = data.get(key)
        if isinstance(block, dict) and isinstance(block.get("ros__parameters"), dict):
            out.update(_flatten(block["ros__parameters"]))
    if not out:
        raise ConfigError(f"{path}: no ros__parameters for node {node_name!r} (keys: {list(data)})")
    return out


def _flatten(d: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in d.items():
        name = f"{prefix}{k}"
        if isinstance(v, Mapping):
            out.update(_flatten(v, name + "."))
        else:
            out[name] = v
    return out


@dataclasses.dataclass(frozen=True)
class ConfigBase:
    """Base of the project's frozen configuration dataclasses.

    Subclasses declare typed fields with defaults and may override :meth:`validate` to check
    ranges (raise :class:`ConfigError` naming the field).
    """

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if isinstance(v, float) and math.isnan(v):
                raise ConfigError(f"{type(self).__name__}.{f.name} is NaN")
            if isinstance(v, list):  # keep the frozen object immutable
                object.__setattr__(self, f.name, tuple(v))
        self.validate()

    def validate(self) -> None:
        """Check field ranges; raise :class:`ConfigError` on a bad value."""

    @classmethod
    def field_names(cls) -> list[str]:
        """The parameter names this configuration accepts."""
        return [f.name for f in dataclasses.fields(cls)]

    @classmethod
    def from_dict(cls: type[T], params: Mapping[str, Any], *, ignore_unknown: bool = False) -> T:
        """Build from a parameter dictionary; unknown keys are rejected by name.

        ``ignore_unknown`` lets a node pass all its parameters (``use_sim_time``, other
        groups) and keep only this configuration's fields.
        """
        names = set(cls.field_names())
        unknown = sorted(set(params) - names)
        if unknown and not ignore_unknown:
            raise ConfigError(
                f"{cls.__name__}: unknown parameter(s) {unknown}; valid: {sorted(names)}"
            )
        kwargs = {}
        for f in dataclasses.fields(cls):
            if f.name not in params:
                continue
            kwargs[f.name] = _coerce(cls.__name__, f, params[f.name])
        try:
            return cls(**kwargs)
        except TypeError as exc:
            raise ConfigError(f"{cls.__name__}: {exc}") from exc

    @classmethod
    def from_yaml(cls: type[T], path: str | Path, node_name: str) -> T:
        """Build from a ROS parameter file, ignoring parameters of other configurations."""
        return cls.from_dict(load_params_file(path, node_name), ignore_unknown=True)

    def to_dict(self) -> dict[str, Any]:
        """Return the fields as a plain dictionary (tuples as lists, for ROS parameters)."""
        return {
            k: (list(v) if isinstance(v, tuple) else v) for k, v in dataclasses.asdict(self).items()
        }


def _coerce(owner: str, f: dataclasses.Field, value: Any) -> Any:
    """Convert YAML/ROS values to the declared field type (int -> float, list -> tuple)."""
    t = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", str(f.type))
    try:
        if t == "float":
            if isinstance(value, bool):
                raise TypeError
            return float(value)
        if t == "int":
            if isinstance(value, bool) or (isinstance(value, float) and not value.is_integer()):
                raise TypeError
            return int(value)
        if t == "bool":
            if not isinstance(value, bool):
                raise TypeError
            return value
        if t == "str":
            if not isinstance(value, str):
                raise TypeError
            return value
        if t.startswith("tuple[float") or t.startswith("Tuple[float"):
            return tuple(float(x) for x in value)
        if t.startswith("tuple[str") or t.startswith("Tuple[str"):
            return tuple(str(x) for x in value)
        if t.startswith("tuple[int") or t.startswith("Tuple[int"):
            return tuple(int(x) for x in value)
    except (TypeError, ValueError):
        raise ConfigError(f"{owner}.{f.name}: expected {t}, got {value!r}") from None
    return value
