"""IkSolver: eq 11 solved by IPOPT for any of the four chains, chosen at run time.

Mirrors iKinCartesianSolver (Sect. 4 of the reaching paper): position as a constraint,
orientation and rest posture in the cost, joint limits and the iCub shoulder constraints,
warm-started from the current joints, IPOPT bounded in iterations and wall time. Problems are
built lazily, once per chain (:meth:`problem`), and reused for every solve.

With ``seed_warm_start`` (default) a compiled fixed-iteration Newton method on eq 11
(:class:`~icub_pmp.cartesian.ik_seed.IkSeed`, ~0.3 ms) runs first from the start joints; when
its point reaches the target and passes a second-order check, IPOPT starts warm from it (primal
point and multipliers) and typically certifies it in 0-2 iterations. The answer is always
IPOPT's; IPOPT from the start joints is the fallback (seed missed, or warm start not converged).
"""

from __future__ import annotations

import math
import time
from typing import Mapping, Sequence

import numpy as np

from icub_pmp.cartesian.ik_config import IkConfig
from icub_pmp.cartesian.ik_problem import IkProblem, NlpConstraint
from icub_pmp.cartesian.ik_seed import IkSeed
from icub_pmp.cartesian.ik_solution import IkSolution
from icub_pmp.cartesian.kinematic_chain import CHAIN_NAMES, KinematicChain
from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_model import IcubModel
from icub_pmp.kinematics.rotations import as_rotation, as_vector, rotation_angle

__all__ = ["IkSolver"]

_CONVERGED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
_VIOLATION_OK = 1e-6  # largest accepted violation of limits / linear constraints [rad]


class IkSolver:
    """Cartesian solver (eq 11) over the iCub upper-body model.

    Args:
        model: the pinocchio model (built from config/robot.yaml when omitted).
        config: solver parameters.
        constraints: additional constraints per chain name (:class:`NlpConstraint`), added to
            the shoulder constraints of that chain's NLP.
    """

    def __init__(
        self,
        model: IcubModel | None = None,
        config: IkConfig | None = None,
        constraints: Mapping[str, Sequence[NlpConstraint]] | None = None,
    ):
        self.model = model or IcubModel()
        self.config = config or IkConfig()
        self.constraints = dict(constraints or {})
        for name in self.constraints:
            if name not in CHAIN_NAMES:
                raise UnknownName("chain", name, CHAIN_NAMES)
        self._problems: dict[str, IkProblem] = {}
        self._seeds: dict[str, IkSeed] = {}
        self._q_rest_full = self.model.posture(self.config.rest_posture)

    # ------------------------------------------------------------------ build
    _BUILD_FIELDS = (
        "constraint_tolerance", "shoulder_constraints", "tol", "max_iter", "max_solve_time",
        "codegen",
    )

    def reconfigure(self, config: IkConfig) -> None:
        """Use ``config`` from now on; the built problems are kept unless a field they are
        built with changed (epsilon, weights and rest posture never need a rebuild)."""
        if any(getattr(config, f) != getattr(self.config, f) for f in self._BUILD_FIELDS):
            self._problems.clear()
            self._seeds.clear()
        self.config = config
        self._q_rest_full = self.model.posture(config.rest_posture)

    def problem(self, chain: str) -> IkProblem:
        """The (cached) NLP of ``chain``; builds it on first use (and its seed when
        ``seed_warm_start`` is on, so that a prebuilt chain never compiles during a request)."""
        if chain not in CHAIN_NAMES:
            raise UnknownName("chain", chain, CHAIN_NAMES)
        if chain not in self._problems:
            kc = KinematicChain.from_name(chain, self.model.spec)
            self._problems[chain] = IkProblem(
                self.model, kc, self.config, self.constraints.get(chain, ())
            )
        prob = self._problems[chain]
        if self.config.seed_warm_start:
            self.seed(chain)  # built (and compiled) with the problem, never during a request
        return prob

    def seed(self, chain: str) -> IkSeed:
        """The (cached) warm-start seed of ``chain``'s NLP; builds both on first use."""
        if chain not in self._seeds:
            prob = self._problems.get(chain) or self.problem(chain)
            if chain not in self._seeds:
                self._seeds[chain] = IkSeed(prob, codegen=self.config.codegen)
        return self._seeds[chain]

    def rest_weights(self, chain: KinematicChain) -> np.ndarray:
        """beta * diag(W) over the chain's optimised joints."""
        w = dict(zip(chain.fk_joints[:3], self.config.rest_joint_weights_torso))
        w.update(zip(chain.fk_joints[3:], self.config.rest_joint_weights_arm))
        return self.config.rest_weight * np.array([w[j] for j in chain.joints])

    # ------------------------------------------------------------------ solve
    def solve(
        self,
        chain: str,
        position: np.ndarray,
        rotation: np.ndarray | None = None,
        q_start: np.ndarray | None = None,
        *,
        orientation_weight: float | None = None,
        epsilon: float | None = None,
    ) -> IkSolution:
        """Solve eq 11 for the hand of ``chain``.

        Args:
            chain: one of ``left_arm``, ``right_arm``, ``torso_left_arm``, ``torso_right_arm``.
            position: target x_d (3,) [m] in root_link.
            rotation: target orientation ``R_root_hand`` (3, 3), or None for position only.
            q_start: full model configuration (nq,) [rad] (IcubModel order): the warm start,
                and the values of the joints the chain holds (the torso of a 7-DoF chain).
                Default: the rest posture.
            orientation_weight: overrides the configured weight (>= 0).
            epsilon: overrides the configured squared position tolerance [m^2] (> 0).

        Raises:
            UnknownName: unknown chain. InvalidInput: NaN/inf, bad shapes, non-rotation.
        """
        prob = self.problem(chain)
        x_d = as_vector(position, 3, "position")
        R_d = None if rotation is None else as_rotation(rotation)
        q_full = self._q_rest_full if q_start is None else self.model.check_q(q_start)
        w_ori = self.config.orientation_weight if orientation_weight is None else orientation_weight
        if not (math.isfinite(w_ori) and w_ori >= 0):
            raise InvalidInput(f"orientation_weight: expected a finite value >= 0, got {w_ori}")
        eps = self.config.epsilon if epsilon is None else epsilon
        if not (math.isfinite(eps) and eps > 0):
            raise InvalidInput(f"epsilon: expected a finite value > 0 [m^2], got {eps}")
        kc = prob.chain
        idx = self.model.indices(kc.joints)
        q_fixed = q_full[self.model.indices(kc.fixed_joints)] if kc.fixed_joints else []
        p = prob.parameters(
            x_d, R_d, w_ori, self.rest_weights(kc), self._q_rest_full[idx], np.asarray(q_fixed)
        )
        lbg, ubg = prob.g_bounds(eps)
        lbx, ubx = prob.x_bounds
        x0 = np.clip(q_full[idx], prob.lbx, prob.ubx)
        bounds = dict(p=p, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
        t0 = time.perf_counter()
        seeded, iterations = False, 0
        if self.config.seed_warm_start:
            seeded, q, status, status_detail, iterations = self._seeded_solve(prob, x0, eps,
                                                                              bounds)
        if not seeded:
            q, status, status_detail, its = _run(prob.solver, kc.n, x0,
                                                 x0=prob.start(x0, p), **bounds)
            iterations += its
        dt = time.perf_counter() - t0
        q = np.clip(q, prob.lbx, prob.ubx)  # IPOPT relaxes bounds by ~1e-8 rad
        return self._evaluate(prob, q, p, x_d, R_d, q_fixed, eps, dt, iterations, status,
                              status_detail, seeded)

    # the seed's point goes to the warm-started IPOPT only when its hand is this close to the
    # target [m]: from a seed that has not converged (mostly pose targets, whose cost is not
    # convex) the warm start needs more iterations than IPOPT from the start joints
    SEED_ACCEPT = 1e-3
    # a seed that misses is continued once from where it stopped (another ~0.3 ms): on the
    # benchmark's targets this rescues about half of the misses (11 of 20 position-only, 31 of
    # 62 with orientation), each saving an IPOPT solve from the start joints (~5-7 ms)
    SEED_CALLS = 2

    def _seeded_solve(self, prob: IkProblem, x0: np.ndarray, eps: float, bounds: dict):
        """IPOPT warm-started from :class:`IkSeed` (run from ``x0``): (seeded, q, status,
        detail, iterations); seeded is False (and IPOPT must run from the usual start) when the
        seed (SEED_CALLS calls, each from where the previous stopped) misses the target by more
        than SEED_ACCEPT or stops at a point that is not a local minimum (second-order check),
        or when the warm start does not converge or leaves a linear constraint violated."""
        q_seed, n = x0, prob.chain.n
        for _ in range(self.SEED_CALLS):
            try:
                xs, lam_x, lam_g, perr, minimum = self.seed(prob.chain.name)(
                    q_seed, bounds["p"], eps)
            except RuntimeError:
                return False, x0, "exception", "seed failed", 0
            if not np.all(np.isfinite(xs)):
                return False, x0, "seed_missed", "seed missed", 0
            if perr <= self.SEED_ACCEPT and minimum:
                break
            q_seed = np.clip(xs[:n], prob.lbx, prob.ubx)
        else:
            return False, x0, "seed_missed", "seed missed", 0
        q, status, detail, its = _run(prob.warm_solver, prob.chain.n, x0, x0=xs, lam_x0=lam_x,
                                      lam_g0=lam_g, **bounds)
        # the seed ignores the linear (shoulder) and extra constraints: IPOPT restores them,
        # but only to its constr_viol_tol; keep the answer only if they hold as tightly as
        # IkSolution.success requires (from the start joints IPOPT stays inside them)
        ok = status in _CONVERGED and prob.linear_violation(q, bounds["p"]) <= _VIOLATION_OK
        return ok, q, status, detail, its

    def _evaluate(self, prob, q, p, x_d, R_d, q_fixed, eps, dt, iterations, status, detail,
                  seeded=False):
        pos, rot = prob.kinematics.pose(np.concatenate([np.asarray(q_fixed, float), q]))
        perr = float(np.linalg.norm(x_d - pos))
        oerr = math.nan if R_d is None else rotation_angle(R_d, rot)
        viol = prob.linear_violation(q, p)
        tol_pos = math.sqrt(eps + self.config.constraint_tolerance)
        feasible = perr <= tol_pos * (1 + 1e-9) and viol <= _VIOLATION_OK
        converged = status in _CONVERGED
        if feasible:
            msg = f"position error {perr * 1e3:.3f} mm"
            if R_d is not None:
                msg += f", orientation error {math.degrees(oerr):.3f} deg"
            if not converged:
                msg += f" (IPOPT stopped early: {detail})"
        elif perr > tol_pos:
            msg = (
                f"target not reached: position error {perr * 1e3:.2f} mm > "
                f"{tol_pos * 1e3:.2f} mm (unreachable for chain {prob.chain.name}?); "
                f"IPOPT: {detail}"
            )
        else:
            msg = f"constraints violated by {viol:.2e} rad; IPOPT: {detail}"
        return IkSolution(
            success=bool(feasible),
            converged=converged,
            chain=prob.chain.name,
            joint_names=prob.chain.joints,
            q=q,
            position=pos,
            rotation=rot,
            position_error=perr,
            orientation_error=oerr,
            constraint_violation=viol,
            solve_time=dt,
            iterations=iterations,
            status=status,
            message=msg,
            seeded=seeded,
        )

    def full_q(self, solution: IkSolution, q_start: np.ndarray | None = None) -> np.ndarray:
        """Full model configuration (nq,): ``q_start`` with the chain's joints from ``solution``."""
        q = np.array(self._q_rest_full if q_start is None else self.model.check_q(q_start))
        q[self.model.indices(solution.joint_names)] = solution.q
        return q


def _run(solver, n: int, q_fallback: np.ndarray, **args):
    """One IPOPT call: (q (n,), status, detail, iterations); ``q_fallback`` when CasADi raises
    (evaluation errors, NaN in functions) or the answer is not finite."""
    try:
        res = solver(**args)
        stats = solver.stats()
        q = np.array(res["x"], dtype=float).reshape(-1)[:n]
        status = str(stats.get("return_status", "unknown"))
        iterations = int(stats.get("iter_count", 0))
    except RuntimeError as exc:
        detail = str(exc).splitlines()[0] if str(exc) else "error"
        return q_fallback, "exception", detail, 0
    if not np.all(np.isfinite(q)):
        return q_fallback, "exception", "non-finite answer", iterations
    return q, status, status, iterations
