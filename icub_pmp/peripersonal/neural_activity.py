"""Neural activity of a peripersonal map for a scene (Bhat and Mohan 2018, "Localization of
an empty area in the workspace").

In response to an input S (an object's 3-D centroid), neuron i fires
``x_i = exp(-||s_i - S||^2 / 2 sigma_s^2) / (sqrt(2 pi) sigma_s)``; a scene of several objects
gives the sum over the objects. The empty-area search counts only the objects within a
threshold distance T of the neuron (the paper's ``x_i = sum_T ...``).
"""

from __future__ import annotations

import math

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["neural_activity"]


def neural_activity(neurons: np.ndarray, objects: np.ndarray, sigma_s: float,
                    threshold: float | None = None) -> np.ndarray:
    """Activity (N,) [1/m] of neurons (N, 3) [m] for objects (m, 3) [m].

    Args:
        neurons: sensory weights s_i (N, 3) [m].
        objects: object centroids S_j (m, 3) [m], same frame; m = 0 gives zero activity.
        sigma_s: kernel width [m] (> 0).
        threshold: if given, object j contributes to neuron i only when
            ``||s_i - S_j|| < threshold`` [m] (the empty-area search).
    """
    if not (math.isfinite(sigma_s) and sigma_s > 0):
        raise InvalidInput(f"sigma_s: expected a width > 0 m, got {sigma_s}")
    if threshold is not None and not (math.isfinite(threshold) and threshold > 0):
        raise InvalidInput(f"threshold: expected a distance > 0 m, got {threshold}")
    if len(objects) == 0:
        return np.zeros(len(neurons))
    d2 = np.sum((neurons[:, None, :] - objects[None, :, :]) ** 2, axis=2)  # (N, m)
    x = np.exp(-d2 / (2.0 * sigma_s ** 2)) / (math.sqrt(2.0 * math.pi) * sigma_s)
    if threshold is not None:
        x = np.where(d2 < threshold ** 2, x, 0.0)
    return x.sum(axis=1)
