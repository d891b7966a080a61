"""The body-schema paper's rows (Bhat, Mohan 2018): the learned body model when
``icub_pmp.body_schema`` exists, and the peripersonal-space GNG map (icub_pmp.peripersonal)."""

from __future__ import annotations

import importlib.util

import numpy as np

from icub_pmp.paper.experiment_result import Curve, ExperimentResult, FigureData, Measurement
from icub_pmp.paper.registry import experiment

__all__ = ["body_model_available"]

PAPER = "body schema"


def body_model_available() -> bool:
    """Whether the learned body model package (icub_pmp.body_schema) is installed."""
    return importlib.util.find_spec("icub_pmp.body_schema") is not None


@experiment("body_schema_model_rmse", quick=1, full=1, tiny=1)
def body_model_rmse(size: int) -> ExperimentResult:
    """The learned body model's forward-kinematics error on held-out babbling (pinocchio FK as
    ground truth): 'not yet implemented' until icub_pmp.body_schema lands."""
    claim = "Body schema learned from motor babbling: hand position error of the learned model."
    reports = ("babbling to learn the forward model (6 inputs, hidden layers of 32 and 41 "
               "neurons); the error is shown in a figure, not a number")
    if not body_model_available():
        return ExperimentResult.not_implemented(
            "body_schema_model_rmse", PAPER, "Sect. 'body schema'", claim, reports,
            "icub_pmp.body_schema (the learned body model) has not landed; this row turns on "
            "when it exists")
    return ExperimentResult.not_implemented(
        "body_schema_model_rmse", PAPER, "Sect. 'body schema'", claim, reports,
        "icub_pmp.body_schema exists but its training API is not wired into the report yet")


@experiment("body_schema_gng_map", quick=3000, full=40000, tiny=400)
def gng_map(size: int) -> ExperimentResult:
    """GNG peripersonal map of the right arm (paper's constants, config defaults) grown from
    ``size`` analytic babbles (seed 1); coverage = fraction of held-out babbles (seed 2,
    same count) within 2 cm of a neuron, quantisation error = their mean distance."""
    from icub_pmp.peripersonal.analytic_babbling import analytic_babbling
    from icub_pmp.peripersonal.growing_neural_gas import GrowingNeuralGas

    size = max(size, 50)
    train = analytic_babbling("right", size, 1).hand
    held = analytic_babbling("right", max(size // 2, 100), 2).hand
    gng = GrowingNeuralGas(label=f"right:{size}:1")
    rep = gng.fit(train)
    cover = gng.coverage(held, 0.02)
    qerr = gng.quantisation_error(held)
    ok = cover >= 0.9
    verdict = (f"{rep.neurons} neurons from {size} babbles cover {cover:.1%} of held-out hand "
               f"positions within 2 cm (mean quantisation error {qerr * 1e3:.1f} mm); the paper "
               "gives the map only as a figure" + ("" if size >= 10000 else
                                                  "; fewer babbles than the paper's 10,000"))
    added = np.cumsum(rep.added)
    return ExperimentResult(
        "body_schema_gng_map", PAPER, "Fig 3 (GNG of the workspace)",
        "A sparse GNG map of the peripersonal space grows from motor babbling.",
        "'the robot babbled to about 10,000 locations in its workspace area before settling to "
        "a sparse representation'; vigilance v = 0.25, e_w = 0.04, e_n = 0.0006",
        (Measurement.of("held-out coverage within 2 cm [fraction]", [cover]),
         Measurement.of("GNG neurons [-]", [rep.neurons]),
         Measurement.of("quantisation error [mm]", [qerr * 1e3])),
        "reproduced" if ok else "differs", verdict,
        (FigureData("GNG growth", "pass over the babbling", "neurons",
                    (Curve("neurons (before pruning)", np.arange(1, added.size + 1), added),)),),
    )
