"""The registry of the report's experiments: each a plain ``run(size) -> ExperimentResult``."""

from __future__ import annotations

import dataclasses
import time
from typing import Callable

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.paper.experiment_result import ExperimentResult

__all__ = ["Experiment", "EXPERIMENTS", "experiment", "find", "run_experiment"]


@dataclasses.dataclass(frozen=True)
class Experiment:
    """A registered experiment.

    Attributes:
        name: unique name (``--only NAME``).
        run: ``run(size) -> ExperimentResult``; ``size`` >= 1 scales the trials.
        quick_size: the size of ``--quick`` (a few minutes at most for all together).
        full_size: the size of the full run (the one quoted in README).
        tiny_size: the size a test uses.
    """

    name: str
    run: Callable[[int], ExperimentResult]
    quick_size: int
    full_size: int
    tiny_size: int = 1


#: every experiment of the report, in report order (filled by the experiment modules)
EXPERIMENTS: list[Experiment] = []

#: report order: the papers by their name prefix (then registration order)
PAPER_ORDER = ("pmp_", "force_", "body_schema_")


def _order(e: Experiment) -> int:
    return next((i for i, p in enumerate(PAPER_ORDER) if e.name.startswith(p)), len(PAPER_ORDER))


def experiment(name: str, quick: int, full: int, tiny: int = 1):
    """Decorator registering ``run(size)`` under ``name``."""

    def register(run: Callable[[int], ExperimentResult]):
        if any(e.name == name for e in EXPERIMENTS):
            raise InvalidInput(f"experiment {name!r} registered twice")
        EXPERIMENTS.append(Experiment(name, run, quick, full, tiny))
        EXPERIMENTS.sort(key=_order)  # stable: registration order within a paper
        return run

    return register


def find(name: str) -> Experiment:
    """The registered experiment ``name`` (UnknownName lists the valid ones)."""
    for e in EXPERIMENTS:
        if e.name == name:
            return e
    raise UnknownName("experiment", name, [e.name for e in EXPERIMENTS])


def run_experiment(exp: Experiment, size: int) -> ExperimentResult:
    """Run ``exp`` at ``size``; the result carries its wall time."""
    if int(size) < 1:
        raise InvalidInput(f"size: expected >= 1, got {size}")
    t0 = time.perf_counter()
    result = exp.run(int(size))
    return dataclasses.replace(result, seconds=time.perf_counter() - t0)
