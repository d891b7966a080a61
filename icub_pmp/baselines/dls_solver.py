"""DlsSolver: damped-least-squares inverse kinematics, the classical baseline of both papers.

The method the PMP paper contrasts itself with (Sect. 1: Nakamura & Hanafusa 1986, Wampler
1986; "DLS, also called the Levenberg-Marquardt method") and the "more conventional strategy"
the Cartesian solver is compared with (Sect. 4.1 of the reaching paper, there through Orocos
KDL): iterate

    dq = J^T (J J^T + mu^2 I)^-1 e,     q <- clip(q + dq, q_min, q_max)

on the stacked errors of k frames (position [m], plus the rotation vector [rad] of
``R_d R^T`` for the frames given a target orientation), each step bounded in norm, until every
frame is within the tolerances. It gives a final posture only (no timing, no trajectory) and
knows nothing of the shoulder constraints or of a rest posture. It runs on any
:class:`~icub_pmp.pmp.JacobianProvider` (the iCub URDF through pinocchio, or a learned body
schema).
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Sequence

import numpy as np
import pinocchio as pin

from icub_pmp.cartesian.kinematic_chain import KinematicChain
from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError, InvalidInput
from icub_pmp.kinematics.dls_step import damped_least_squares_step
from icub_pmp.kinematics.robot_spec import RobotSpec
from icub_pmp.kinematics.rotations import as_rotation, as_vector
from icub_pmp.pmp.jacobian_provider import JacobianProvider

__all__ = ["DlsConfig", "DlsResult", "DlsSolver", "PMP_DLS_CONFIG"]

_CONVERGED = "Solve_Succeeded"
_STALLED = "Stalled"
_MAX_ITER = "Maximum_Iterations_Exceeded"


@dataclasses.dataclass(frozen=True)
class DlsConfig(ConfigBase):
    """Attributes:
    damping: mu [m] (mixed units for a pose error, as in KDL).
    max_step: largest joint step norm per iteration [rad].
    max_iter: iteration limit.
    position_tolerance: stop when every frame is this close to its target [m].
    orientation_tolerance: and within this angle of its target orientation [rad].
    success_tolerance: verdict: success when every frame ends this close [m] (and within
        ``orientation_tolerance``); 0 = ``position_tolerance`` (success = converged).
    stall_iterations: stop after this many iterations without a 1 % improvement of the
        worst position error (0 = never).
    """

    damping: float = 0.02
    max_step: float = 0.2
    max_iter: int = 300
    position_tolerance: float = 5e-4
    orientation_tolerance: float = math.radians(0.5)
    success_tolerance: float = 0.0
    stall_iterations: int = 0

    def validate(self) -> None:
        """Check ranges."""
        for name in ("damping", "max_step", "position_tolerance", "orientation_tolerance"):
            v = getattr(self, name)
            if not (v > 0 and math.isfinite(v)):
                raise ConfigError(f"DlsConfig.{name} must be > 0, got {v!r}")
        if not (self.success_tolerance >= 0 and math.isfinite(self.success_tolerance)):
            raise ConfigError(
                f"DlsConfig.success_tolerance must be >= 0, got {self.success_tolerance!r}")
        if self.max_iter < 1:
            raise ConfigError(f"DlsConfig.max_iter must be >= 1, got {self.max_iter}")
        if self.stall_iterations < 0:
            raise ConfigError(
                f"DlsConfig.stall_iterations must be >= 0, got {self.stall_iterations}")


#: the settings of the PMP comparison (bimanual position targets, bench/pmp.py): a tight stop
#: [m], the 1 mm verdict of the PMP planner, long steps and a stall stop
PMP_DLS_CONFIG = DlsConfig(max_step=0.5, max_iter=200, position_tolerance=2e-5,
                           success_tolerance=1e-3, stall_iterations=20)


@dataclasses.dataclass(frozen=True)
class DlsResult:
    """Outcome of a DLS solve.

    Attributes:
        q: full configuration (nq,) [rad] in the provider's joint order.
        joint_names: the joints the solve moved; joint_positions: their values (n,) [rad].
        frames: the frames driven to their targets; positions: where they ended (k, 3) [m].
        position_errors: (k,) distances to the targets [m].
        orientation_errors: (k,) angles to the target orientations [rad] (NaN: none given).
        iterations: DLS steps taken. converged: the tolerances were met.
        success: the verdict (``success_tolerance``, see :class:`DlsConfig`).
        status: ``Solve_Succeeded``, ``Stalled`` or ``Maximum_Iterations_Exceeded``.
        solve_time: wall time of the iteration [s]. message: one line for a user.
    """

    q: np.ndarray
    joint_names: tuple[str, ...]
    joint_positions: np.ndarray
    frames: tuple[str, ...]
    positions: np.ndarray
    position_errors: np.ndarray
    orientation_errors: np.ndarray
    iterations: int
    converged: bool
    success: bool
    status: str
    solve_time: float
    message: str

    @property
    def position_error(self) -> float:
        """The largest position error [m]."""
        return float(self.position_errors.max())

    @property
    def orientation_error(self) -> float:
        """The largest orientation error [rad] (NaN when no orientation was asked)."""
        e = self.orientation_errors[np.isfinite(self.orientation_errors)]
        return float(e.max()) if e.size else math.nan


class DlsSolver:
    """DLS IK on ``provider`` (see the module doc).

    Args:
        provider: the body model (forward kinematics and Jacobians).
        config: iteration settings (:class:`DlsConfig`).
    """

    def __init__(self, provider: JacobianProvider, config: DlsConfig | None = None):
        self.provider = provider
        self.config = config or DlsConfig()
        self._chains: dict[str, KinematicChain] = {}
        self._rest: np.ndarray | None = None

    def solve(
        self,
        q_start: np.ndarray,
        joint_names: Sequence[str],
        frames: Sequence[str],
        positions: np.ndarray,
        rotations: Sequence[np.ndarray | None] | None = None,
        lower: np.ndarray | None = None,
        upper: np.ndarray | None = None,
    ) -> DlsResult:
        """Iterate from ``q_start`` (nq,) [rad], moving ``joint_names`` only, until each of the
        k ``frames`` reaches its target ``positions[i]`` (k, 3) [m] (and ``rotations[i]``
        (3, 3) ``R_base_frame`` where given). ``lower`` / ``upper`` (n,) [rad] replace the
        provider's joint limits. Raises :class:`InvalidInput` (NaN, shapes, unknown joint)."""
        prov, cfg = self.provider, self.config
        frames = tuple(frames)
        k = len(frames)
        if k == 0:
            raise InvalidInput("frames: expected at least one frame, got none")
        x_d = as_vector(positions, 3 * k, "positions").reshape(k, 3)
        R_d = [None] * k if rotations is None else list(rotations)
        if len(R_d) != k:
            raise InvalidInput(f"rotations: expected {k} entries (or None), got {len(R_d)}")
        R_d = [None if R is None else as_rotation(R) for R in R_d]
        names = tuple(joint_names)
        unknown = [j for j in names if j not in prov.joint_names]
        if unknown:
            raise InvalidInput(f"joint_names: {unknown} are not joints of the body model")
        idx = np.array([prov.joint_names.index(j) for j in names], dtype=int)
        q = as_vector(q_start, prov.nq, "q_start").copy()
        lo = prov.lower[idx] if lower is None else as_vector(lower, len(idx), "lower")
        hi = prov.upper[idx] if upper is None else as_vector(upper, len(idx), "upper")
        q[idx] = np.clip(q[idx], lo, hi)
        # rows of the stacked Jacobians (k * 6, nq) in the task: x, y, z (+ rotation) per frame
        rows = np.concatenate([6 * i + np.arange(3 if R is None else 6) for i, R in enumerate(R_d)])
        rotated = [i for i in range(k) if R_d[i] is not None]
        best, best_it = np.inf, 0
        status = _MAX_ITER
        it = 0
        t0 = time.perf_counter()
        while True:
            kin = prov.kinematics(q, frames)
            e_pos = x_d - kin.positions
            pos_err = np.sqrt(np.einsum("ij,ij->i", e_pos, e_pos))
            ori_err = np.full(k, math.nan)
            if rotated:
                errors = np.zeros((k, 6))
                errors[:, :3] = e_pos
                for i in rotated:
                    errors[i, 3:] = pin.log3(R_d[i] @ kin.rotations[i].T)
                    ori_err[i] = math.sqrt(errors[i, 3:] @ errors[i, 3:])
                error = errors.reshape(-1)[rows]
            else:
                error = e_pos.reshape(-1)
            worst = float(pos_err.max())
            ori_ok = not rotated or float(np.max(ori_err[rotated])) <= cfg.orientation_tolerance
            if worst <= cfg.position_tolerance and ori_ok:
                status = _CONVERGED
                break
            if it >= cfg.max_iter:
                break
            if worst < 0.99 * best:
                best, best_it = worst, it
            elif cfg.stall_iterations and it - best_it >= cfg.stall_iterations:
                status = _STALLED
                break
            it += 1
            jac = kin.jacobians.reshape(6 * k, -1)[rows][:, idx]
            dq = damped_least_squares_step(jac, error, cfg.damping, cfg.max_step)
            q[idx] = np.clip(q[idx] + dq, lo, hi)
        solve_time = time.perf_counter() - t0
        verdict = cfg.success_tolerance or cfg.position_tolerance
        success = bool(worst <= verdict and ori_ok)
        return DlsResult(
            q=q,
            joint_names=names,
            joint_positions=q[idx].copy(),
            frames=frames,
            positions=kin.positions.copy(),
            position_errors=pos_err,
            orientation_errors=ori_err,
            iterations=it,
            converged=status == _CONVERGED,
            success=success,
            status=status,
            solve_time=solve_time,
            message=f"DLS {status}: position error {worst * 1e3:.3f} mm",
        )

    def solve_chain(
        self,
        chain: str,
        position: np.ndarray,
        rotation: np.ndarray | None = None,
        q_start: np.ndarray | None = None,
    ) -> DlsResult:
        """Solve for the hand of a Cartesian-solver chain (``right_arm``, ``torso_right_arm``,
        ...) from ``q_start`` (nq,) [rad] (default: the rest posture of config/robot.yaml)."""
        kc = self._chains.get(chain)
        if kc is None:
            kc = self._chains[chain] = KinematicChain.from_name(chain)
        if q_start is None:
            if self._rest is None:
                rest = RobotSpec.load().posture("rest")
                self._rest = np.array([rest.get(j, 0.0) for j in self.provider.joint_names])
            q_start = self._rest
        return self.solve(q_start, kc.joints, [kc.frame], position,
                          None if rotation is None else [rotation])
