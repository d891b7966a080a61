"""LoomingDetector: objects approaching or receding, from the ego-motion residual of LK tracks.

An addition to motionCUT (Sect. 5 of Metta et al., eq. 13), not part of it. Eq. 13 compares
frame t with frame t+1 only; an 8 cm ball approaching at 10 cm/s 0.47 m away expands its
outline by about 0.2 px per frame at 30 Hz, so its patches match from one frame to the next
and no node fails. Its divergent flow does accumulate: over ten frames the nodes on the ball
have drifted 1-2 px away from where the ego-motion would have carried them.

Per grid node the residual ``r = v - v_ego`` of its LK flow ``v`` to the ego-motion flow
``v_ego`` (the segmenter's RANSAC homography) is clipped to ``accum_clip`` and accumulated
along the node's track with exponential forgetting,

    R_t(q) = r_t(q) + accum_decay * R_{t-1}(track of q),

the sum being carried forward to where each track lands (bilinear splat onto the grid; nodes
reached by no reliable track start again from zero, so the background uncovered behind an
object carries no history). Accumulated residuals of at least ``accum_tol`` px group into
8-connected components. Motion parallax gives such components too: the eyes sit off the neck
axes, so under head rotation anything off the homography's dominant plane (an object standing
on the table, a depth edge) drifts consistently, but as a near-uniform translation of the
component. A component is therefore reported only when the least-squares fit

    R(p) = t + a (p - c) + w perp(p - c)        (c: the component's centroid)

has an expansion ``|a| * rho`` (rho: rms distance of its nodes from c [px]) of at least
``loom_tol`` px: the component grows or shrinks in the image, i.e. the object approaches or
recedes. Independent translation parallel to the image is left to eq. 13.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["LoomingDetector", "expansion"]


def expansion(points: np.ndarray, residuals: np.ndarray) -> float:
    """Expansion of a residual field: ``|a| * rho`` of the fit ``R = t + a d + w perp(d)``.

    Args:
        points: (M, 2) node positions [px], M >= 3.
        residuals: (M, 2) accumulated residuals at the nodes [px].

    Returns:
        |a| times the rms distance of the points from their centroid [px]: the mean radial
        displacement the expansion (a > 0) or contraction (a < 0) explains.
    """
    p = np.asarray(points, np.float64)
    d = p - p.mean(axis=0)
    m = len(p)
    a = np.zeros((2 * m, 4))
    a[0::2, 0] = 1.0
    a[1::2, 1] = 1.0
    a[0::2, 2] = d[:, 0]
    a[1::2, 2] = d[:, 1]
    a[0::2, 3] = -d[:, 1]
    a[1::2, 3] = d[:, 0]
    x, *_ = np.linalg.lstsq(a, np.asarray(residuals, np.float64).ravel(), rcond=None)
    return float(abs(x[2]) * np.sqrt((d * d).sum(axis=1).mean()))


class LoomingDetector:
    """Accumulated ego-motion residuals on a fixed grid and their expanding components.

    Args:
        nodes: (N, 2) grid node positions (u, v) [px], row-major over ``grid_shape``.
        grid_shape: (rows, cols) with rows * cols = N.
        grid_step: node spacing [px].
        decay: weight of the accumulated residual carried to the next frame, in [0, 1).
        clip: largest per-frame residual counted [px/frame].
        tol: accumulated residual marking a candidate node [px].
        loom_tol: expansion a component needs [px] (module doc).
        min_nodes: components of at most this many nodes are ignored.
    """

    def __init__(self, nodes: np.ndarray, grid_shape: tuple[int, int], grid_step: int,
                 decay: float, clip: float, tol: float, loom_tol: float, min_nodes: int,
                 fill_hull: bool = True):
        self.nodes = np.asarray(nodes, np.float32)
        self.grid_shape = grid_shape
        self.origin = self.nodes[0].astype(np.float64)
        self.step = float(grid_step)
        self.decay, self.clip, self.tol = decay, clip, tol
        self.loom_tol, self.min_nodes = loom_tol, min_nodes
        self.fill_hull = fill_hull
        self.reset()

    def reset(self) -> None:
        """Forget the accumulated residuals."""
        self.accumulated = np.zeros((self.nodes.shape[0], 2), np.float32)

    def update(self, flow: np.ndarray, ego_flow: np.ndarray | None, reliable: np.ndarray
               ) -> np.ndarray:
        """Add one frame; return the (rows, cols) bool grid of nodes in expanding components.

        Args:
            flow: (rows, cols, 2) LK flow of the nodes from frame t to t+1 [px] (NaN: lost).
            ego_flow: (rows, cols, 2) ego-motion flow at the nodes [px], None when it could
                not be estimated (the accumulation restarts).
            reliable: (rows, cols) bool, nodes whose flow is trusted (tracked, textured, no
                eq. 13 failure); the others carry no residual and end their track.

        The result refers to the nodes' grid positions in frame t (as eq. 13's failures).
        """
        rows, cols = self.grid_shape
        if ego_flow is None:
            self.reset()
            return np.zeros(self.grid_shape, bool)
        ok = np.asarray(reliable, bool).ravel() & np.isfinite(flow).all(axis=2).ravel()
        v = np.nan_to_num(flow).reshape(-1, 2).astype(np.float32)
        r = v - ego_flow.reshape(-1, 2).astype(np.float32)
        norm = np.linalg.norm(r, axis=1, keepdims=True)
        r *= np.minimum(1.0, self.clip / np.maximum(norm, 1e-9))
        total = r + self.decay * self.accumulated
        total[~ok] = 0.0
        self.accumulated = self._carry(total, v, ok)
        cand = ok.reshape(rows, cols) & (np.linalg.norm(total, axis=1) >= self.tol).reshape(
            rows, cols)
        cand[0, :] = cand[-1, :] = cand[:, 0] = cand[:, -1] = False
        out = np.zeros(self.grid_shape, bool)
        if not cand.any():
            return out
        n, labels, stats, _ = cv2.connectedComponentsWithStats(
            cand.astype(np.uint8), connectivity=8)
        flat = labels.ravel()
        for k in range(1, n):
            if stats[k, cv2.CC_STAT_AREA] <= self.min_nodes:
                continue
            idx = np.nonzero(flat == k)[0]
            if expansion(self.nodes[idx], total[idx]) >= self.loom_tol:
                if self.fill_hull:
                    rr, cc = np.divmod(idx, cols)
                    hull = cv2.convexHull(np.stack([cc, rr], 1).astype(np.int32))
                    filled = np.zeros(self.grid_shape, np.uint8)
                    cv2.fillConvexPoly(filled, hull, 1)
                    out |= filled.astype(bool)
                else:
                    out |= labels == k
        return out

    def _carry(self, total: np.ndarray, v: np.ndarray, ok: np.ndarray) -> np.ndarray:
        """Splat each reliable node's ``total`` to where its track lands (``p + v``), bilinear
        weights on the grid; nodes that receive less than a quarter of a track start at 0."""
        rows, cols = self.grid_shape
        n = rows * cols
        g = (self.nodes + v - self.origin) / self.step
        i0 = np.floor(g).astype(np.intp)
        f = g - i0
        w_sum = np.zeros(n + 1)
        acc = np.zeros((n + 1, 2))
        for dx, dy in ((0, 0), (1, 0), (0, 1), (1, 1)):
            x, y = i0[:, 0] + dx, i0[:, 1] + dy
            w = (f[:, 0] if dx else 1.0 - f[:, 0]) * (f[:, 1] if dy else 1.0 - f[:, 1])
            inside = ok & (x >= 0) & (x < cols) & (y >= 0) & (y < rows)
            idx = np.where(inside, y * cols + x, n)
            w_sum += np.bincount(idx, w, n + 1)
            acc[:, 0] += np.bincount(idx, w * total[:, 0], n + 1)
            acc[:, 1] += np.bincount(idx, w * total[:, 1], n + 1)
        w_sum = w_sum[:n, None]
        return np.where(w_sum > 0.25, acc[:n] / np.maximum(w_sum, 1e-9), 0.0).astype(np.float32)
