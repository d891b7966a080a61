"""RandomFeaturesRidge: incremental random-features ridge regression (RFRR^D, Sect. 3.1).

Gijsberts & Metta's incremental learner of the internal dynamics, as summarised in Sect. 3.1 of
the force-control paper: a Gaussian (RBF) kernel ``k(x, y) = exp(-|x - y|^2 / (2 sigma^2))`` is
approximated by ``D`` random Fourier features (Rahimi & Recht 2007)

    phi(x) = sqrt(2 / D) * cos(Omega x + b),   Omega ~ N(0, I / sigma^2),  b ~ U(0, 2 pi),

and the ridge regression ``y = W^T phi(x)`` is solved incrementally by recursive least squares:
with ``P = (lambda I + sum phi phi^T)^-1`` (D, D), each sample costs O(D^2):

    k = P phi / (beta + phi^T P phi);   W += k (y - W^T phi)^T;   P = (P - k phi^T P) / beta

(``beta`` = forgetting factor, 1 = plain ridge). Inputs are divided by ``input_scale`` before
the features.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["RandomFeaturesRidge"]


class RandomFeaturesRidge:
    """RFRR with ``n_features`` = D random features, ``n_inputs`` -> ``n_outputs``.

    ``bandwidth`` = sigma of the RBF kernel (in scaled input units), ``ridge`` = lambda,
    ``forgetting`` = beta in (0, 1], ``seed`` fixes Omega and b.
    """

    def __init__(
        self,
        n_inputs: int,
        n_outputs: int,
        n_features: int = 200,
        bandwidth: float = 1.0,
        ridge: float = 1e-3,
        forgetting: float = 1.0,
        input_scale: Sequence[float] | float = 1.0,
        seed: int = 0,
    ):
        if n_inputs < 1 or n_outputs < 1 or n_features < 1:
            raise InvalidInput(
                f"RandomFeaturesRidge: n_inputs, n_outputs, n_features must be >= 1, got "
                f"{n_inputs}, {n_outputs}, {n_features}"
            )
        if not (bandwidth > 0 and ridge > 0 and 0 < forgetting <= 1):
            raise InvalidInput(
                f"RandomFeaturesRidge: need bandwidth > 0, ridge > 0, 0 < forgetting <= 1; got "
                f"{bandwidth}, {ridge}, {forgetting}"
            )
        scale = np.broadcast_to(np.asarray(input_scale, dtype=float), (n_inputs,)).copy()
        if not np.all(scale > 0):
            raise InvalidInput("RandomFeaturesRidge: input_scale must be > 0")
        self.n_inputs = n_inputs
        self.n_outputs = n_outputs
        self.n_features = n_features
        self.bandwidth = float(bandwidth)
        self.ridge = float(ridge)
        self.forgetting = float(forgetting)
        rng = np.random.default_rng(seed)
        # fold the input scaling into Omega: Omega' = Omega / scale
        self._omega = rng.normal(0.0, 1.0 / bandwidth, (n_features, n_inputs)) / scale
        self._b = rng.uniform(0.0, 2.0 * math.pi, n_features)
        self._c = math.sqrt(2.0 / n_features)
        self.reset()

    def reset(self) -> None:
        """Forget everything learnt (W = 0, P = I / lambda)."""
        self._w = np.zeros((self.n_features, self.n_outputs))
        self._p = np.eye(self.n_features) / self.ridge
        self.n_samples = 0

    def features(self, x: np.ndarray) -> np.ndarray:
        """Random Fourier features phi(x) (D,) of one input (n_inputs,)."""
        return self._c * np.cos(self._omega @ x + self._b)

    def _check(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if x.shape != (self.n_inputs,) or not np.all(np.isfinite(x)):
            raise InvalidInput(
                f"RandomFeaturesRidge: input must be {self.n_inputs} finite values, "
                f"got shape {x.shape}"
            )
        return x

    def predict(self, x: np.ndarray) -> np.ndarray:
        """Prediction (n_outputs,) for one input (n_inputs,)."""
        return self.features(self._check(x)) @ self._w

    def update(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """One RLS step with sample (x, y); returns the prediction made *before* the update."""
        phi = self.features(self._check(x))
        y = np.asarray(y, dtype=float)
        if y.shape != (self.n_outputs,) or not np.all(np.isfinite(y)):
            raise InvalidInput(
                f"RandomFeaturesRidge: target must be {self.n_outputs} finite values, "
                f"got shape {y.shape}"
            )
        pphi = self._p @ phi
        k = pphi / (self.forgetting + phi @ pphi)
        pred = phi @ self._w
        self._w += np.outer(k, y - pred)
        # P is symmetric: P - k (P phi)^T keeps it so up to round-off
        self._p -= np.outer(k, pphi)
        if self.forgetting != 1.0:
            self._p /= self.forgetting
        self.n_samples += 1
        return pred

    def fit_batch(self, xs: np.ndarray, ys: np.ndarray) -> None:
        """The exact ridge solution on a batch (N, n_inputs) -> (N, n_outputs), replacing the
        current state (equal to N calls of :meth:`update` from scratch, with beta = 1)."""
        xs = np.asarray(xs, dtype=float)
        ys = np.asarray(ys, dtype=float)
        phi = self._c * np.cos(xs @ self._omega.T + self._b)
        a = phi.T @ phi + self.ridge * np.eye(self.n_features)
        self._p = np.linalg.inv(a)
        self._w = self._p @ (phi.T @ ys)
        self.n_samples = len(xs)
