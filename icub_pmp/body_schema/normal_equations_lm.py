"""Levenberg-Marquardt on the normal equations: J^T J accumulated over sample batches.

The body network's residual Jacobian at 10,000 babbles is 30,000 x 1,735: MINPACK factorises
it whole (about 37 s a step here) and the matrix-free trust-region step of ``trf-lsmr`` is
inexact (decision records 0040, 0042). This solver never holds J: it builds it batch by
batch with the network's batched backpropagation (:meth:`TanhMlp.weight_jacobian`), adds
each batch's J_b^T J_b into the P x P curvature with BLAS ``syrk`` (P = 1,735 for 7-32-41-3)
and solves the damped Gauss-Newton step with a Cholesky factorisation (LAPACK ``potrf``
through scipy):

    (J^T J + mu * D) delta = -J^T r,     D = diag(J^T J) + floor     (Marquardt's scaling)

A step is accepted when it lowers the training cost; the damping follows Nielsen's rule
(mu *= max(1/3, 1 - (2 rho - 1)^3) on success, mu *= nu, nu *= 2 on failure, rho the ratio of
actual to predicted reduction), so it shrinks toward Gauss-Newton near a minimum and grows
toward gradient descent where the linearisation is poor. Rejected steps reuse the same
factorable matrix (only a new Cholesky and a forward pass), so they are cheap.

Options that trade exactness for speed, both measured in decision 0042:
``curvature_samples`` builds J^T J from a random subset of the samples each iteration (the
gradient and the acceptance test stay on all of them: a subsampled Gauss-Newton step), and
``curvature_dtype`` float32 halves the cost of ``syrk`` (the curvature only preconditions the
step; the gradient and the cost are float64).

Stops: an iteration budget, a wall-time budget (an iteration is not started when the last one's
duration would overrun it), a validation split that stopped improving for ``patience``
accepted steps (the best weights on it are returned), a vanishing gradient or step, or a damping
that grew past ``max_damping``.
"""

from __future__ import annotations

import time
from typing import Callable, NamedTuple

import numpy as np
from scipy.linalg import LinAlgError, blas, cho_factor, cho_solve

from icub_pmp.body_schema.tanh_mlp import TanhMlp
from icub_pmp.errors import InvalidInput

__all__ = ["NormalEquationsLm", "NormalLmResult", "STOP_REASONS"]

#: why :meth:`NormalEquationsLm.run` stopped
STOP_REASONS = ("iterations", "time budget", "validation", "gradient", "step", "damping")


class NormalLmResult(NamedTuple):
    """Outcome of a run (costs are mean squared normalised residuals)."""

    theta: np.ndarray  # (P,) the returned parameters (best on validation when there is one)
    iterations: int  # curvature builds (outer iterations)
    evaluations: int  # forward passes of the training set (one per tried step + the first)
    rejected: int  # steps rejected (the damping grew)
    reason: str  # one of STOP_REASONS
    damping: tuple[float, ...]  # mu after each outer iteration
    train_cost: tuple[float, ...]  # training cost after each outer iteration
    validation_cost: tuple[float, ...]  # validation cost after each (empty without a split)
    seconds: float  # time [s] on ``clock``
    times: tuple[float, ...] = ()  # clock time [s] since the start after each iteration


class NormalEquationsLm:
    """Levenberg-Marquardt on J^T J accumulated in batches (module doc).

    Args:
        batch: samples per Jacobian batch (memory: batch * n_out * P floats).
        max_iterations: outer iterations (curvature builds) at most.
        time_budget: wall time [s] (0: none); checked before each iteration.
        initial_damping: mu at the start (relative to diag(J^T J)).
        max_damping: stop when mu grows past it (no step lowers the cost).
        patience: stop after this many accepted steps without a better validation cost.
        curvature_samples: samples J^T J is built from each iteration (0: all).
        curvature_dtype: 'float64' | 'float32' for J^T J.
        gradient_tol: stop when max |J^T r| / n < it.
        step_tol: stop when ||delta|| < step_tol * (||theta|| + step_tol).
        seed: seed of the curvature subsets.
        clock: wall clock [s] (``time.perf_counter``; tests pass their own).
    """

    def __init__(self, batch: int = 1000, max_iterations: int = 1000, time_budget: float = 0.0,
                 initial_damping: float = 1e-3, max_damping: float = 1e10, patience: int = 20,
                 curvature_samples: int = 0, curvature_dtype: str = "float64",
                 gradient_tol: float = 1e-12, step_tol: float = 1e-10, seed: int = 0,
                 clock: Callable[[], float] = time.perf_counter):
        if curvature_dtype not in ("float64", "float32"):
            raise InvalidInput(f"curvature_dtype: expected 'float64' or 'float32', got "
                               f"{curvature_dtype!r}")
        self.batch = max(1, int(batch))
        self.max_iterations = int(max_iterations)
        self.time_budget = float(time_budget)
        self.initial_damping = float(initial_damping)
        self.max_damping = float(max_damping)
        self.patience = int(patience)
        self.curvature_samples = int(curvature_samples)
        self.dtype = np.dtype(curvature_dtype)
        self.gradient_tol = float(gradient_tol)
        self.step_tol = float(step_tol)
        self.seed = int(seed)
        self.clock = clock

    # ------------------------------------------------------------------ pieces
    def curvature(self, net: TanhMlp, xn: np.ndarray, full: bool = True) -> np.ndarray:
        """J^T J (P, P) of the normalised outputs over the inputs ``xn`` (n, n_in), summed over
        batches with ``syrk``: the full symmetric matrix, or with ``full=False`` only its
        lower triangle (float64, Fortran order: what the Cholesky and ``symv`` read)."""
        p = net.n_params
        syrk = blas.ssyrk if self.dtype == np.float32 else blas.dsyrk
        a = np.zeros((p, p), dtype=self.dtype, order="F")
        for k in range(0, len(xn), self.batch):
            jb = net.weight_jacobian(xn[k:k + self.batch], dtype=self.dtype)
            # jb is C-ordered (rows, P): jb.T is Fortran-ordered, so syrk reads it in place
            a = syrk(1.0, jb.T, beta=1.0, c=a, trans=0, lower=1, overwrite_c=1)
        a = np.asarray(a, dtype=float, order="F")
        if not full:
            return a
        low = np.tril(a)
        return low + np.tril(low, -1).T

    @staticmethod
    def cost(net: TanhMlp, xn: np.ndarray, yn: np.ndarray) -> float:
        """Mean squared normalised residual over samples and outputs."""
        return float(np.mean((net.predict_normalised(xn) - yn) ** 2))

    # ------------------------------------------------------------------ the loop
    def run(self, net: TanhMlp, xn: np.ndarray, yn: np.ndarray,
            xv: np.ndarray | None = None, yv: np.ndarray | None = None) -> NormalLmResult:
        """Minimise the squared normalised residuals of ``net`` on (xn, yn) from its current
        parameters; (xv, yv), when given, is the validation split for early stopping."""
        t0 = self.clock()
        rng = np.random.default_rng(self.seed)
        work = net.with_params(net.params())
        theta = work.params()
        n = len(xn)
        m = yn.size
        has_val = xv is not None and yv is not None and len(xv) > 0
        acts = work._forward(xn)
        r = acts[-1] - yn
        cost = float(np.mean(r ** 2))
        evaluations, rejected, iterations = 1, 0, 0
        mu, nu = self.initial_damping, 2.0
        best_theta, best_val = theta.copy(), np.inf
        since_best = 0
        damping: list[float] = []
        costs: list[float] = []
        vals: list[float] = []
        times: list[float] = []
        reason = "iterations"
        last = 0.0
        while iterations < self.max_iterations:
            now = self.clock()
            if self.time_budget > 0 and now - t0 + last > self.time_budget:
                reason = "time budget"
                break
            g = work.weight_vjp(xn, r.ravel(), acts)  # J^T r over all samples
            if np.max(np.abs(g)) / m < self.gradient_tol:
                reason = "gradient"
                break
            if 0 < self.curvature_samples < n:
                pick = rng.choice(n, self.curvature_samples, replace=False)
                a = self.curvature(work, xn[pick], full=False) * (n / self.curvature_samples)
            else:
                a = self.curvature(work, xn, full=False)
            diag = np.diag(a).copy()
            d = diag + 1e-9 * max(float(np.mean(diag)), 1e-300)
            iterations += 1
            accepted = False
            while True:
                damped = a.copy(order="F")
                damped[np.diag_indices_from(damped)] += mu * d
                try:
                    factor = cho_factor(damped, lower=True, overwrite_a=True,
                                        check_finite=False)
                    delta = -cho_solve(factor, g, check_finite=False)
                except LinAlgError:
                    mu, nu = mu * nu, nu * 2.0
                    rejected += 1
                    if mu > self.max_damping:
                        break
                    continue
                if np.linalg.norm(delta) < self.step_tol * (np.linalg.norm(theta) + self.step_tol):
                    reason = "step"
                    break
                trial = theta + delta
                work.set_params(trial)
                t_acts = work._forward(xn)
                evaluations += 1
                t_r = t_acts[-1] - yn
                t_cost = float(np.mean(t_r ** 2))
                # predicted reduction of the sum of squares by the linear model
                predicted = -(g @ delta) - 0.5 * float(delta @ blas.dsymv(1.0, a, delta,
                                                                          lower=1))
                actual = 0.5 * m * (cost - t_cost)
                if np.isfinite(t_cost) and t_cost < cost:
                    rho = actual / predicted if predicted > 0 else 0.0
                    mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
                    nu = 2.0
                    theta, acts, r, cost = trial, t_acts, t_r, t_cost
                    accepted = True
                    break
                work.set_params(theta)
                rejected += 1
                mu, nu = mu * nu, nu * 2.0
                if mu > self.max_damping:
                    break
            damping.append(mu)
            costs.append(cost)
            last = self.clock() - now
            times.append(now + last - t0)
            if not accepted:
                if reason != "step":
                    reason = "damping"
                break
            if has_val:
                val = self.cost(work, xv, yv)
                vals.append(val)
                if val < best_val:
                    best_val, best_theta, since_best = val, theta.copy(), 0
                else:
                    since_best += 1
                    if since_best >= self.patience:
                        reason = "validation"
                        break
        if has_val and np.isfinite(best_val):
            out = best_theta
        else:
            out = theta
        return NormalLmResult(out, iterations, evaluations, rejected, reason, tuple(damping),
                              tuple(costs), tuple(vals), self.clock() - t0,
                              tuple(times))
