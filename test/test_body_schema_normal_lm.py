"""Levenberg-Marquardt on the normal equations (``NormalEquationsLm``, ``lm-normal``): each test
states a property the body network's trainer must have (decision record 0042)."""

from __future__ import annotations

import numpy as np
import pytest
from test_body_schema_core import MM, planar_fk  # the planar 2-link arm (0.30 + 0.25 m)

from icub_pmp.body_schema import BodyNetwork, LmTrainer, LmTrainerConfig, TanhMlp
from icub_pmp.body_schema.normal_equations_lm import NormalEquationsLm
from icub_pmp.errors import ConfigError, InvalidInput


def planar_problem(n: int, hidden=(10, 10), seed: int = 0):
    """A fresh network of the planar arm and its normalised training data (xn, yn)."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-1.4, 1.4, (n, 2))
    y = planar_fk(q)
    scale = y.std(axis=0)
    scale[scale < 1e-12] = 1.0
    net = TanhMlp((2,) + tuple(hidden) + (3,), x_mean=q.mean(0), x_scale=q.std(0),
                  y_mean=y.mean(0), y_scale=scale, seed=seed)
    return net, net.normalise_x(q), net.normalise_y(y)


def test_lm_normal_learns_the_planar_arm():
    """``lm-normal`` fits the 2-link arm's forward kinematics to sub-millimetre accuracy on
    postures it never saw (links 0.30 + 0.25 m), like MINPACK's LM does."""
    rng = np.random.default_rng(0)
    q = rng.uniform(-1.4, 1.4, (400, 2))
    trainer = LmTrainer(LmTrainerConfig(method="lm-normal", max_evaluations=300,
                                        validation_fraction=0.1))
    net, report = BodyNetwork.train("right", ("j1", "j2"), q, planar_fk(q), [-1.4, -1.4],
                                    [1.4, 1.4], "tip", hidden=(10, 10), trainer=trainer)
    qt = np.random.default_rng(9).uniform(-1.4, 1.4, (500, 2))
    err = np.linalg.norm(net.position(qt) - planar_fk(qt), axis=1)
    assert report.rmse < 0.5 * MM
    assert report.validation_rmse < 1.0 * MM
    assert np.sqrt(np.mean(err ** 2)) < 1.0 * MM
    assert report.iterations >= 1 and report.message in ("iterations", "validation", "gradient",
                                                         "step", "damping")


def test_curvature_is_jtj_in_any_batching_and_precision():
    """The accumulated curvature equals J^T J of the dense residual Jacobian, whatever the batch
    size; in float32 it agrees to float32 precision."""
    net, xn, _ = planar_problem(37)
    jac = net.weight_jacobian(xn)
    exact = jac.T @ jac
    for batch in (1, 5, 37, 100):
        a = NormalEquationsLm(batch=batch).curvature(net, xn)
        assert np.allclose(a, exact, rtol=1e-12, atol=1e-10)
    a32 = NormalEquationsLm(batch=8, curvature_dtype="float32").curvature(net, xn)
    assert np.max(np.abs(a32 - exact)) < 1e-5 * np.max(np.abs(exact))


def test_damping_grows_on_bad_steps_and_shrinks_on_good_ones():
    """Marquardt's damping adapts: from a vanishing damping the first Gauss-Newton steps of the
    untrained network overshoot, are rejected and raise mu; from a huge damping the accepted
    steps lower it (by up to 3x each) toward Gauss-Newton, and every iteration lowers the
    cost."""
    net, xn, yn = planar_problem(200, hidden=(20, 20), seed=3)
    small = NormalEquationsLm(max_iterations=30, initial_damping=1e-12).run(net, xn, yn)
    assert small.rejected > 0
    assert max(small.damping) > 1e-6
    big = NormalEquationsLm(max_iterations=15, initial_damping=1e4).run(net, xn, yn)
    assert big.damping[-1] < 1e4 * 1e-3
    assert big.train_cost[-1] < 0.1 * big.train_cost[0]
    assert list(big.train_cost) == sorted(big.train_cost, reverse=True)


def test_time_budget_stops_before_an_overrunning_iteration():
    """With a time budget the solver starts no iteration that its last iteration's duration says
    would overrun the budget (a clock that advances one second per reading: deterministic)."""
    ticks = iter(range(10 ** 6))
    net, xn, yn = planar_problem(100)
    res = NormalEquationsLm(max_iterations=1000, time_budget=20.0,
                            clock=lambda: float(next(ticks))).run(net, xn, yn)
    assert res.reason == "time budget"
    assert 1 <= res.iterations < 20
    assert res.seconds - 20.0 < res.seconds / res.iterations  # less than one iteration over


def test_validation_split_returns_the_best_weights():
    """With a validation split the returned weights are those of the best validation error seen,
    and an over-parameterised network on few samples stops on it (early stopping)."""
    net, xn, yn = planar_problem(60, hidden=(30, 30), seed=5)
    xv, yv = xn[40:], yn[40:]
    res = NormalEquationsLm(max_iterations=400, patience=5, initial_damping=1e-6,
                            gradient_tol=0.0, step_tol=0.0).run(net, xn[:40], yn[:40], xv, yv)
    best = net.with_params(res.theta)
    assert NormalEquationsLm.cost(best, xv, yv) == pytest.approx(min(res.validation_cost))
    assert res.reason == "validation"


def test_lm_normal_continues_from_a_trained_network():
    """Continued training (the online adaptation path) starts from the given weights: after one
    iteration the error is far below that of a fresh network's first iteration."""
    rng = np.random.default_rng(2)
    q = rng.uniform(-1.4, 1.4, (300, 2))
    cfg = dict(method="lm-normal", validation_fraction=0.0)
    net, _ = BodyNetwork.train("right", ("j1", "j2"), q, planar_fk(q), [-1.4] * 2, [1.4] * 2,
                               "tip", hidden=(10, 10),
                               trainer=LmTrainer(LmTrainerConfig(max_evaluations=200, **cfg)))
    one = LmTrainer(LmTrainerConfig(max_evaluations=1, **cfg))
    cont, rep_cont = BodyNetwork.train("right", ("j1", "j2"), q, planar_fk(q), [-1.4] * 2,
                                       [1.4] * 2, "tip", hidden=(10, 10), trainer=one,
                                       initial=net)
    _, rep_fresh = BodyNetwork.train("right", ("j1", "j2"), q, planar_fk(q), [-1.4] * 2,
                                     [1.4] * 2, "tip", hidden=(10, 10), trainer=one)
    assert rep_cont.rmse < 0.1 * rep_fresh.rmse
    assert np.isnan(rep_cont.validation_rmse)


def test_bad_settings_are_rejected():
    """Out-of-range settings of the new trainer name the field."""
    for kwargs, field in (({"batch": 0}, "batch"), ({"validation_fraction": 0.5},
                                                     "validation_fraction"),
                          ({"patience": 0}, "patience"), ({"curvature_samples": -1},
                                                          "curvature_samples"),
                          ({"curvature_dtype": "float16"}, "curvature_dtype"),
                          ({"initial_damping": 0.0}, "initial_damping"),
                          ({"budget_clock": "sundial"}, "budget_clock")):
        with pytest.raises(ConfigError, match=field):
            LmTrainerConfig(method="lm-normal", **kwargs)
    with pytest.raises(InvalidInput, match="curvature_dtype"):
        NormalEquationsLm(curvature_dtype="half")


def test_subsampled_curvature_still_converges():
    """With J^T J built from a random quarter of the samples each iteration (the bench's
    subsampled Gauss-Newton), the gradient and the acceptance test on all samples still drive
    the training error down by orders of magnitude, never up."""
    net, xn, yn = planar_problem(200, seed=4)
    res = NormalEquationsLm(max_iterations=40, curvature_samples=50).run(net, xn, yn)
    start = NormalEquationsLm.cost(net, xn, yn)
    assert res.train_cost[-1] < 1e-3 * start
    assert list(res.train_cost) == sorted(res.train_cost, reverse=True)


def test_validation_split_is_kept_when_samples_are_appended():
    """Online adaptation trains again on a grown dataset: the first samples' split is the same,
    so no sample fitted before becomes a validation sample; about the asked share is held out."""
    from icub_pmp.body_schema.lm_trainer import validation_split

    val_a, fit_a = validation_split(3200, 0.1, 7)
    val_b, fit_b = validation_split(6400, 0.1, 7)
    np.testing.assert_array_equal(val_b[val_b < 3200], val_a)
    np.testing.assert_array_equal(fit_b[fit_b < 3200], fit_a)
    assert 0.08 < len(val_b) / 6400 < 0.12
    assert len(validation_split(5, 0.0, 1)[0]) == 0
