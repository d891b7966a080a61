"""Errors of the peripersonal-space models (subclasses of the project's hierarchy)."""

from __future__ import annotations

from icub_pmp.errors import ModelError, PlanningError

__all__ = ["MapNotTrained", "NoEmptyArea"]


class MapNotTrained(ModelError):
    """A peripersonal map was used before it was trained or loaded."""


class NoEmptyArea(PlanningError):
    """No neuron of the shared workspace is clear of the objects.

    Attributes:
        best_clearance: the largest distance from a candidate neuron to its nearest object
            [m] (what the scene offers), or 0 when there is no candidate at all.
        required: the clearance that was asked for [m].
    """

    def __init__(self, message: str, best_clearance: float, required: float):
        super().__init__(message)
        self.best_clearance = best_clearance
        self.required = required
