"""TbgTiming: puts the relaxation's nodes on the TBG's clock (Sect. 2.4, eq 7, Appendix A).

Two parametrisations of the same relaxation path:

``"gamma"`` (eq 7 / 4a literally): the state at time t is the relaxation's state at
``s(t) = -ln(1 - xi(t))`` (piecewise-linear between nodes). Appendix A: a network whose
relaxation rate is gamma then moves as ``z = z0 (1 - xi)^gamma``: the target is reached at
tau, but a rate gamma != 1 distorts the bell (gamma > 1 early, gamma < 1 late), and the slow
directions of an ill-conditioned J A J^T (rates two orders of magnitude apart on the iCub)
are completed only in the last instants before tau.

``"progress"`` (default): Appendix A with gamma normalised to 1, i.e. the time-varying gain
``Gamma(t) / gamma_eff(s)``, where ``gamma_eff = -d ln(1 - p) / ds`` is the network's own
relative rate of progress p along its extrinsic path. Then ``p(t) = xi(t)`` exactly: the
extrinsic path (hands, orientation scaled by a length) is travelled with the minimum-jerk
profile of the TBG, bell-shaped with its peak at tau/2, the same for every distance, ending at
tau (each hand's own profile is bell-shaped to the extent the hands progress alike in s).
p is the mean over the hands of each hand's travelled fraction of its own path length
(orientation changes counted as length), monotone by construction, so hands with paths of
different lengths keep pace in relative terms.
Null-space motion with no extrinsic motion (the settling of Sect. 2.3) is timed by its
joint-space length scaled by the reach's own hand-length per joint-length ratio, so it gets
time in proportion to how much the joints move.

``joint_floor`` > 0 (an extension, decision 0061): every segment counts at least that fraction
of its joint-space length (scaled by the same hand-per-joint ratio of the whole path) as
extrinsic length. Near the edge of the workspace the relaxation's last nodes turn a joint
(``shoulder_yaw``) a long way while the hand moves a millimetre; by hand progress alone they
get almost no time, the joint would spin at several rad/s and the joint rate limits stretch
the whole reach several-fold. The floor gives those segments time; segments where the hand
moves in proportion to the joints keep their minimum-jerk timing (0 = off, the paper's).

Both map ``t = tau`` to the equilibrium (the last node), never evaluating the divergent Gamma.
"""

from __future__ import annotations

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.pmp.time_base_generator import TimeBaseGenerator

__all__ = ["TbgTiming"]


def _segment_lengths(points: np.ndarray) -> np.ndarray:
    """Lengths (N-1,) of the polyline through ``points`` (N, d)."""
    return np.linalg.norm(np.diff(points, axis=0), axis=1)


def _rotation_angles(rotations: np.ndarray) -> np.ndarray:
    """(N-1, k) angle [rad] between successive rotations (N, k, 3, 3) of each frame."""
    rel = np.einsum("nkij,nkil->nkjl", rotations[:-1], rotations[1:])  # R_n^T R_n+1
    cos = np.clip((np.trace(rel, axis1=2, axis2=3) - 1.0) / 2.0, -1.0, 1.0)
    return np.arccos(cos)


class TbgTiming:
    """Maps relaxation nodes onto sample times of a TBG of duration ``tbg.tau``."""

    def __init__(self, tbg: TimeBaseGenerator, mode: str = "progress",
                 rotation_length_scale: float = 0.1, joint_floor: float = 0.0):
        if mode not in ("progress", "gamma"):
            raise InvalidInput(f"time parametrisation {mode!r}; valid: ['gamma', 'progress']")
        if not np.isfinite(joint_floor) or joint_floor < 0:
            raise InvalidInput(f"joint_floor: expected a finite value >= 0, got {joint_floor}")
        self.tbg = tbg
        self.mode = mode
        self.rotation_length_scale = float(rotation_length_scale)
        self.joint_floor = float(joint_floor)

    def progress(
        self,
        hand_positions: np.ndarray,
        hand_rotations: np.ndarray,
        joints: np.ndarray,
        null_space: np.ndarray | None = None,
        use_rotation: bool = False,
    ) -> np.ndarray:
        """Cumulative progress (N,) in [0, 1] at the nodes.

        Args:
            hand_positions: (N, k, 3) [m]. hand_rotations: (N, k, 3, 3).
            joints: (N, n) [rad]. null_space: (N-1,) bool, segments of null-space settling.
            use_rotation: count orientation changes (scaled by ``rotation_length_scale``).
        """
        n_nodes = len(joints)
        if n_nodes < 2:
            return np.ones(n_nodes)
        d = np.linalg.norm(np.diff(hand_positions, axis=0), axis=2)  # (N-1, k)
        if use_rotation:
            d = d + self.rotation_length_scale * _rotation_angles(hand_rotations)
        dq = _segment_lengths(joints)
        if null_space is not None and np.any(null_space):
            reach = ~null_space
            ratio = d[reach].sum(axis=0) / dq[reach].sum() if dq[reach].sum() > 0 else 1.0
            d = np.where(null_space[:, None], d + ratio * dq[:, None], d)
        totals = d.sum(axis=0)  # (k,) path length of each hand
        moving = totals > 1e-9
        if not np.any(moving):  # no extrinsic motion: time the joint-space path instead
            total = dq.sum()
            if total <= 1e-12:
                return np.linspace(0.0, 1.0, n_nodes)  # nothing moves at all
            return np.concatenate([[0.0], np.cumsum(dq) / total])
        if self.joint_floor > 0 and dq.sum() > 0:  # joint motion the hands barely show
            ratio = totals[moving] / dq.sum()
            d = d[:, moving]
            d = np.maximum(d, self.joint_floor * ratio[None, :] * dq[:, None])
            totals, moving = d.sum(axis=0), np.ones(d.shape[1], dtype=bool)
        # mean over the moving hands of each hand's own travelled fraction
        frac = np.cumsum(d[:, moving], axis=0) / totals[moving]
        p = np.concatenate([[0.0], frac.mean(axis=1)])
        p[-1] = 1.0
        return p

    def locate(self, times: np.ndarray, s_nodes: np.ndarray, progress: np.ndarray):
        """For each time, the node segment index k (M,) and fraction phi in [0, 1] (M,):
        the state is ``z_k + phi (z_k+1 - z_k)``."""
        n = len(s_nodes)
        if n < 2:
            return np.zeros(len(times), dtype=int), np.zeros(len(times))
        if self.mode == "gamma":
            key, axis = self.tbg.relaxation_time(times), s_nodes
        else:
            key, axis = self.tbg.xi(times), progress
        key = np.minimum(key, axis[-1])
        k = np.clip(np.searchsorted(axis, key, side="right") - 1, 0, n - 2)
        span = axis[k + 1] - axis[k]
        with np.errstate(divide="ignore", invalid="ignore"):
            phi = np.where(span > 0, (key - axis[k]) / span, 1.0)
        return k, np.clip(phi, 0.0, 1.0)

    @staticmethod
    def interpolate(values: np.ndarray, k: np.ndarray, phi: np.ndarray) -> np.ndarray:
        """Piecewise-linear node values (N, ...) at (k, phi) -> (M, ...)."""
        shape = (-1,) + (1,) * (values.ndim - 1)
        return values[k] + phi.reshape(shape) * (values[k + 1] - values[k])

    @staticmethod
    def interpolate_smooth(
        values: np.ndarray, axis: np.ndarray, k: np.ndarray, phi: np.ndarray
    ) -> np.ndarray:
        """C1 cubic Hermite interpolation of node values (N, d) over the node parameter
        ``axis`` (N,) (progress or s) at (k, phi) -> (M, d); tangents by central differences
        in ``axis`` (Catmull-Rom on a non-uniform grid), zero across empty segments. Smooth
        speeds where the piecewise-linear path has corners at the nodes."""
        n = len(axis)
        if n < 3:
            return TbgTiming.interpolate(values, k, phi)
        idx_prev = np.maximum(np.arange(n) - 1, 0)
        idx_next = np.minimum(np.arange(n) + 1, n - 1)
        span = axis[idx_next] - axis[idx_prev]
        with np.errstate(divide="ignore", invalid="ignore"):
            tang = np.where(span[:, None] > 0,
                            (values[idx_next] - values[idx_prev]) / span[:, None], 0.0)
        h = (axis[k + 1] - axis[k])[:, None]
        f = phi[:, None]
        f2, f3 = f * f, f * f * f
        return ((2 * f3 - 3 * f2 + 1) * values[k] + (f3 - 2 * f2 + f) * h * tang[k]
                + (-2 * f3 + 3 * f2) * values[k + 1] + (f3 - f2) * h * tang[k + 1])
