"""DlsSolver: damped-least-squares inverse kinematics, the baseline of Sect. 4.1.

The "more conventional strategy" the paper compares against (there through Orocos KDL): the
iteration ``dq = J^T (J J^T + lambda^2 I)^-1 e`` on the hand error e (position [m], or
position + rotation vector [rad] of R_d R^T), each step bounded in norm and projected onto the
joint limits. It knows nothing of the shoulder constraints and has no rest-posture term.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
import pinocchio as pin

from icub_pmp.cartesian.ik_solution import IkSolution
from icub_pmp.cartesian.ik_solver import _rotation, _vector, rotation_angle
from icub_pmp.cartesian.kinematic_chain import KinematicChain
from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError
from icub_pmp.kinematics.dls_step import damped_least_squares_step
from icub_pmp.kinematics.robot_model import IcubModel

__all__ = ["DlsConfig", "DlsSolver"]


@dataclasses.dataclass(frozen=True)
class DlsConfig(ConfigBase):
    """Attributes:
    damping: lambda [m] (mixed units for a pose error, as in KDL).
    max_step: largest joint step norm per iteration [rad].
    max_iter: iteration limit.
    position_tolerance: stop below this position error [m].
    orientation_tolerance: and below this orientation error [rad] (pose targets).
    """

    damping: float = 0.02
    max_step: float = 0.2
    max_iter: int = 300
    position_tolerance: float = 5e-4
    orientation_tolerance: float = math.radians(0.5)

    def validate(self) -> None:
        """Check ranges."""
        for name in ("damping", "max_step", "position_tolerance", "orientation_tolerance"):
            v = getattr(self, name)
            if not (v > 0 and math.isfinite(v)):
                raise ConfigError(f"DlsConfig.{name} must be > 0, got {v!r}")
        if self.max_iter < 1:
            raise ConfigError(f"DlsConfig.max_iter must be >= 1, got {self.max_iter}")


class DlsSolver:
    """Iterative DLS IK over a chain of the iCub model (the comparison baseline)."""

    def __init__(self, model: IcubModel | None = None, config: DlsConfig | None = None):
        self.model = model or IcubModel()
        self.config = config or DlsConfig()

    def solve(
        self,
        chain: str,
        position: np.ndarray,
        rotation: np.ndarray | None = None,
        q_start: np.ndarray | None = None,
    ) -> IkSolution:
        """Solve for the hand of ``chain`` from ``q_start`` (nq,) [rad] (default: rest)."""
        kc = KinematicChain.from_name(chain, self.model.spec)
        x_d = _vector(position, 3, "position")
        R_d = None if rotation is None else _rotation(rotation)
        m, cfg = self.model, self.config
        q = m.posture("rest") if q_start is None else m.check_q(q_start).copy()
        idx = m.indices(kc.joints)
        fid = m.frame_id(kc.frame)
        lo, hi = m.lower[idx], m.upper[idx]
        q[idx] = np.clip(q[idx], lo, hi)
        rows = 3 if R_d is None else 6
        t0 = time.perf_counter()
        status = "Maximum_Iterations_Exceeded"
        it = 0
        for it in range(cfg.max_iter + 1):
            J = m.frame_jacobian(q, fid)[:rows, idx]  # runs the forward kinematics too
            pose = m.data.oMf[fid]
            e = x_d - pose.translation
            done = np.linalg.norm(e) <= cfg.position_tolerance
            if R_d is not None:
                e_rot = pin.log3(R_d @ pose.rotation.T)
                done = done and np.linalg.norm(e_rot) <= cfg.orientation_tolerance
                e = np.concatenate([e, e_rot])
            if done:
                status = "Solve_Succeeded"
                break
            if it == cfg.max_iter:
                break
            dq = damped_least_squares_step(J, e, cfg.damping, cfg.max_step)
            q[idx] = np.clip(q[idx] + dq, lo, hi)
        dt = time.perf_counter() - t0
        pose = m.frame_pose(q, fid)
        perr = float(np.linalg.norm(x_d - pose.translation))
        oerr = math.nan if R_d is None else rotation_angle(R_d, pose.rotation)
        ok = status == "Solve_Succeeded"
        return IkSolution(
            success=ok,
            converged=ok,
            chain=kc.name,
            joint_names=kc.joints,
            q=q[idx],
            position=pose.translation,
            rotation=pose.rotation,
            position_error=perr,
            orientation_error=oerr,
            constraint_violation=0.0,
            solve_time=dt,
            iterations=it,
            status=status,
            message=f"DLS {status}: position error {perr * 1e3:.3f} mm",
        )
