"""IkSeed: a compiled, fixed-iteration Newton method on eq 11 that gives IPOPT a warm start.

IPOPT remains the solver whose answer is returned (:class:`IkSolver`): the seed only provides
the starting point and multipliers for a warm-started IPOPT (``warm_start_init_point``), which
then needs ~0-3 iterations instead of ~12 from the rest posture. Measured in the previous round:
an IPOPT solve costs a fixed ~0.45 ms plus ~0.3 ms per iteration, so a seed pays only when it
costs well under a millisecond; this one is a single generated C function (no Python in its
loop).

Method (one CasADi Function, ``n_iter`` unrolled iterations, generated to C with gcc): Newton
steps on the KKT conditions of eq 11 with the position constraint as an equality,

    min_q f(q)   s.t.   c(q) = x_d - K_x(q) - s = 0,   q_L <= q <= q_U,

where s is the point of the epsilon ball where eq 11's optimum puts the hand's error: when the
ball constraint ``||s||^2 <= epsilon`` is active, stationarity in s of the lifted form
(see :mod:`ik_problem`) gives ``s = sqrt(epsilon) lambda / ||lambda||`` with lambda the
multiplier of c. Each iteration solves the (n+3) x (n+3) KKT system

    [H   J^T] [dq     ]   [-grad f]
    [J   0  ] [lambda+] = [-c     ],     J = dc/dq,

with the joints within 1e-6 rad of a limit held (their row replaced by dq_i = 0) unless their
multiplier says the Lagrangian decreases into the interior (one active-set update per
iteration), the step scaled to at most ``max_step`` [rad] per joint and the result clipped to
the limits. The first ``n_gauss`` iterations use the Gauss-Newton Hessian of f (orientation
residual ``R_d - R(q)``: ``w_ori J_r^T J_r`` + the rest term's diagonal, positive semi-definite)
+ damping and s = 0: robust far from the target. The others use the exact Hessian of the
Lagrangian + damping with s put on the ball: quadratic convergence near a KKT point. Newton's
method also converges to saddles and maxima (e.g. the hand turned by 180 deg, where the
orientation term is stationary), so the seed's point is used only if it passes a second-order
check (computed in the same generated C).
The seed ignores iKin's linear shoulder constraints and any extra constraints: the
warm-started IPOPT handles them; :class:`IkSolver` falls back to IPOPT from the usual start
when the seed misses the target or fails the check, or the warm-started IPOPT does not
converge or leaves a linear constraint violated.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from icub_pmp.cartesian.ik_problem import IkProblem
from icub_pmp.cartesian.nlp_codegen import compiled_function
from icub_pmp.cartesian.nlp_scaling import POSITION_SCALE, SLACK_SCALE

__all__ = ["IkSeed"]


class IkSeed:
    """The compiled seed of one :class:`~icub_pmp.cartesian.ik_problem.IkProblem`.

    Args:
        problem: the eq 11 NLP (its symbols ``q``, ``p``, ``f``, ``fk_position`` are reused).
        n_iter: number of Newton iterations (fixed; the generated C has no early exit).
        n_gauss: of which the first ones use the Gauss-Newton Hessian of f (module docstring).
        max_step: largest joint step per iteration [rad].
        damping: added to the diagonal of H [1/rad^2 in f's units].
        codegen: compile to C with gcc (cached); otherwise CasADi's virtual machine.

    Call :meth:`__call__` with ``q0`` (n,) [rad], the parameter vector ``p`` and epsilon
    [m^2]; it returns ``(x0, lam_x0, lam_g0, position_error, minimum)``: the warm start of the
    lifted NLP (x = [q; s], multipliers in CasADi's convention, ``lam_g0`` over the NLP's
    constraints in order), the hand's distance to the target [m] and the second-order check.
    It is a warm start only: :class:`IkSolver` returns IPOPT's answer.
    """

    def __init__(
        self,
        problem: IkProblem,
        n_iter: int = 24,
        n_gauss: int = 10,
        max_step: float = 0.5,
        damping: float = 1e-4,
        codegen: bool = True,
    ):
        self.problem = problem
        self.n_iter, self.n_gauss = int(n_iter), int(n_gauss)
        n = problem.chain.n
        q, p = problem.q, problem.p
        lam = ca.SX.sym("lam", 3)
        sqrt_eps = ca.SX.sym("sqrt_eps")
        exact = ca.SX.sym("exact")  # 0: Gauss-Newton Hessian of f, 1: Hessian of the Lagrangian
        lb, ub = ca.DM(problem.lbx), ca.DM(problem.ubx)
        x_d = p[problem.layout.x_d]
        lam_norm = ca.sqrt(ca.sumsqr(lam) + 1e-30)
        s = exact * sqrt_eps * lam / lam_norm  # where eq 11 puts the hand's error
        c = x_d - problem.fk_position - s
        J = ca.jacobian(c, q)
        grad_f = ca.gradient(problem.f, q)
        # Gauss-Newton Hessian of f (positive semi-definite): orientation residual R_d - R(q)
        L = problem.layout
        _, fk_rot = problem.kinematics.function(ca.vertcat(p[L.q_fixed], q))
        r_ori = ca.vec(ca.reshape(p[L.R_d], 3, 3) - fk_rot)
        J_ori = ca.jacobian(r_ori, q)
        H_f = p[L.w_ori] * (J_ori.T @ J_ori) + ca.diag(2 * p[L.w_rest])
        H_l = ca.hessian(problem.f + ca.dot(lam, c), q)[0]
        H = H_f + exact * (H_l - H_f) + damping * ca.SX.eye(n)

        def kkt_step(free):
            D = ca.diag(free)
            K = ca.blockcat([[D @ H @ D + ca.diag(1 - free), D @ J.T], [J @ D, ca.SX.zeros(3, 3)]])
            sol = ca.solve(K, ca.vertcat(-D @ grad_f, -c))
            return sol[:n], sol[n:]

        at_lb = q <= lb + _AT_BOUND
        at_ub = q >= ub - _AT_BOUND
        # active set on the limits: hold every joint at a limit, then release those whose
        # multiplier has the wrong sign (the model's Lagrangian decreases into the interior)
        held = ca.logic_or(at_lb, at_ub)
        dq1, lam1 = kkt_step(1 - held)
        grad_l = H @ dq1 + grad_f + J.T @ lam1
        release = ca.logic_or(ca.logic_and(at_lb, grad_l < 0), ca.logic_and(at_ub, grad_l > 0))
        dq, lam_new = kkt_step(1 - ca.logic_and(held, ca.logic_not(release)))
        scale = ca.fmin(1.0, max_step / (ca.mmax(ca.fabs(dq)) + 1e-30))
        q_new = ca.fmin(ca.fmax(q + scale * dq, lb), ub)
        step = ca.Function(
            "ik_seed_step", [q, lam, p, sqrt_eps, exact], [q_new, lam_new],
        )
        # the unrolled loop, as an MX graph calling the step (generated as one C loop body)
        q_mx, p_mx, se_mx = ca.MX.sym("q", n), ca.MX.sym("p", p.numel()), ca.MX.sym("se")
        qk, lk = q_mx, ca.MX.zeros(3)
        for k in range(self.n_iter):
            qk, lk = step(qk, lk, p_mx, se_mx, 0.0 if k < self.n_gauss else 1.0)
        # outputs for the lifted NLP: s on the ball, multipliers mapped (see module docstring)
        fin = self._finish_function(problem, lam)
        seed = ca.Function(
            f"{problem.name}_seed", [q_mx, p_mx, se_mx], [fin(qk, lk, p_mx, se_mx)],
            ["q0", "p", "sqrt_eps"], ["out"],
        )
        self._nx, self._ng = n + 3, problem.g.numel()
        self.function, self.compiled = (
            compiled_function(seed) if codegen else (seed, False)
        )

    @staticmethod
    def _finish_function(problem, lam) -> ca.Function:
        """(q, lambda, p, sqrt(epsilon)) -> x0, lam_x0, lam_g0, ||x_d - K_x(q)|| [m] for the
        lifted NLP g = [SLACK_SCALE (x_d - K_x - s), POSITION_SCALE ||s||^2, C q, extra]."""
        q, p = problem.q, problem.p
        sqrt_eps = ca.SX.sym("sqrt_eps")
        x_d = p[problem.layout.x_d]
        err = x_d - problem.fk_position
        lam_norm = ca.sqrt(ca.sumsqr(lam) + 1e-30)
        s = sqrt_eps * lam / lam_norm
        # multipliers: CasADi's grad f + J_g^T lam_g + lam_x = 0
        lam_g1 = lam / SLACK_SCALE
        lam_g2 = lam_norm / (2.0 * POSITION_SCALE * sqrt_eps)
        c = x_d - problem.fk_position - s
        grad_l = ca.gradient(problem.f + ca.dot(lam, c), q)
        lb, ub = ca.DM(problem.lbx), ca.DM(problem.ubx)
        at_bound = ca.logic_or(q <= lb + _AT_BOUND, q >= ub - _AT_BOUND)
        lam_x_q = -grad_l * at_bound
        n_rest = problem.g.numel() - 4
        lam_g = ca.vertcat(lam_g1, lam_g2, ca.SX.zeros(n_rest))
        # second-order check: H_l positive semi-definite on the null space of the position
        # Jacobian over the free joints <=> H_l + rho J^T J is (for rho large enough; H_l is
        # O(1e-3..1), J^T J's nonzero eigenvalues O(1e-3..1e-1) [m^2]); tested with the
        # pivots of its LDL^T (joints at a bound: identity rows), all in the generated C
        H_l = ca.hessian(problem.f + ca.dot(lam, c), q)[0]
        J = ca.jacobian(problem.fk_position, q)
        D = ca.diag(1 - at_bound)
        A = D @ (H_l + _RHO * J.T @ J) @ D + ca.diag(at_bound)
        minimum = ca.SX(1)
        for d in _ldl_pivots(A):
            minimum = minimum * (d >= -_PIVOT_TOL)
        return ca.Function(
            "ik_seed_finish", [q, lam, p, sqrt_eps],
            [ca.vertcat(q, s, lam_x_q, ca.SX.zeros(3), lam_g, ca.norm_2(err), minimum)],
        )

    def __call__(self, q0: np.ndarray, p: np.ndarray, epsilon: float):
        """Run the seed from joints ``q0`` (n,) [rad]: (x0 (n+3,), lam_x0 (n+3,), lam_g0,
        position error [m] of the seed's joints, minimum).

        ``minimum`` is the second-order check: the Hessian of the Lagrangian is positive
        semi-definite (up to round-off) on the null space of the position Jacobian over the
        joints not at a bound. Newton's method converges to any KKT point, saddles and maxima
        included (e.g. the hand turned by 180 deg, where the orientation term is stationary),
        and IPOPT warm-started there would certify it: such a seed must not be used.
        """
        out = np.asarray(self.function(q0, p, math.sqrt(epsilon)), dtype=float).reshape(-1)
        nx, ng = self._nx, self._ng
        x0, lam_x, lam_g = out[:nx], out[nx: 2 * nx], out[2 * nx: 2 * nx + ng]
        return x0, lam_x, lam_g, float(out[-2]), bool(out[-1] > 0.5)


_RHO = 1e4  # [1/m^2] weight of J^T J in the second-order check
# a joint this close to a limit counts as at the limit [rad] (IPOPT's answers, the node's warm
# starts, stay ~1e-8 inside: treated as free, the Newton step pushes them out and the clipping
# makes the step inconsistent)
_AT_BOUND = 1e-6
_PIVOT_TOL = 1e-9  # smallest accepted pivot (semi-definite up to round-off)


def _ldl_pivots(A: ca.SX) -> list:
    """Pivots d_k of the LDL^T factorisation of the symmetric SX matrix A (no pivoting):
    A is positive definite iff all are > 0 (a zero or negative pivot makes the following
    ones meaningless, which the caller's all(d >= -tol) test tolerates: NaN compares False)."""
    n = A.shape[0]
    L = [[None] * n for _ in range(n)]
    d = []
    for j in range(n):
        dj = A[j, j] - sum((L[j][k] ** 2 * d[k] for k in range(j)), ca.SX(0))
        d.append(dj)
        for i in range(j + 1, n):
            L[i][j] = (A[i, j] - sum((L[i][k] * L[j][k] * d[k] for k in range(j)), ca.SX(0))) / dj
    return d
