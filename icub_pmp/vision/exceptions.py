"""Errors of the vision cores (subclasses of the project's hierarchy)."""

from __future__ import annotations

from icub_pmp.errors import IcubPmpError

__all__ = ["ObjectNotFound"]


class ObjectNotFound(IcubPmpError):
    """The stereo pair shows no measurable object where it was looked for.

    Attributes:
        reason: short machine-readable cause (``empty_seed``, ``no_support``, ``no_object``,
            ``image_border``, ``too_few_points``, ``too_far``).
    """

    def __init__(self, reason: str, message: str):
        super().__init__(message)
        self.reason = reason
