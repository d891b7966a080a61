"""IkProblem: eq 11 of the reaching paper as a CasADi NLP for one chain (built, not solved).

    q_d = argmin_q  w_o ||alpha_d - K_alpha(q)||^2 + beta (q_rest - q)^T W (q_rest - q)
          s.t.      ||x_d - K_x(q)||^2 <= epsilon,   q_L <= q <= q_U,   lb <= C q <= ub

Position is the constraint (higher priority), orientation and rest posture are in the cost.
The position constraint is given to IPOPT in lifted form, with the hand's position error as 3
extra variables s [m]: ``x_d - K_x(q) - s = 0`` and ``||s||^2 <= epsilon``. The set of feasible
q is exactly that of eq 11 (s is determined by q) and the objective does not involve s, so the
problem and its solutions are eq 11's; but the nonlinear kinematics now sit in equality
constraints whose Jacobian (the hand Jacobian) has full rank, instead of in a squared distance
whose gradient vanishes at the target, and IPOPT needs about a quarter fewer iterations (median
16 -> 12, p95 34 -> 18 from the rest posture on the benchmark's targets).
The orientation distance is written on rotation matrices, ``1/2 ||R_d - R(q)||_F^2 =
2 (1 - cos theta)`` with theta the angle of ``R_d^T R(q)``: it equals theta^2 (the squared
axis-angle distance of eq 11) to second order, is smooth everywhere (the axis-angle map is not
at theta = 0) and has its only minimum at theta = 0. The squared position error is expressed
in cm^2 inside the NLP so that IPOPT's absolute ``constr_viol_tol`` is meaningful; epsilon and
all weights are run-time parameters or bounds, so changing them never rebuilds the problem.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable, NamedTuple, Sequence

import casadi as ca
import numpy as np

from icub_pmp.cartesian.arm_linear_constraints import ArmLinearConstraints, LinearConstraints
from icub_pmp.cartesian.casadi_kinematics import CasadiKinematics
from icub_pmp.cartesian.ik_config import IkConfig
from icub_pmp.cartesian.kinematic_chain import KinematicChain
from icub_pmp.cartesian.nlp_codegen import compiled_nlpsol
from icub_pmp.cartesian.nlp_scaling import POSITION_SCALE, SLACK_SCALE
from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.robot_model import IcubModel

__all__ = ["IkProblem", "NlpConstraint"]


class NlpConstraint(NamedTuple):
    """An additional constraint ``lb <= expression(q_fk, kinematics) <= ub`` (item 5 of Sect. 4:
    "it is easy to add new constraints as linear and/or nonlinear inequalities").

    ``expression`` receives the SX vector of the chain's ``fk_joints`` (torso first, 10) [rad]
    and the chain's :class:`CasadiKinematics` (``kinematics.function(q_fk)`` gives the hand
    position and rotation) and returns an SX column of the same length as ``lb`` and ``ub``
    (use +-inf for a one-sided bound).
    """

    name: str
    expression: Callable[[ca.SX, CasadiKinematics], ca.SX]
    lb: Sequence[float]
    ub: Sequence[float]


@dataclasses.dataclass(frozen=True)
class _Layout:
    """Slices of the parameter vector p."""

    x_d: slice
    R_d: slice
    w_ori: slice
    w_rest: slice
    q_rest: slice
    q_fixed: slice
    size: int


class IkProblem:
    """The eq 11 NLP of ``chain``: symbols, bounds, and the IPOPT solver (built once).

    Attributes:
        chain: the :class:`KinematicChain`.
        kinematics: the :class:`CasadiKinematics` of the chain's hand frame.
        q: SX joint variables (n,) [rad] (the chain's optimised joints).
        s: SX position-error variables (3,) [m]; the NLP's variables are ``x = [q; s]``.
        p: SX parameter vector (see :meth:`parameters`).
        fk_position: SX hand position K_x(q) (3,) [m].
        f, g: SX objective and constraints: g = [SLACK_SCALE (x_d - K_x(q) - s) (3, [cm]),
            POSITION_SCALE ||s||^2 ([cm^2]), C q (linear constraints), extra constraints].
        lbx, ubx: joint limits (n,) [rad] from the URDF.
        linear: the linear constraints (C, lb, ub) over ``q`` (empty when disabled).
        solver: the CasADi ``nlpsol`` (IPOPT, exact Hessian).
        warm_solver: the same NLP and IPOPT, set to start from a given primal-dual point
            (the warm-start seed's, :class:`~icub_pmp.cartesian.ik_seed.IkSeed`, which
            :class:`~icub_pmp.cartesian.ik_solver.IkSolver` builds for it).
        compiled: whether the NLP functions run as compiled C.
    """

    def __init__(
        self,
        model: IcubModel,
        chain: KinematicChain,
        config: IkConfig,
        constraints: Sequence[NlpConstraint] = (),
    ):
        self.chain = chain
        self.config = config
        self.kinematics = CasadiKinematics(model, chain.frame, chain.fk_joints)
        n, nf = chain.n, len(chain.fixed_joints)
        sizes = (
            ("x_d", 3), ("R_d", 9), ("w_ori", 1), ("w_rest", n), ("q_rest", n), ("q_fixed", nf)
        )
        slices, i = {}, 0
        for name, k in sizes:
            slices[name] = slice(i, i + k)
            i += k
        self.layout = _Layout(size=i, **slices)
        self.p = ca.SX.sym("p", i)
        self.q = ca.SX.sym("q", n)
        self.s = ca.SX.sym("s", 3)
        p, L = self.p, self.layout
        q_fk = ca.vertcat(p[L.q_fixed], self.q)  # fixed joints are the torso: first in fk order
        fk_pos, fk_rot = self.kinematics.function(q_fk)
        self.fk_position = fk_pos
        x_d = p[L.x_d]
        R_d = ca.reshape(p[L.R_d], 3, 3)
        orientation = 0.5 * ca.sumsqr(R_d - fk_rot)
        rest = ca.dot(p[L.w_rest], (p[L.q_rest] - self.q) ** 2)
        self.f = p[L.w_ori] * orientation + rest
        idx = model.indices(chain.joints)
        self.lbx = model.lower[idx].copy()
        self.ubx = model.upper[idx].copy()
        self.linear: LinearConstraints | None = None
        if config.shoulder_constraints:
            self.linear = ArmLinearConstraints(chain.hand).over(chain.joints)
        g = [SLACK_SCALE * (x_d - fk_pos - self.s), POSITION_SCALE * ca.sumsqr(self.s)]
        if self.linear is not None:
            g.append(ca.DM(self.linear.C) @ self.q)
        self.constraints = tuple(constraints)
        extra, self._extra_lb, self._extra_ub = [], [], []
        for c in self.constraints:
            expr = ca.vec(c.expression(q_fk, self.kinematics))
            lb = np.asarray(c.lb, dtype=float).reshape(-1)
            ub = np.asarray(c.ub, dtype=float).reshape(-1)
            if not (expr.numel() == lb.size == ub.size) or np.any(lb > ub):
                raise InvalidInput(
                    f"constraint {c.name!r}: expression has {expr.numel()} rows, "
                    f"lb {lb.size}, ub {ub.size} (and lb <= ub is required)"
                )
            extra.append(expr)
            self._extra_lb += list(lb)
            self._extra_ub += list(ub)
        g += extra
        self.g = ca.vertcat(*g)
        self._extra_fn = None
        if extra:
            self._extra_fn = ca.Function("extra", [self.q, self.p], [ca.vertcat(*extra)])
        opts: dict[str, Any] = {
            "ipopt.print_level": 0,
            "ipopt.sb": "yes",
            "print_time": False,
            "error_on_fail": False,
            "ipopt.hessian_approximation": "exact",
            "ipopt.tol": config.tol,
            "ipopt.constr_viol_tol": config.constraint_tolerance * POSITION_SCALE,
            "ipopt.acceptable_iter": 0,
            "ipopt.mu_strategy": "adaptive",
            "ipopt.max_iter": config.max_iter,
            "ipopt.max_wall_time": config.max_solve_time,
            # skip the residual check (iterative refinement) of every linear solve: about 10 %
            # less time per iteration on this 13-variable problem, same iterations and answers
            # on the benchmark; every answer is checked by IkSolver anyway
            "ipopt.fast_step_computation": "yes",
            "record_time": False,
        }
        # the same NLP for a start from the seed's point and multipliers (IkSeed): IPOPT takes
        # them as they are (no push into the interior, barrier parameter already small), so a
        # KKT point is certified in ~0-2 iterations instead of re-converging from mu = 0.1
        warm_opts = dict(opts)
        warm_opts.update({
            "ipopt.warm_start_init_point": "yes",
            "ipopt.mu_init": 1e-6,
            "ipopt.warm_start_bound_push": 1e-9,
            "ipopt.warm_start_bound_frac": 1e-9,
            "ipopt.warm_start_slack_bound_push": 1e-9,
            "ipopt.warm_start_slack_bound_frac": 1e-9,
            "ipopt.warm_start_mult_bound_push": 1e-9,
        })
        nlp = {"x": ca.vertcat(self.q, self.s), "p": self.p, "f": self.f, "g": self.g}
        name = f"ik_{chain.name}{'_lin' if self.linear is not None else ''}"
        name += "".join(f"_{c.name}" for c in self.constraints if c.name.isidentifier())
        self.name = name
        if config.codegen:
            (self.solver, self.warm_solver), self.compiled = compiled_nlpsol(
                name, nlp, opts, warm_opts
            )
        else:
            self.solver = ca.nlpsol(name, "ipopt", nlp, opts)
            self.warm_solver = ca.nlpsol(name, "ipopt", nlp, warm_opts)
            self.compiled = False
        self.n_linear = 0 if self.linear is None else self.linear.C.shape[0]
        self._fk_position = ca.Function("fk_position", [self.q, self.p], [fk_pos])

    # ------------------------------------------------------------------ run-time data
    def parameters(
        self,
        x_d: np.ndarray,
        R_d: np.ndarray | None,
        w_ori: float,
        w_rest: np.ndarray,
        q_rest: np.ndarray,
        q_fixed: np.ndarray,
    ) -> np.ndarray:
        """Parameter vector p for a target (x_d (3,) [m], R_d (3, 3) or None) and weights."""
        L = self.layout
        p = np.zeros(L.size)
        p[L.x_d] = x_d
        p[L.R_d] = (np.eye(3) if R_d is None else np.asarray(R_d)).flatten(order="F")
        p[L.w_ori] = 0.0 if R_d is None else w_ori
        p[L.w_rest] = w_rest
        p[L.q_rest] = q_rest
        p[L.q_fixed] = q_fixed
        return p

    @property
    def x_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lbx, ubx) of the NLP variables x = [q; s]: joint limits, s free."""
        inf = np.full(3, np.inf)
        return np.concatenate([self.lbx, -inf]), np.concatenate([self.ubx, inf])

    def start(self, q0: np.ndarray, p: np.ndarray) -> np.ndarray:
        """x0 = [q0; x_d - K_x(q0)] for a cold start at joints q0 (n,) [rad] (the equality
        constraints hold there; only the bound on ||s||^2 is violated)."""
        pos = np.asarray(self._fk_position(q0, p), dtype=float).reshape(-1)
        return np.concatenate([q0, p[self.layout.x_d] - pos])

    def g_bounds(self, epsilon: float) -> tuple[np.ndarray, np.ndarray]:
        """(lbg, ubg): x_d - K_x(q) - s = 0, the bound epsilon [m^2] on ||s||^2 (both scaled),
        then the linear and the extra constraints."""
        lbg, ubg = [0.0, 0.0, 0.0, -np.inf], [0.0, 0.0, 0.0, epsilon * POSITION_SCALE]
        if self.linear is not None:
            lbg += list(self.linear.lb)
            ubg += list(self.linear.ub)
        return np.array(lbg + self._extra_lb), np.array(ubg + self._extra_ub)

    def linear_violation(self, q: np.ndarray, p: np.ndarray | None = None) -> float:
        """Largest violation of joint limits [rad], linear constraints [rad] and the extra
        constraints (their units; needs the parameter vector ``p``) at ``q`` (n,)."""
        v = max(0.0, float(np.max(self.lbx - q)), float(np.max(q - self.ubx)))
        if self.linear is not None:
            c = self.linear.C @ q
            v = max(v, float(np.max(self.linear.lb - c)), float(np.max(c - self.linear.ub)))
        if self._extra_fn is not None and p is not None:
            c = np.array(self._extra_fn(q, p)).reshape(-1)
            lb, ub = np.array(self._extra_lb), np.array(self._extra_ub)
            v = max(v, float(np.max(lb - c)), float(np.max(c - ub)))
        return v
