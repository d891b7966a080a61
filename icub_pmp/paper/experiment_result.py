"""ExperimentResult: one row of the paper report (the paper's number beside ours)."""

from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["ExperimentResult", "Measurement", "FigureData", "Curve", "STATUSES"]

#: verdict categories of a row
STATUSES = ("reproduced", "differs", "not yet implemented")


@dataclasses.dataclass(frozen=True)
class Measurement:
    """What we measured: mean, spread (sample standard deviation) and number of trials.

    Attributes:
        quantity: what is measured, with its unit in brackets (e.g. 'residual at tau [mm]').
        mean: mean over the trials (NaN when nothing was measured).
        spread: sample standard deviation over the trials (0 for a single trial).
        n: number of trials.
    """

    quantity: str
    mean: float
    spread: float
    n: int

    @classmethod
    def of(cls, quantity: str, values: Sequence[float]) -> "Measurement":
        """Mean, sample std and count of ``values`` (NaN mean when empty)."""
        a = np.asarray(values, dtype=float).reshape(-1)
        if a.size == 0:
            return cls(quantity, math.nan, math.nan, 0)
        spread = float(np.std(a, ddof=1)) if a.size > 1 else 0.0
        return cls(quantity, float(np.mean(a)), spread, int(a.size))

    def text(self) -> str:
        """'mean +- spread (n = N)' with 4 significant digits, or 'not measured'."""
        if self.n == 0:
            return "not measured"
        return f"{self.mean:.4g} ± {self.spread:.2g} (n = {self.n})"


@dataclasses.dataclass(frozen=True)
class Curve:
    """One line of a figure: label, x (k,), y (k,)."""

    label: str
    x: np.ndarray
    y: np.ndarray

    def __post_init__(self) -> None:
        x = np.array(self.x, dtype=float).reshape(-1)
        y = np.array(self.y, dtype=float).reshape(-1)
        if x.shape != y.shape:
            raise InvalidInput(f"curve {self.label!r}: x has {x.size} points, y has {y.size}")
        x.setflags(write=False)
        y.setflags(write=False)
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)


@dataclasses.dataclass(frozen=True)
class FigureData:
    """The data of one figure panel; the report writer draws it (PNG) and saves it (CSV)."""

    title: str
    xlabel: str
    ylabel: str
    curves: tuple[Curve, ...]
    log_y: bool = False


@dataclasses.dataclass(frozen=True)
class ExperimentResult:
    """One experiment of the report.

    Attributes:
        name: registry name (``--only NAME``).
        paper: which paper ('PMP', 'force', 'body schema').
        reference: the paper's figure / table / section ('Fig 2').
        claim: what the experiment checks, one line.
        paper_reports: what the paper reports (quoted).
        measured: our figures (the first is the headline).
        status: one of :data:`STATUSES`.
        verdict: one line: reproduced / differs, and why.
        figures: figure data drawn by the report writer.
        seconds: wall time of the run [s] (set by the runner).
    """

    name: str
    paper: str
    reference: str
    claim: str
    paper_reports: str
    measured: tuple[Measurement, ...]
    status: str
    verdict: str
    figures: tuple[FigureData, ...] = ()
    seconds: float = 0.0

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise InvalidInput(f"status: expected one of {STATUSES}, got {self.status!r}")
        object.__setattr__(self, "measured", tuple(self.measured))
        object.__setattr__(self, "figures", tuple(self.figures))

    @classmethod
    def not_implemented(cls, name: str, paper: str, reference: str, claim: str,
                        paper_reports: str, why: str) -> "ExperimentResult":
        """A row for an experiment that cannot run yet (``why`` says what is missing)."""
        return cls(name, paper, reference, claim, paper_reports, (), "not yet implemented", why)
