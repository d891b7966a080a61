"""SegmentationCounts: pixel confusion counts -> precision, recall, F1 (benchmark metrics)."""

from __future__ import annotations

import dataclasses

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["SegmentationCounts"]


@dataclasses.dataclass
class SegmentationCounts:
    """Accumulated true/false positives and false negatives over frames [pixels]."""

    tp: int = 0
    fp: int = 0
    fn: int = 0

    def add(self, predicted: np.ndarray, truth: np.ndarray, roi: np.ndarray | None = None) -> None:
        """Add one frame: (H, W) bool predicted and true masks, optional (H, W) bool region."""
        p = np.asarray(predicted, bool)
        t = np.asarray(truth, bool)
        if p.shape != t.shape or (roi is not None and np.shape(roi) != t.shape):
            raise InvalidInput(
                f"mask shapes differ: predicted {p.shape}, truth {t.shape}, "
                f"roi {None if roi is None else np.shape(roi)}"
            )
        if roi is not None:
            p = p & roi
            t = t & roi
        self.tp += int(np.count_nonzero(p & t))
        self.fp += int(np.count_nonzero(p & ~t))
        self.fn += int(np.count_nonzero(~p & t))

    def __iadd__(self, other: "SegmentationCounts") -> "SegmentationCounts":
        self.tp += other.tp
        self.fp += other.fp
        self.fn += other.fn
        return self

    @property
    def precision(self) -> float:
        """tp / (tp + fp); 0 when nothing was predicted."""
        return self.tp / (self.tp + self.fp) if self.tp + self.fp else 0.0

    @property
    def recall(self) -> float:
        """tp / (tp + fn); 0 when there was nothing to find."""
        return self.tp / (self.tp + self.fn) if self.tp + self.fn else 0.0

    @property
    def f1(self) -> float:
        """Harmonic mean of precision and recall (0 when both are 0)."""
        p, r = self.precision, self.recall
        return 2 * p * r / (p + r) if p + r else 0.0
