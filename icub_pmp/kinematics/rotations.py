"""Rotation helpers shared by the cores and the adapters: validation of vectors and rotation
matrices, the angle between two rotations, and unit quaternions (w, x, y, z) <-> matrices."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = [
    "as_vector",
    "as_rotation",
    "rotation_angle",
    "quat_wxyz_to_matrix",
    "matrix_to_quat_wxyz",
]


def as_vector(v: object, n: int, name: str) -> np.ndarray:
    """``v`` as a finite float vector (n,); raises InvalidInput naming ``name``."""
    try:
        a = np.asarray(v, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidInput(f"{name}: expected {n} numbers, got {v!r}") from None
    if a.shape != (n,):
        raise InvalidInput(f"{name}: expected {n} values, got {a.size}")
    if not np.all(np.isfinite(a)):
        raise InvalidInput(f"{name}: contains NaN or infinite values: {a.tolist()}")
    return a


def as_rotation(R: object) -> np.ndarray:
    """``R`` as a rotation matrix (3, 3) (orthonormal to 1e-6, det > 0); raises InvalidInput."""
    try:
        R = np.asarray(R, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput(f"rotation: expected a 3x3 matrix, got {R!r}") from None
    if R.shape != (3, 3) or not np.all(np.isfinite(R)):
        raise InvalidInput(f"rotation: expected a finite 3x3 matrix, got shape {R.shape}")
    if np.abs(R.T @ R - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0:
        raise InvalidInput("rotation: not a rotation matrix (R^T R != I or det < 0)")
    return R


def rotation_angle(R_a: np.ndarray, R_b: np.ndarray) -> float:
    """Angle [rad] of the rotation between two rotation matrices (0 .. pi)."""
    c = (float(np.trace(np.asarray(R_a).T @ np.asarray(R_b))) - 1.0) / 2.0
    return math.acos(min(1.0, max(-1.0, c)))


def quat_wxyz_to_matrix(q: Sequence[float]) -> np.ndarray:
    """Unit quaternion (w, x, y, z) -> rotation matrix (3, 3)."""
    w, x, y, z = (float(v) for v in q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_to_quat_wxyz(R: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) -> unit quaternion (w, x, y, z) with w >= 0."""
    R = np.asarray(R, dtype=float)
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2]) * 2
        q = [(R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s]
    elif R[1, 1] > R[2, 2]:
        s = math.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2]) * 2
        q = [(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s]
    else:
        s = math.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1]) * 2
        q = [(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s]
    qa = np.array(q)
    qa /= np.linalg.norm(qa)
    return -qa if qa[0] < 0 else qa
