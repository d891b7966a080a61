"""The papers' results reproduced side by side (issue 21): experiments as plain functions
``run(size) -> ExperimentResult`` in a registry, and a report writer. No ROS imports."""

from icub_pmp.paper import (  # noqa: F401 (they register their experiments)
    body_schema_experiments,
    force_experiments,
    motion_experiments,
    pmp_experiments,
)
from icub_pmp.paper.experiment_result import (
    STATUSES,
    Curve,
    ExperimentResult,
    FigureData,
    Measurement,
)
from icub_pmp.paper.registry import EXPERIMENTS, Experiment, experiment, find, run_experiment
from icub_pmp.paper.report_writer import REPORT_COLUMNS, report_table, write_report

__all__ = [
    "Curve",
    "EXPERIMENTS",
    "Experiment",
    "ExperimentResult",
    "FigureData",
    "Measurement",
    "REPORT_COLUMNS",
    "STATUSES",
    "experiment",
    "find",
    "report_table",
    "run_experiment",
    "write_report",
]
