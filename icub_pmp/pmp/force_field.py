"""ForceField: the target-centred virtual force field in the extrinsic space (eq 1).

    F = K_ext (x_T - x)                                   (eq 1 of Mohan et al. 2009)

``K_ext`` is the virtual stiffness [N/m]: isotropic (a scalar), anisotropic (3 eigenvalues,
or any symmetric positive semi-definite 3x3 matrix). The paper notes that "more complex curved
trajectories can be obtained by adding a rotational component to the convergent force field":
``curl * n x (x_T - x)`` rotates the flowlines about the axis ``n`` without moving the
equilibrium (it vanishes at ``x = x_T``).
"""

from __future__ import annotations

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["ForceField"]


def _skew(n: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]])


def _vector3(name: str, value) -> np.ndarray:
    v = np.array(value, dtype=float).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise InvalidInput(f"{name}: expected 3 finite numbers, got {value!r}")
    return v


class ForceField:
    """Attractive field toward ``target`` (3,) [m]; force in [N], stiffness in [N/m]."""

    def __init__(self, target, stiffness=1000.0, curl: float = 0.0, curl_axis=(0.0, 0.0, 1.0)):
        self.target = _vector3("target", target)
        self.target.setflags(write=False)
        k = np.array(stiffness, dtype=float)
        if k.ndim == 0:
            k = np.eye(3) * float(k)
        elif k.shape == (3,):
            k = np.diag(k)
        if k.shape != (3, 3) or not np.all(np.isfinite(k)):
            raise InvalidInput(f"stiffness: expected a scalar, 3 values or 3x3, got {stiffness!r}")
        if np.abs(k - k.T).max() > 1e-9 * max(1.0, np.abs(k).max()):
            raise InvalidInput("stiffness: the 3x3 matrix must be symmetric")
        if np.linalg.eigvalsh(k).min() < 0.0 or not np.any(k):
            raise InvalidInput(f"stiffness: must be positive semi-definite and non-zero, got {k}")
        if not np.isfinite(curl):
            raise InvalidInput(f"curl: expected a finite gain, got {curl}")
        axis = _vector3("curl_axis", curl_axis)
        norm = np.linalg.norm(axis)
        if curl != 0.0 and norm == 0.0:
            raise InvalidInput("curl_axis: must be non-zero when curl != 0")
        self.curl = float(curl)
        self._k = k
        # -dF/dx: the field's own stiffness, used by the implicit relaxation step
        self._k_total = k + (self.curl * _skew(axis / norm) if self.curl else 0.0)
        self._k.setflags(write=False)
        self._k_total.setflags(write=False)

    def retarget(self, target) -> "ForceField":
        """The same field (stiffness, curl) centred on another ``target`` (3,) [m]."""
        field = object.__new__(ForceField)
        field.__dict__.update(self.__dict__)
        field.target = _vector3("target", target)
        field.target.setflags(write=False)
        return field

    @property
    def stiffness_matrix(self) -> np.ndarray:
        """K_ext (3, 3) [N/m] (symmetric part, without the rotational component)."""
        return self._k

    @property
    def jacobian(self) -> np.ndarray:
        """-dF/dx (3, 3) [N/m]: K_ext plus the (skew) rotational component."""
        return self._k_total

    def force(self, x) -> np.ndarray:
        """F(x) (3,) [N] at hand position ``x`` (3,) [m] (eq 1, plus the curl term)."""
        return self._k_total @ (self.target - np.asarray(x, dtype=float))

    def potential(self, x) -> float:
        """Elastic energy 1/2 (x_T - x)^T K_ext (x_T - x) [J] (the curl term has none)."""
        e = self.target - np.asarray(x, dtype=float)
        return 0.5 * float(e @ self._k @ e)
