"""MotionBlob / MotionBlobs: the typed result of one segmenter step (motionCUT output)."""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["MotionBlob", "MotionBlobs"]


@dataclasses.dataclass(frozen=True)
class MotionBlob:
    """One blob of independently moving grid nodes (8-connected on the grid).

    Attributes:
        centroid: mean image position of the blob's nodes (u = column, v = row) [px].
        size: number of grid nodes in the blob.
        area: image area the blob's node cells cover (size * grid_step**2) [px^2].
        bbox: (u_min, v_min, u_max, v_max) of the node cells, inclusive [px].
        mean_flow: mean LK flow (du, dv) of the blob's nodes over the last frame [px/frame].
    """

    centroid: tuple[float, float]
    size: int
    area: int
    bbox: tuple[int, int, int, int]
    mean_flow: tuple[float, float]


@dataclasses.dataclass(frozen=True)
class MotionBlobs:
    """Result of :meth:`MotionSegmenter.process` for one frame.

    Attributes:
        frame_index: index of the processed frame (0 = first frame, which has no flow).
        blobs: blobs sorted by decreasing size (largest first); empty when nothing moves.
        mask: (H, W) uint8 image, 255 on the cells of the blobs' nodes, else 0.
        failures: (rows, cols) bool grid, raw tracking failures of eq. 13 this frame.
        active: (rows, cols) bool grid, nodes ON after neighbour filter and persistence.
        flow: (rows, cols, 2) float32 LK flow of each node [px/frame] (NaN when not found).
        discrepancy: (rows, cols) float32 ``M(p) / |W|`` of eq. 13 [grey level^2].
    """

    frame_index: int
    blobs: tuple[MotionBlob, ...]
    mask: np.ndarray
    failures: np.ndarray
    active: np.ndarray
    flow: np.ndarray
    discrepancy: np.ndarray

    def __post_init__(self) -> None:
        for name in ("mask", "failures", "active", "flow", "discrepancy"):
            a = np.array(getattr(self, name), copy=True)
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    @property
    def has_motion(self) -> bool:
        """True when at least one blob survived the filters."""
        return len(self.blobs) > 0

    @property
    def largest(self) -> MotionBlob:
        """The largest blob; raises ``IndexError`` when there is none (check ``has_motion``)."""
        if not self.blobs:
            raise IndexError("no motion blob in this frame")
        return self.blobs[0]
