"""Levenberg-Marquardt training of a :class:`TanhMlp` through ``scipy.optimize.least_squares``.

The residuals are the normalised output errors ``(y_n(x; theta) - y_n)``, their Jacobian with
respect to the weights is the network's analytic one (:meth:`TanhMlp.weight_jacobian`). Three
solvers, all scipy's:

- ``lm``: MINPACK's Levenberg-Marquardt on the dense Jacobian (QR of the whole (n*3, P)
  matrix each iteration: exact and robust, slow beyond a few thousand samples);
- ``trf``: scipy's trust-region reflective, the Levenberg-Marquardt step solved exactly
  (``tr_solver="exact"``) on the dense Jacobian;
- ``trf-lsmr``: trust-region reflective with the step solved by LSMR on the Jacobian as a
  ``LinearOperator`` (forward- and back-propagation, never formed): memory O(n + P)
  (decision record 0040);
- ``lm-normal``: Levenberg-Marquardt on the normal equations, J^T J (P x P) accumulated over
  sample batches and solved by Cholesky with Marquardt's adaptive damping, early stopping on
  a validation split (:class:`NormalEquationsLm`, decision record 0042).

A time budget stops ``trf`` / ``trf-lsmr`` through scipy's callback (StopIteration) and
``lm-normal`` before an iteration that would overrun it; ``lm`` is bounded by its evaluation
budget only.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any, NamedTuple

import numpy as np
from scipy.optimize import least_squares
from scipy.sparse.linalg import LinearOperator

from icub_pmp.body_schema.normal_equations_lm import NormalEquationsLm
from icub_pmp.body_schema.tanh_mlp import TanhMlp
from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError, InvalidInput

__all__ = ["LmTrainerConfig", "TrainingReport", "LmTrainer", "check_dataset",
           "validation_split"]

METHODS = ("lm", "trf", "trf-lsmr", "lm-normal")


@dataclasses.dataclass(frozen=True)
class LmTrainerConfig(ConfigBase):
    """Settings of :class:`LmTrainer`.

    Attributes:
        method: ``lm`` | ``trf`` | ``trf-lsmr`` | ``lm-normal`` (module doc; ``lm-normal``
            by default, decision 0054).
        max_evaluations: residual evaluations at most (scipy's ``max_nfev``; for ``lm-normal``
            the number of J^T J builds, i.e. iterations).
        time_budget: time [s] on ``budget_clock`` after which ``trf``/``trf-lsmr``/
            ``lm-normal`` stop (0: none).
        ftol, xtol, gtol: scipy's termination tolerances.
        seed: seed of the initial weights.
        lsmr_iterations: LSMR iterations per trust-region step of ``trf-lsmr`` (an inexact
            Levenberg-Marquardt step; scipy's default, min(m, n), costs minutes at 10k
            samples).
        batch: samples per Jacobian batch of ``lm-normal``.
        validation_fraction: share of the samples ``lm-normal`` holds out for early stopping
            (0: none; the returned weights are the best on it); each sample is held out with
            this probability by a seeded draw of its own, so appending samples keeps the split
            of the earlier ones.
        patience: accepted ``lm-normal`` steps without a better validation error before it
            stops.
        curvature_samples: samples J^T J is built from per ``lm-normal`` iteration (0: all).
        curvature_dtype: ``float64`` | ``float32`` precision of ``lm-normal``'s J^T J.
        initial_damping: ``lm-normal``'s starting mu (relative to diag(J^T J)).
        budget_clock: ``wall`` | ``cpu``: what the time budget counts (``cpu``:
            this process's CPU time, which a shared machine's load does not inflate; with
            one BLAS thread it equals the wall time of an idle machine).
    """

    method: str = "lm-normal"
    max_evaluations: int = 400
    time_budget: float = 0.0
    ftol: float = 1e-10
    xtol: float = 1e-10
    gtol: float = 1e-10
    seed: int = 0
    lsmr_iterations: int = 40
    batch: int = 1000
    validation_fraction: float = 0.1
    patience: int = 20
    curvature_samples: int = 0
    curvature_dtype: str = "float64"
    initial_damping: float = 1e-3
    budget_clock: str = "wall"

    def validate(self) -> None:
        """Ranges (raise :class:`ConfigError` naming the field)."""
        if self.method not in METHODS:
            raise ConfigError(f"method: expected one of {METHODS}, got {self.method!r}")
        if self.max_evaluations < 1:
            raise ConfigError(f"max_evaluations: expected >= 1, got {self.max_evaluations}")
        if self.time_budget < 0:
            raise ConfigError(f"time_budget: expected >= 0 s, got {self.time_budget}")
        if self.lsmr_iterations < 1:
            raise ConfigError(f"lsmr_iterations: expected >= 1, got {self.lsmr_iterations}")
        if self.batch < 1:
            raise ConfigError(f"batch: expected >= 1, got {self.batch}")
        if not 0.0 <= self.validation_fraction < 0.5:
            raise ConfigError(f"validation_fraction: expected in [0, 0.5), got "
                              f"{self.validation_fraction}")
        if self.patience < 1:
            raise ConfigError(f"patience: expected >= 1, got {self.patience}")
        if self.curvature_samples < 0:
            raise ConfigError(f"curvature_samples: expected >= 0, got {self.curvature_samples}")
        if self.curvature_dtype not in ("float64", "float32"):
            raise ConfigError(f"curvature_dtype: expected 'float64' or 'float32', got "
                              f"{self.curvature_dtype!r}")
        if self.budget_clock not in ("wall", "cpu"):
            raise ConfigError(f"budget_clock: expected 'wall' or 'cpu', got "
                              f"{self.budget_clock!r}")
        if not self.initial_damping > 0:
            raise ConfigError(f"initial_damping: expected > 0, got {self.initial_damping}")



class TrainingReport(NamedTuple):
    """What a training run achieved (errors in the outputs' raw units)."""

    rmse: float  # root mean squared Euclidean output error on the training data
    evaluations: int  # residual evaluations
    seconds: float  # wall time [s]
    status: int  # scipy's status (-2: stopped by the time budget); lm-normal: 0
    message: str  # scipy's message; lm-normal: why it stopped
    validation_rmse: float = float("nan")  # on lm-normal's validation split
    iterations: int = 0  # lm-normal's J^T J builds
    rejected: int = 0  # lm-normal's rejected steps
    damping: tuple[float, ...] = ()  # lm-normal's mu after each iteration
    cpu_seconds: float = float("nan")  # this process's CPU time [s]


def check_dataset(x: np.ndarray, y: np.ndarray, n_in: int, n_out: int
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Validated float copies of inputs (n, n_in) and targets (n, n_out): no empty dataset, no
    NaN/inf, matching lengths (raises :class:`InvalidInput` naming the first bad row)."""
    x = np.array(x, dtype=float)
    y = np.array(y, dtype=float)
    if x.ndim != 2 or x.shape[1] != n_in:
        raise InvalidInput(f"inputs: expected shape (n, {n_in}), got {x.shape}")
    if y.ndim != 2 or y.shape[1] != n_out:
        raise InvalidInput(f"targets: expected shape (n, {n_out}), got {y.shape}")
    if len(x) == 0:
        raise InvalidInput("dataset is empty: no samples to learn from")
    if len(x) != len(y):
        raise InvalidInput(f"dataset: {len(x)} inputs but {len(y)} targets")
    bad = ~(np.all(np.isfinite(x), axis=1) & np.all(np.isfinite(y), axis=1))
    if np.any(bad):
        rows = np.flatnonzero(bad)
        raise InvalidInput(f"dataset: {len(rows)} sample(s) with NaN or infinite values "
                           f"(first at row {rows[0]}); drop them before training")
    return x, y


def validation_split(n: int, fraction: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(validation, fit) indices of ``n`` samples: sample i is held out when draw i of a
    stream seeded with ``seed`` is below ``fraction``. The split of the first n samples does not
    change when samples are appended, so training continued on a grown dataset (online
    adaptation) never validates on samples it fitted before, as a permutation of the grown set
    would (decision 0054). No fit sample left: no validation."""
    pick = np.random.default_rng(seed).random(int(n)) < fraction
    val, fit = np.flatnonzero(pick), np.flatnonzero(~pick)
    if len(fit) == 0:
        return val[:0], np.arange(int(n))
    return val, fit


def _scale(v: np.ndarray) -> np.ndarray:
    s = v.std(axis=0)
    return np.where(s > 1e-12, s, 1.0)


class LmTrainer:
    """Fits a :class:`TanhMlp` to a dataset by Levenberg-Marquardt (module doc)."""

    def __init__(self, config: LmTrainerConfig | None = None):
        self.config = config or LmTrainerConfig()

    def fit(self, hidden: tuple[int, ...], x: np.ndarray, y: np.ndarray,
            initial: TanhMlp | None = None) -> tuple[TanhMlp, TrainingReport]:
        """Train a network ``n_in -> hidden -> n_out`` on (x, y); normalisation from the data
        (mean and standard deviation), or ``initial``'s normalisation and weights when given
        (continued training, e.g. online adaptation)."""
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        if x.ndim != 2 or y.ndim != 2:
            raise InvalidInput(f"inputs and targets: expected 2-D arrays, got {x.shape}, "
                               f"{y.shape}")
        x, y = check_dataset(x, y, x.shape[1], y.shape[1])
        if initial is not None:
            if initial.n_in != x.shape[1] or initial.n_out != y.shape[1]:
                raise InvalidInput(f"initial network maps {initial.n_in} -> {initial.n_out}, "
                                   f"data {x.shape[1]} -> {y.shape[1]}")
            net = initial.with_params(initial.params())
        else:
            net = TanhMlp((x.shape[1],) + tuple(hidden) + (y.shape[1],),
                          x_mean=x.mean(axis=0), x_scale=_scale(x),
                          y_mean=y.mean(axis=0), y_scale=_scale(y), seed=self.config.seed)
        return self._solve(net, net.normalise_x(x), net.normalise_y(y), y)

    def _solve(self, net: TanhMlp, xn: np.ndarray, yn: np.ndarray, y: np.ndarray
               ) -> tuple[TanhMlp, TrainingReport]:
        c = self.config
        if c.method == "lm-normal":
            return self._solve_normal(net, xn, yn, y)
        m = yn.size
        if c.method == "lm" and m < net.n_params:
            raise InvalidInput(f"method 'lm' needs at least as many residuals as weights: "
                               f"{m} < {net.n_params}; add samples or use 'trf'")
        work = net.with_params(net.params())
        cache: dict[str, Any] = {}

        def forward(theta: np.ndarray) -> list[np.ndarray]:
            key = theta.tobytes()
            if cache.get("key") != key:
                work.set_params(theta)
                cache["key"], cache["acts"] = key, work._forward(xn)
            return cache["acts"]

        def residuals(theta: np.ndarray) -> np.ndarray:
            return (forward(theta)[-1] - yn).ravel()

        def dense_jac(theta: np.ndarray) -> np.ndarray:
            work.set_params(theta)
            return work.weight_jacobian(xn)

        def operator_jac(theta: np.ndarray) -> LinearOperator:
            acts = forward(theta)
            fixed = net.with_params(theta)
            return LinearOperator(
                (m, net.n_params), dtype=float,
                matvec=lambda v: fixed.weight_jvp(xn, np.ravel(v), acts),
                rmatvec=lambda u: fixed.weight_vjp(xn, np.ravel(u), acts),
            )

        t0, c0 = time.perf_counter(), time.process_time()
        kwargs: dict[str, Any] = dict(ftol=c.ftol, xtol=c.xtol, gtol=c.gtol,
                                      max_nfev=c.max_evaluations)
        if c.method == "lm":
            kwargs.update(method="lm", jac=dense_jac)
        else:
            if c.time_budget > 0:
                clock = time.process_time if c.budget_clock == "cpu" else time.perf_counter
                b0 = clock()

                def stop(intermediate_result) -> None:  # noqa: ARG001 - scipy's signature
                    if clock() - b0 > c.time_budget:
                        raise StopIteration
                kwargs["callback"] = stop
            if c.method == "trf":
                kwargs.update(method="trf", jac=dense_jac, tr_solver="exact")
            else:
                kwargs.update(method="trf", jac=operator_jac, tr_solver="lsmr", x_scale=1.0,
                              tr_options={"maxiter": c.lsmr_iterations})
        result = least_squares(residuals, net.params(), **kwargs)
        seconds = time.perf_counter() - t0
        out = net.with_params(result.x)
        err = out.predict_normalised(xn) * out.y_scale + out.y_mean - y
        rmse = float(np.sqrt(np.mean(np.sum(err ** 2, axis=1))))
        return out, TrainingReport(rmse, int(result.nfev), seconds, int(result.status),
                                   str(result.message),
                                   cpu_seconds=time.process_time() - c0)

    def _solve_normal(self, net: TanhMlp, xn: np.ndarray, yn: np.ndarray, y: np.ndarray
                      ) -> tuple[TanhMlp, TrainingReport]:
        c = self.config
        val, fit = validation_split(len(xn), c.validation_fraction, c.seed + 1)
        n_val = len(val)
        solver = NormalEquationsLm(
            batch=c.batch, max_iterations=c.max_evaluations, time_budget=c.time_budget,
            initial_damping=c.initial_damping, patience=c.patience,
            curvature_samples=c.curvature_samples, curvature_dtype=c.curvature_dtype,
            gradient_tol=c.gtol, step_tol=c.xtol, seed=c.seed,
            clock=time.process_time if c.budget_clock == "cpu" else time.perf_counter)
        t0, c0 = time.perf_counter(), time.process_time()
        res = solver.run(net, xn[fit], yn[fit], xn[val] if n_val else None,
                         yn[val] if n_val else None)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        out = net.with_params(res.theta)

        def rmse(idx: np.ndarray) -> float:
            err = out.predict_normalised(xn[idx]) * out.y_scale + out.y_mean - y[idx]
            return float(np.sqrt(np.mean(np.sum(err ** 2, axis=1))))

        return out, TrainingReport(
            rmse(fit), res.evaluations, wall, 0, res.reason,
            rmse(val) if n_val else float("nan"), res.iterations, res.rejected, res.damping, cpu)
