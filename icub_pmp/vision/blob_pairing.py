"""BlobPairing: which motion blob of the left eye is the same object as which of the right eye.

Largest-blob-per-eye is not enough: each eye may see another object moving (a hand in one
view, the object cut by the other's border). In the rectified pair
(:class:`~icub_pmp.vision.stereo_rectification.StereoRectification`) a scene point lies on the
same row of both images, so two blobs of one object must:

- lie on the same rows (epipolar consistency): rectified centroid rows within
  ``pair_max_row_offset`` and row ranges overlapping by ``pair_min_row_overlap``;
- be in front of the cameras within the depth range: the centroid disparity between those of
  ``max_depth`` and ``min_depth`` (with the blobs' half width as slack);
- have similar sizes (node counts within ``pair_max_size_ratio``: both eyes are about as far
  from the object);
- move together (timing): between the same two frames the object moves by the same number of
  rectified rows in both eyes (rectified vertical flows within ``pair_max_flow_offset``).

Pairs are chosen one-to-one, the largest consistent blobs first.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from icub_pmp.vision.motion_blobs import MotionBlob, MotionBlobs
from icub_pmp.vision.stereo_rectification import StereoRectification
from icub_pmp.vision.stereo_target_config import StereoTargetConfig

__all__ = ["BlobPairing", "BlobPair"]


@dataclasses.dataclass(frozen=True)
class BlobPair:
    """Two blobs judged to be one object.

    Attributes:
        left: index of the blob in the left frame's ``blobs``.
        right: index in the right frame's ``blobs``.
        row_offset: difference of the rectified centroid rows [px].
        disparity: difference of the rectified centroid columns [px].
        size: total node count of the two blobs.
    """

    left: int
    right: int
    row_offset: float
    disparity: float
    size: int


class BlobPairing:
    """Pair the two eyes' motion blobs (module doc)."""

    def __init__(self, config: StereoTargetConfig | None = None):
        self.config = config or StereoTargetConfig()

    def check(self, left: MotionBlob, right: MotionBlob, rect: StereoRectification) -> str:
        """Why ``left`` and ``right`` cannot be one object ('' when they can)."""
        c = self.config
        cl = rect.to_rectified(np.array([left.centroid]), "left")[0]
        cr = rect.to_rectified(np.array([right.centroid]), "right")[0]
        dv = float(cl[1] - cr[1])
        if abs(dv) > c.pair_max_row_offset:
            return (f"epipolar: rectified rows differ by {dv:.1f} px "
                    f"(> pair_max_row_offset {c.pair_max_row_offset})")
        rl, rr = _rows(left, rect, "left"), _rows(right, rect, "right")
        inter = min(rl[1], rr[1]) - max(rl[0], rr[0])
        shorter = max(min(rl[1] - rl[0], rr[1] - rr[0]), 1.0)
        if inter / shorter < c.pair_min_row_overlap:
            return (f"epipolar: row ranges overlap {max(inter, 0.0) / shorter:.2f} of the "
                    f"shorter (< pair_min_row_overlap {c.pair_min_row_overlap})")
        disp = float(cl[0] - cr[0])
        slack = 0.5 * max(left.bbox[2] - left.bbox[0], right.bbox[2] - right.bbox[0])
        lo, hi = rect.disparity_at(c.max_depth) - slack, rect.disparity_at(c.min_depth) + slack
        if not lo <= disp <= hi:
            return f"depth: disparity {disp:.1f} px outside [{lo:.1f}, {hi:.1f}]"
        ratio = max(left.size, right.size) / max(min(left.size, right.size), 1)
        if ratio > c.pair_max_size_ratio:
            return (f"size: {left.size} vs {right.size} nodes (ratio {ratio:.2f} > "
                    f"pair_max_size_ratio {c.pair_max_size_ratio})")
        fl = rect.rectified_flow(np.array([left.centroid]), np.array([left.mean_flow]), "left")
        fr = rect.rectified_flow(np.array([right.centroid]), np.array([right.mean_flow]), "right")
        df = float(fl[0, 1] - fr[0, 1])
        if abs(df) > c.pair_max_flow_offset:
            return (f"timing: the blobs move by {fl[0, 1]:.1f} and {fr[0, 1]:.1f} rectified rows "
                    f"per frame (differ by > pair_max_flow_offset {c.pair_max_flow_offset})")
        return ""

    def pair(self, left: MotionBlobs, right: MotionBlobs, rect: StereoRectification
             ) -> tuple[BlobPair, ...]:
        """The consistent pairs, one-to-one, largest first."""
        cands = []
        for i, bl in enumerate(left.blobs):
            for j, br in enumerate(right.blobs):
                if self.check(bl, br, rect):
                    continue
                cl = rect.to_rectified(np.array([bl.centroid]), "left")[0]
                cr = rect.to_rectified(np.array([br.centroid]), "right")[0]
                cands.append(BlobPair(i, j, float(cl[1] - cr[1]), float(cl[0] - cr[0]),
                                      bl.size + br.size))
        cands.sort(key=lambda p: (-p.size, abs(p.row_offset)))
        used_l: set[int] = set()
        used_r: set[int] = set()
        out = []
        for p in cands:
            if p.left in used_l or p.right in used_r:
                continue
            used_l.add(p.left)
            used_r.add(p.right)
            out.append(p)
        return tuple(out)


def _rows(blob: MotionBlob, rect: StereoRectification, side: str) -> tuple[float, float]:
    """Rectified row range of a blob's bounding box."""
    u0, v0, u1, v1 = blob.bbox
    corners = np.array([[u0, v0], [u1, v0], [u0, v1], [u1, v1]], dtype=float)
    r = rect.to_rectified(corners, side)[:, 1]
    return float(r.min()), float(r.max())
