"""ReportWriter: report.md with the paper's numbers beside ours, PNG figures and their CSV data."""

from __future__ import annotations

import csv
import re
from pathlib import Path
from typing import Sequence

from icub_pmp.paper.experiment_result import ExperimentResult, FigureData

__all__ = ["REPORT_COLUMNS", "write_report", "report_table"]

#: the columns of the report's table
REPORT_COLUMNS = ("Experiment", "Paper", "Figure/table", "Paper reports", "We measure",
                  "Verdict")


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def report_table(results: Sequence[ExperimentResult]) -> str:
    """The Markdown table of the report (one row per experiment, :data:`REPORT_COLUMNS`)."""
    lines = ["| " + " | ".join(REPORT_COLUMNS) + " |",
             "|" + "---|" * len(REPORT_COLUMNS)]
    for r in results:
        measured = "; ".join(f"{m.quantity}: {m.text()}" for m in r.measured) or "-"
        verdict = f"**{r.status}**: {r.verdict}"
        lines.append("| " + " | ".join(_cell(c) for c in (
            r.name, r.paper, r.reference, r.paper_reports, measured, verdict)) + " |")
    return "\n".join(lines)


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "_", text.lower()).strip("_")[:60]


def _save_figure(fig: FigureData, stem: Path) -> list[Path]:
    """CSV of the curves (always) and a PNG drawn with matplotlib (Agg)."""
    out = [stem.with_suffix(".csv")]
    with out[0].open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["curve", fig.xlabel, fig.ylabel])
        for c in fig.curves:
            for x, y in zip(c.x, c.y):
                w.writerow([c.label, f"{x:.9g}", f"{y:.9g}"])
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    f, ax = plt.subplots(figsize=(6, 4))
    for c in fig.curves:
        ax.plot(c.x, c.y, marker="." if c.x.size < 30 else None, label=c.label)
    ax.set(title=fig.title, xlabel=fig.xlabel, ylabel=fig.ylabel)
    if fig.log_y:
        ax.set_yscale("log")
    if len(fig.curves) > 1:
        ax.legend(fontsize=7)
    f.tight_layout()
    png = stem.with_suffix(".png")
    f.savefig(png, dpi=100)
    plt.close(f)
    out.append(png)
    return out


def write_report(results: Sequence[ExperimentResult], directory: str | Path,
                 header: str = "") -> Path:
    """Write ``directory``/report.md (table + one section per experiment with its figures)
    and the figures (PNG + CSV); returns the report's path."""
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    parts = ["# The papers' results, reproduced side by side", ""]
    if header:
        parts += [header, ""]
    counts = {s: sum(r.status == s for r in results)
              for s in ("reproduced", "differs", "not yet implemented")}
    parts += [", ".join(f"{n} {s}" for s, n in counts.items()) + ".", "",
              report_table(results), ""]
    for r in results:
        parts += [f"## {r.name}: {r.paper} paper, {r.reference}", "", r.claim, "",
                  f"- paper: {r.paper_reports}"]
        parts += [f"- {m.quantity}: {m.text()}" for m in r.measured]
        parts += [f"- verdict ({r.status}): {r.verdict}", f"- run time: {r.seconds:.1f} s", ""]
        for k, fig in enumerate(r.figures):
            files = _save_figure(fig, d / f"{r.name}_{k}_{_slug(fig.title)}")
            parts += [f"![{fig.title}]({files[-1].name}) (data: {files[0].name})", ""]
    path = d / "report.md"
    path.write_text("\n".join(parts))
    return path
