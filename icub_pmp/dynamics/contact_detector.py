"""ContactDetector: a contact flag per hand from the estimated external force, with hysteresis.

Under the paper's hypothesis (Fig. 4b) contacts happen only at the end effectors, so a contact
is declared when the estimated external force at the hand exceeds ``force_on`` [N] for
``min_samples`` consecutive samples, and released when it falls below ``force_off`` [N]
(``force_off < force_on``) for as many samples.
"""

from __future__ import annotations

import math

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["ContactDetector"]


class ContactDetector:
    """Hysteresis switch on the norm of a force (3,) [N]."""

    def __init__(self, force_on: float, force_off: float, min_samples: int = 1):
        if not (np.isfinite(force_on) and np.isfinite(force_off) and 0 <= force_off < force_on):
            raise InvalidInput(
                f"ContactDetector: need 0 <= force_off < force_on, got force_off={force_off}, "
                f"force_on={force_on}"
            )
        if min_samples < 1:
            raise InvalidInput(f"ContactDetector: min_samples must be >= 1, got {min_samples}")
        self.force_on = float(force_on)
        self.force_off = float(force_off)
        self.min_samples = int(min_samples)
        self.in_contact = False
        self._count = 0

    def reset(self) -> None:
        """Back to 'no contact'."""
        self.in_contact = False
        self._count = 0

    def update(self, force: np.ndarray) -> bool:
        """Feed the force (3,) [N] of one sample; returns the contact flag."""
        fx, fy, fz = force  # three scalars: cheaper than a numpy norm at 1 kHz
        f = math.hypot(fx, fy, fz)
        switching = f < self.force_off if self.in_contact else f > self.force_on
        self._count = self._count + 1 if switching else 0
        if self._count >= self.min_samples:
            self.in_contact = not self.in_contact
            self._count = 0
        return self.in_contact
