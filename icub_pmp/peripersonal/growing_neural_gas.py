"""GrowingNeuralGas: the internal model of an arm's peripersonal space (Bhat and Mohan 2018).

The map is learned from the hand positions S_t (n, 3) [m, root_link] of the motor babbling
that also trains the body model, with the paper's steps (a)-(g) ("Acquisition of the
peripersonal representation"; Fritzke 1995 for the lateral connections):

(a) start with one neuron with random sensory weights;
(b) take the next babbled position S_t;
(c) the winner i minimises ||s_i - S_t||; the second best k is found too;
(d) the winner's error is low-pass filtered,
    ``tau_e d(error_i)/dt = -error_i + (1 - K(||s_i - S_t||))``, and when
    ``error_i > v`` a neuron j is added with s_j = S_t;
(e) ``s_i <- s_i + e_w (S_t - s_i)``, ``s_n <- s_n + e_n (S_t - s_n)`` for the neighbours n;
(f) the lateral connection i-k is created (or refreshed) with age 0, the winner's other
    connections age by one, those older than ``age_max`` are removed;
(g) dead neurons (no lateral connection left) are removed.

Interpretations the paper's text leaves open (stated here, checked by the tests):

- Kernel: the paper writes ``K(d) = exp(-d^2 / 2 sigma_e^2) / (sqrt(2 pi) sigma_e)``. With
  sigma_e = 1 that kernel never exceeds 0.40, so the error's fixed point never drops below
  0.60 > v = 0.25 and every input would add a neuron. We use the peak-normalised kernel
  ``K(d) = exp(-d^2 / 2 sigma_e^2)`` (K(0) = 1: no error for a perfect match).
- Units: distances enter the kernel in units of ``length_scale`` [m] (the paper does not
  give its unit). A neuron that keeps winning inputs at distance d grows a new one when
  ``1 - K(d) > v``, i.e. beyond ``d* = sigma_e sqrt(-2 ln(1 - v)) length_scale``
  (0.76 length_scale): ``length_scale`` sets the map's resolution and size.
- Time: one input is one time unit (Euler step dt = 1 of the filter); only the winner's
  error is filtered (the equation names S_i, the winner's weights).
- Growth: the new neuron starts with error 0, is connected to the winner (age 0), and the
  winner's error is reset to 0, so one large error adds one neuron, not one per input.
- Neighbour rule: the paper prints ``e_n (S - s_i)`` for the neighbours; we use Fritzke's
  ``e_n (S - s_n)`` (each neuron moves toward the input).
- "Successive best winning neurons" are the best and second-best neurons of one input
  (Fritzke's rule): babbled positions are independent, so consecutive winners in time are
  not neighbours in space.
- Training passes over the data until a pass adds fewer than ``min_growth`` times the map
  size (the paper's "quasi stationary" map) or ``max_epochs`` passes.
- Pruning never removes the last two neurons; a neuron is dead only once its last
  connection has aged out (a newborn is connected to its parent).

After training: :meth:`nearest`, :meth:`coverage`, :meth:`quantisation_error`; maps are
saved and loaded as ``.npz`` (:meth:`save`, :meth:`load`).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import NamedTuple

import numpy as np

from icub_pmp.errors import InvalidInput, ModelError
from icub_pmp.peripersonal.exceptions import MapNotTrained
from icub_pmp.peripersonal.gng_config import GrowingNeuralGasConfig

__all__ = ["GrowingNeuralGas", "GngTrainingReport", "as_points"]

_FAR = 1.0e150  # squared distance of removed neurons (never a winner)
_FORMAT = "icub_pmp.peripersonal.GrowingNeuralGas/1"


def as_points(points: object, name: str = "points", dim: int = 3) -> np.ndarray:
    """``points`` as a float (m, dim) array: a single (dim,) point becomes (1, dim). Raises
    :class:`InvalidInput` naming ``name`` on a wrong shape or NaN/inf values."""
    try:
        a = np.array(points, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput(f"{name}: expected numbers of shape (m, {dim}), got {points!r}"
                           ) from None
    if a.ndim == 1 and a.size == dim:
        a = a.reshape(1, dim)
    if a.ndim != 2 or a.shape[1] != dim:
        raise InvalidInput(f"{name}: expected shape (m, {dim}) [m], got {a.shape}")
    bad = ~np.all(np.isfinite(a), axis=1)
    if bad.any():
        raise InvalidInput(f"{name}: row(s) {np.flatnonzero(bad)[:10].tolist()} contain NaN "
                           f"or infinite values")
    return a


class GngTrainingReport(NamedTuple):
    """What one :meth:`GrowingNeuralGas.fit` did."""

    neurons: int  # map size at the end
    edges: int  # lateral connections at the end
    epochs: int  # passes over the data
    inputs: int  # inputs presented (epochs x samples)
    added: tuple[int, ...]  # neurons added per pass
    removed: tuple[int, ...]  # dead neurons removed per pass


class GrowingNeuralGas:
    """A growing neural gas over 3-D hand positions (module doc).

    Args:
        config: the constants (default: the paper's, :class:`GrowingNeuralGasConfig`).
        label: free text saved with the map (e.g. the arm, ``"left"``).
    """

    def __init__(self, config: GrowingNeuralGasConfig | None = None, label: str = ""):
        self.config = config or GrowingNeuralGasConfig()
        self.label = str(label)
        self._neurons = np.zeros((0, 3))  # [m]
        self._errors = np.zeros(0)
        self._edges = np.zeros((0, 2), dtype=int)
        self._ages = np.zeros(0, dtype=int)
        self._tree = None
        self.report: GngTrainingReport | None = None

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_neurons(cls, neurons: object, edges: object = (), label: str = "",
                     config: GrowingNeuralGasConfig | None = None) -> "GrowingNeuralGas":
        """A map with given neurons (N, 3) [m] and lateral connections (E, 2) (indices)."""
        gng = cls(config, label)
        pts = as_points(neurons, "neurons")
        e = np.array(edges, dtype=int).reshape(-1, 2) if len(edges) else np.zeros((0, 2), int)
        if e.size and (e.min() < 0 or e.max() >= len(pts) or np.any(e[:, 0] == e[:, 1])):
            raise InvalidInput(f"edges: need pairs of distinct indices in [0, {len(pts)}), "
                               f"got {e.tolist()[:5]}...")
        gng._set(pts, np.zeros(len(pts)), np.sort(e, axis=1), np.zeros(len(e), dtype=int))
        return gng

    def _set(self, neurons: np.ndarray, errors: np.ndarray, edges: np.ndarray,
             ages: np.ndarray) -> None:
        for a in (neurons, errors, edges, ages):
            a.setflags(write=False)
        self._neurons, self._errors, self._edges, self._ages = neurons, errors, edges, ages
        self._tree = None

    # ------------------------------------------------------------------ state
    @property
    def trained(self) -> bool:
        """Whether the map has neurons (trained, loaded or given)."""
        return len(self._neurons) > 0

    @property
    def size(self) -> int:
        """Number of neurons N."""
        return len(self._neurons)

    @property
    def neurons(self) -> np.ndarray:
        """Sensory weights s_i (N, 3) [m] in the babbling frame (root_link), read-only."""
        return self._neurons

    @property
    def errors(self) -> np.ndarray:
        """Filtered representational errors (N,) [-], read-only."""
        return self._errors

    @property
    def edges(self) -> np.ndarray:
        """Lateral connections (E, 2) as neuron index pairs (i < j), read-only."""
        return self._edges

    @property
    def edge_ages(self) -> np.ndarray:
        """Ages (E,) of :attr:`edges` [inputs], read-only."""
        return self._ages

    def require_trained(self) -> None:
        """Raise :class:`MapNotTrained` when the map is empty."""
        if not self.trained:
            what = f" of {self.label}" if self.label else ""
            raise MapNotTrained(f"the peripersonal map{what} has no neurons: train it (fit) or "
                                f"load a saved map first")

    # ------------------------------------------------------------------ training
    def fit(self, points: object) -> GngTrainingReport:
        """Grow the map on babbled hand positions ``points`` (n, 3) [m] (steps a-g, module
        doc), from scratch. Returns (and keeps in :attr:`report`) what happened."""
        data = as_points(points, "points")
        if len(data) < 2:
            raise InvalidInput(f"points: need at least 2 babbled positions, got {len(data)}")
        c = self.config
        rng = np.random.default_rng(c.seed)
        x_all = data / c.length_scale  # kernel units
        cap = min(c.max_neurons, max(64, len(data) // 4))
        pos = np.full((cap, 3), np.sqrt(_FAR / 3.0))
        err = np.zeros(cap)
        alive = np.zeros(cap, dtype=bool)
        nbrs: list[dict[int, int]] = [dict() for _ in range(cap)]
        free: list[int] = []
        lo, hi = data.min(axis=0) / c.length_scale, data.max(axis=0) / c.length_scale
        pos[0] = rng.uniform(lo, hi)  # (a) one neuron, random weights
        alive[0] = True
        top, n_alive = 1, 1
        inv_tau, v, e_w, e_n = 1.0 / c.tau_e, c.vigilance, c.e_w, c.e_n
        two_s2 = 2.0 * c.sigma_e ** 2
        age_max = c.age_max
        added_per, removed_per = [], []
        epochs = 0
        for _ in range(c.max_epochs):
            epochs += 1
            added = removed = 0
            for x in x_all[rng.permutation(len(x_all))]:  # (b)
                d2 = pos[:top] - x
                d2 = np.einsum("ij,ij->i", d2, d2)
                i = int(np.argmin(d2))  # (c)
                di2 = d2[i]
                k = -1
                if n_alive > 1:
                    d2[i] = np.inf
                    k = int(np.argmin(d2))
                # (d) error low-pass (dt = 1 input), growth above the vigilance
                err[i] += inv_tau * (1.0 - np.exp(-di2 / two_s2) - err[i])
                if err[i] > v and n_alive < c.max_neurons:
                    if free:
                        j = free.pop()
                    else:
                        if top == cap:
                            cap = min(c.max_neurons, 2 * cap)
                            pos = np.vstack([pos, np.full((cap - top, 3), np.sqrt(_FAR / 3))])
                            err = np.concatenate([err, np.zeros(cap - top)])
                            alive = np.concatenate([alive, np.zeros(cap - top, dtype=bool)])
                            nbrs.extend(dict() for _ in range(cap - top))
                        j = top
                        top += 1
                    pos[j] = x
                    err[j] = 0.0
                    err[i] = 0.0
                    alive[j] = True
                    n_alive += 1
                    added += 1
                    nbrs[j] = {i: 0}
                    nbrs[i][j] = 0
                # (e) adapt the winner and its topological neighbours
                pos[i] += e_w * (x - pos[i])
                ni = nbrs[i]
                for n in ni:
                    pos[n] += e_n * (x - pos[n])
                # (f) age the winner's connections, connect winner and second best
                for n in ni:
                    ni[n] += 1
                    nbrs[n][i] = ni[n]
                if k >= 0:
                    ni[k] = 0
                    nbrs[k][i] = 0
                old = [n for n, a in ni.items() if a > age_max]
                for n in old:
                    del ni[n]
                    del nbrs[n][i]
                    # (g) a neuron left without connections is dead
                    if not nbrs[n] and n_alive > 2:
                        alive[n] = False
                        pos[n] = np.sqrt(_FAR / 3.0)
                        err[n] = 0.0
                        free.append(n)
                        n_alive -= 1
                        removed += 1
            added_per.append(added)
            removed_per.append(removed)
            if added < c.min_growth * n_alive:
                break
        # compact: renumber the living neurons, keep the connections and their ages
        idx = np.flatnonzero(alive[:top])
        new_of = np.full(top, -1, dtype=int)
        new_of[idx] = np.arange(len(idx))
        edges, ages = [], []
        for a in idx:
            for b, age in nbrs[a].items():
                if a < b:
                    edges.append((new_of[a], new_of[b]))
                    ages.append(age)
        e = np.array(edges, dtype=int).reshape(-1, 2)
        self._set(pos[idx] * c.length_scale, err[idx].copy(), np.sort(e, axis=1),
                  np.array(ages, dtype=int))
        self.report = GngTrainingReport(len(idx), len(e), epochs, epochs * len(data),
                                        tuple(added_per), tuple(removed_per))
        return self.report

    # ------------------------------------------------------------------ queries
    def _kdtree(self):
        self.require_trained()
        if self._tree is None:
            from scipy.spatial import cKDTree

            self._tree = cKDTree(self._neurons)
        return self._tree

    def nearest(self, points: object) -> tuple[np.ndarray, np.ndarray]:
        """Best-matching neuron of each point (m, 3) [m]: (indices (m,), distances (m,) [m])."""
        pts = as_points(points)
        dist, idx = self._kdtree().query(pts)
        return np.asarray(idx, dtype=int), np.asarray(dist, dtype=float)

    def within(self, points: object, radius: float) -> list[list[int]]:
        """Indices of the neurons within ``radius`` [m] of each point (m lists)."""
        if not np.isfinite(radius) or radius < 0:
            raise InvalidInput(f"radius: expected a finite distance >= 0 m, got {radius}")
        return self._kdtree().query_ball_point(as_points(points), radius)

    def coverage(self, points: object, radius: float = 0.02) -> float:
        """Fraction of ``points`` (m, 3) [m] within ``radius`` [m] of a neuron."""
        if not np.isfinite(radius) or radius <= 0:
            raise InvalidInput(f"radius: expected a finite distance > 0 m, got {radius}")
        _, d = self.nearest(points)
        return float(np.mean(d <= radius))

    def quantisation_error(self, points: object) -> float:
        """Mean distance [m] from ``points`` (m, 3) to their best-matching neurons."""
        _, d = self.nearest(points)
        return float(np.mean(d))

    def neighbours(self, i: int) -> np.ndarray:
        """Neurons laterally connected to neuron ``i``."""
        self.require_trained()
        if not 0 <= int(i) < self.size:
            raise InvalidInput(f"neuron index: expected 0..{self.size - 1}, got {i}")
        e = self._edges
        return np.sort(np.concatenate([e[e[:, 0] == i, 1], e[e[:, 1] == i, 0]]))

    # ------------------------------------------------------------------ persistence
    def save(self, path: str | Path) -> Path:
        """Write the map to ``path`` (.npz): neurons [m], connections, ages, errors, config."""
        self.require_trained()
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_suffix(".npz")
        path.parent.mkdir(parents=True, exist_ok=True)
        meta = {"format": _FORMAT, "label": self.label, "frame": "root_link", "units": "m",
                "config": dataclasses.asdict(self.config),
                "report": self.report._asdict() if self.report else None}
        np.savez(path, neurons=self._neurons, edges=self._edges, edge_ages=self._ages,
                 errors=self._errors, meta=np.array(json.dumps(meta)))
        return path

    @classmethod
    def load(cls, path: str | Path) -> "GrowingNeuralGas":
        """Read a map written by :meth:`save` (raises :class:`ModelError` when the file is
        missing, unreadable or not such a map)."""
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as f:
                meta = json.loads(str(f["meta"]))
                if meta.get("format") != _FORMAT:
                    raise ModelError(f"{path}: not a peripersonal map (format "
                                     f"{meta.get('format')!r}, expected {_FORMAT!r})")
                config = GrowingNeuralGasConfig.from_dict(meta["config"])
                gng = cls.from_neurons(f["neurons"], f["edges"], meta.get("label", ""), config)
                errors = np.array(f["errors"], dtype=float)
                ages = np.array(f["edge_ages"], dtype=int)
        except ModelError:
            raise
        except (OSError, KeyError, ValueError, TypeError) as exc:
            raise ModelError(f"cannot load the peripersonal map {path}: {exc}") from exc
        if errors.shape != (gng.size,) or ages.shape != (len(gng.edges),):
            raise ModelError(f"{path}: errors/edge_ages do not match the neurons/edges")
        gng._set(gng._neurons, errors, gng._edges, ages)
        rep = meta.get("report")
        if rep:
            gng.report = GngTrainingReport(**{k: tuple(v) if isinstance(v, list) else v
                                              for k, v in rep.items()})
        return gng
