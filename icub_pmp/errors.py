"""The project's exception hierarchy: one base class, specific subclasses.

Messages name the argument, the value received, what was expected and the valid choices, so a
node can forward ``str(err)`` to a user as a one-line answer.
"""

from __future__ import annotations

import difflib
from typing import Iterable

__all__ = [
    "IcubPmpError",
    "ConfigError",
    "InvalidInput",
    "UnknownName",
    "ModelError",
    "PlanningError",
    "SolverError",
    "BagError",
]


class IcubPmpError(Exception):
    """Base class of every error this project raises on purpose."""


class ConfigError(IcubPmpError):
    """A configuration (dataclass, YAML parameter file) is malformed or out of range."""


class InvalidInput(IcubPmpError, ValueError):
    """An input value is malformed: NaN/inf, wrong shape or length, out of range."""


class UnknownName(InvalidInput):
    """A name (joint, frame, chain, hand, topic) is not one of the valid choices."""

    def __init__(self, kind: str, name: str, valid: Iterable[str]):
        self.kind = kind
        self.name = name
        self.valid = sorted(valid)
        if len(self.valid) <= 40:
            hint = "valid: " + ", ".join(self.valid)
        else:
            close = difflib.get_close_matches(str(name), self.valid, n=8, cutoff=0.3)
            hint = f"{len(self.valid)} valid names, closest: " + ", ".join(close or self.valid[:8])
        super().__init__(f"unknown {kind} {name!r}; {hint}")


class ModelError(IcubPmpError):
    """The robot model could not be found, loaded or built."""


class PlanningError(IcubPmpError):
    """A planner could not produce a plan (the evidence is kept in attributes)."""


class SolverError(IcubPmpError):
    """A numerical solver failed (IPOPT status, iteration limit, time limit)."""


class BagError(IcubPmpError):
    """A bag is missing, truncated, corrupt or not in the expected layout."""
