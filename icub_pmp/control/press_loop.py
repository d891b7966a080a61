"""press_loop: an outer force loop for a hand held by joint springs pressing on a surface.

A position-mode hand exerts a force through a target beyond the contact (``x_contact + C F``,
:mod:`icub_pmp.control.hand_compliance`). The loop corrects the target from the measured
force, ``x <- x + C (F_target - F_measured)``, and refines ``C`` from the measured force
changes (Broyden's secant update), as a force loop closed on the FT sensors does on the iCub.
What the model leaves out (friction at the contact, the hand turning about it, the estimate's
noise) makes single secants wrong, sometimes by an order of magnitude or in sign; so the loop
is guarded as one on the real robot would be (docs/decisions/0069):

- a secant is accepted only if its compliance along the force change lies within a factor
  ``secant_ratio`` of the model's (else the model is kept: the press slipped or the
  estimate was noise);
- one correction moves the target at most ``max_step``;
- a press much worse than the best so far is not built on: the next correction starts from
  the best press (the loop returns to it);
- :attr:`PressLoop.best` is the press to end on when the last one is not the best.

No ROS.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["PressLoop", "PressLoopConfig", "PressRecord", "robust_secant_update"]


@dataclass
class PressLoopConfig:
    """Guards of the force loop (see the module docstring)."""

    #: stop once the force error is within this fraction of the target's magnitude
    stop_tolerance: float = 0.04
    #: the largest move of the target in one correction [m]
    max_step: float = 0.004
    #: a secant's compliance along the force change must lie within [1/r, r] x the model's
    secant_ratio: float = 3.0
    #: force changes smaller than this [N] are not used to fit the compliance
    min_change: float = 0.3
    #: a press whose error exceeds this factor x the best error (and the stop tolerance)
    #: counts as diverged: the next correction starts from the best press
    diverged_factor: float = 2.0

    def __post_init__(self) -> None:
        for name in ("stop_tolerance", "max_step", "min_change"):
            v = getattr(self, name)
            if not np.isfinite(v) or v <= 0:
                raise InvalidInput(f"PressLoopConfig.{name}: expected a finite value > 0, got {v}")
        for name in ("secant_ratio", "diverged_factor"):
            v = getattr(self, name)
            if not np.isfinite(v) or v < 1:
                raise InvalidInput(f"PressLoopConfig.{name}: expected a finite value >= 1, "
                                   f"got {v}")


@dataclass(eq=False)
class PressRecord:
    """One press: the target [m], the measured force exerted [N], its relative error."""

    target: np.ndarray
    exerted: np.ndarray
    error: float
    #: index of the press this one's target was corrected from (-1: the first press)
    base: int = -1
    #: whether the secant from ``base`` to this press updated the compliance
    secant_accepted: bool = False


def robust_secant_update(C: np.ndarray, C_model: np.ndarray, dx: np.ndarray, dF: np.ndarray,
                         min_change: float = 0.3, ratio: float = 3.0
                         ) -> tuple[np.ndarray, bool]:
    """Broyden's update of the compliance ``C`` (3, 3) [m/N] from a target move ``dx`` (3,)
    [m] that changed the exerted force by ``dF`` (3,) [N], guarded by the model ``C_model``:
    rejected (``C`` returned unchanged, False) when the force changed by less than
    ``min_change`` [N], when a value is not finite, or when the secant's compliance along
    ``dF`` (``dx . dF / |dF|^2``) is outside ``[1/ratio, ratio]`` x the model's
    (``dF . C_model dF / |dF|^2``): a contact that slipped or stuck, or noise. Else the
    updated matrix (maps ``dF`` to ``dx`` exactly, unchanged across ``dF``) and True."""
    C = np.asarray(C, float)
    dx, dF = np.asarray(dx, float), np.asarray(dF, float)
    n2 = float(dF @ dF)
    if not (np.all(np.isfinite(dx)) and np.all(np.isfinite(dF))) or n2 < min_change**2:
        return C, False
    model = float(dF @ np.asarray(C_model, float) @ dF) / n2
    secant = float(dx @ dF) / n2
    if not (model > 0 and model / ratio <= secant <= model * ratio):
        return C, False
    return C + np.outer(dx - C @ dF, dF) / n2, True


@dataclass
class PressLoop:
    """The force loop's state: feed it each press's target and measured force
    (:meth:`record`), ask it where to press next (:meth:`next_target`).

    Args:
        force: (3,) the force the hand must exert [N] (non-zero).
        compliance: (3, 3) the model compliance [m/N] (e.g. ``J_h K^-1 J_c^T``).
        config: the guards.
    """

    force: np.ndarray
    compliance: np.ndarray
    config: PressLoopConfig = field(default_factory=PressLoopConfig)
    presses: list[PressRecord] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.force = np.asarray(self.force, float)
        self.compliance = np.asarray(self.compliance, float)
        if self.force.shape != (3,) or not np.all(np.isfinite(self.force)) \
                or not np.linalg.norm(self.force) > 0:
            raise InvalidInput(f"PressLoop: force must be a finite non-zero 3-vector, got "
                               f"{self.force.tolist()}")
        if self.compliance.shape != (3, 3) or not np.all(np.isfinite(self.compliance)):
            raise InvalidInput("PressLoop: compliance must be a finite 3x3 matrix")
        self.model = self.compliance.copy()
        self._base = -1

    def error(self, exerted: np.ndarray) -> float:
        """``|exerted - force| / |force|``."""
        return float(np.linalg.norm(np.asarray(exerted, float) - self.force)
                     / np.linalg.norm(self.force))

    def record(self, target: np.ndarray, exerted: np.ndarray) -> PressRecord:
        """Add the press just made at ``target`` (3,) [m] with the measured ``exerted``
        force (3,) [N]; fits the compliance to the change from the press it was corrected
        from (guarded by :func:`robust_secant_update`)."""
        target, exerted = np.asarray(target, float).copy(), np.asarray(exerted, float).copy()
        if target.shape != (3,) or exerted.shape != (3,):
            raise InvalidInput("PressLoop.record: target and exerted must be 3-vectors")
        rec = PressRecord(target, exerted, self.error(exerted), base=self._base)
        if self._base >= 0 and np.all(np.isfinite(exerted)):
            b = self.presses[self._base]
            self.compliance, rec.secant_accepted = robust_secant_update(
                self.compliance, self.model, target - b.target, exerted - b.exerted,
                self.config.min_change, self.config.secant_ratio)
        self.presses.append(rec)
        return rec

    @property
    def best(self) -> PressRecord:
        """The press with the smallest error so far."""
        if not self.presses:
            raise InvalidInput("PressLoop.best: no press recorded yet")
        return min(self.presses, key=lambda r: r.error)

    @property
    def done(self) -> bool:
        """The last press is within the stop tolerance."""
        return bool(self.presses) and self.presses[-1].error <= self.config.stop_tolerance

    def next_target(self) -> np.ndarray:
        """Where to press next: the last press corrected by ``C (F - F_measured)`` (at most
        ``max_step``), or the best one's when the last diverged from it or was not finite."""
        if not self.presses:
            raise InvalidInput("PressLoop.next_target: no press recorded yet")
        last, best = self.presses[-1], self.best
        diverged = (not np.isfinite(last.error)
                    or (last.error > self.config.stop_tolerance
                        and last.error > self.config.diverged_factor * best.error))
        base = best if diverged else last
        self._base = next(i for i, r in enumerate(self.presses) if r is base)
        step = self.compliance @ (self.force - base.exerted)
        n = float(np.linalg.norm(step))
        if n > self.config.max_step:
            step *= self.config.max_step / n
        return base.target + step
