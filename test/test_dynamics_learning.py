"""Filters and the incremental random-features ridge regression (RFRR, Sect. 3.1)."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.dynamics.butterworth_low_pass import ButterworthLowPass
from icub_pmp.dynamics.ft_dynamics_model import FtDynamicsModel
from icub_pmp.dynamics.joint_state_filter import JointStateFilter
from icub_pmp.dynamics.random_features_ridge import RandomFeaturesRidge
from icub_pmp.dynamics.wrench_estimator import WrenchEstimator
from icub_pmp.dynamics.wrench_estimator_config import WrenchEstimatorConfig
from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.robot_model import IcubModel


def test_butterworth_passes_dc_and_cuts_high_frequencies():
    """Unit DC gain from the first sample (no transient); a tone at 10x the cut-off is
    attenuated below 2 % (2nd order: -40 dB/decade)."""
    f = ButterworthLowPass(2, 20.0, 1000.0)
    for _ in range(5):
        np.testing.assert_allclose(f(np.array([1.0, -2.0])), [1.0, -2.0], atol=1e-12)
    g = ButterworthLowPass(1, 20.0, 1000.0)
    t = np.arange(2000) / 1000.0
    out = np.array([g(np.array([np.sin(2 * np.pi * 200.0 * tk)]))[0] for tk in t])
    assert np.max(np.abs(out[500:])) < 0.02
    with pytest.raises(InvalidInput, match="Nyquist"):
        ButterworthLowPass(1, 600.0, 1000.0)


def test_butterworth_matches_scipy_lfilter():
    """Sample by sample the filter equals scipy's lfilter of the same 2nd-order Butterworth
    started at the first sample's steady state (the stacked one-product update is exact)."""
    from scipy import signal

    f = ButterworthLowPass(20, 30.0, 1000.0)
    x = np.random.default_rng(0).normal(size=(500, 20)).cumsum(axis=0)
    y = np.array([f(xk) for xk in x])
    b, a = signal.butter(2, 30.0, fs=1000.0)
    ref, _ = signal.lfilter(b, a, x, axis=0, zi=signal.lfilter_zi(b, a)[:, None] * x[0])
    np.testing.assert_allclose(y, ref, atol=1e-9)


def test_joint_state_filter_differentiates():
    """For q = t^2 sampled at 1 kHz the filter returns v = 2t and a = 2 once settled
    (within the filter lag)."""
    f = JointStateFilter(1, 1000.0, velocity_cutoff_hz=0.0, acceleration_cutoff_hz=30.0)
    for k in range(600):
        t = k * 1e-3
        s = f.update(t, np.array([t * t]), np.array([2 * t]))
    assert s.v[0] == pytest.approx(2 * 0.599, abs=1e-9)
    assert s.a[0] == pytest.approx(2.0, abs=0.02)
    g = JointStateFilter(1, 1000.0, velocity_cutoff_hz=50.0, acceleration_cutoff_hz=30.0)
    for k in range(600):
        t = k * 1e-3
        s = g.update(t, np.array([t * t]))  # velocity by differentiation
    assert s.v[0] == pytest.approx(2 * 0.599, abs=0.02)


def test_rls_update_equals_batch_ridge():
    """N incremental RLS updates give the same weights as the batch ridge solution."""
    rng = np.random.default_rng(0)
    x = rng.normal(size=(300, 4))
    y = np.stack([np.sin(x[:, 0]) + x[:, 1] ** 2, np.cos(x[:, 2] * x[:, 3])], axis=1)
    inc = RandomFeaturesRidge(4, 2, n_features=100, bandwidth=1.0, ridge=0.1, seed=5)
    bat = RandomFeaturesRidge(4, 2, n_features=100, bandwidth=1.0, ridge=0.1, seed=5)
    for xi, yi in zip(x, y):
        inc.update(xi, yi)
    bat.fit_batch(x, y)
    xt = rng.normal(size=(20, 4))
    for xi in xt:
        np.testing.assert_allclose(inc.predict(xi), bat.predict(xi), atol=1e-6)


def test_features_approximate_the_rbf_kernel():
    """phi(x) . phi(y) approximates exp(-|x - y|^2 / (2 sigma^2)) (error ~ 1/sqrt(D))."""
    r = RandomFeaturesRidge(3, 1, n_features=4000, bandwidth=0.8, seed=1)
    rng = np.random.default_rng(2)
    for _ in range(10):
        x, y = rng.normal(size=3) * 0.5, rng.normal(size=3) * 0.5
        k = np.exp(-np.sum((x - y) ** 2) / (2 * 0.8**2))
        assert r.features(x) @ r.features(y) == pytest.approx(k, abs=0.05)


def test_rfrr_learns_a_nonlinear_function_incrementally():
    """Trained online on a smooth 2-D function, RFRR's held-out nMSE falls below 1 %."""
    rng = np.random.default_rng(4)
    r = RandomFeaturesRidge(2, 1, n_features=200, bandwidth=0.7, ridge=1e-3, seed=0)

    def fn(x):
        return np.array([np.sin(2 * x[0]) * np.cos(x[1])])

    for _ in range(3000):
        x = rng.uniform(-1.5, 1.5, 2)
        r.update(x, fn(x))
    xt = rng.uniform(-1.5, 1.5, (500, 2))
    yt = np.array([fn(x) for x in xt])[:, 0]
    pred = np.array([r.predict(x)[0] for x in xt])
    assert np.mean((pred - yt) ** 2) / np.var(yt) < 0.01


def test_rfrr_corrects_a_forearm_mass_mismatch():
    """With a 10 % heavier left forearm in the estimator's model, learning the residual on
    15 s of contact-free motion cuts the FT prediction nMSE on the next 2.5 s (new joint
    combinations of the same motion) at least fourfold (the truth is the nominal model)."""
    truth = FtDynamicsModel()
    icub = IcubModel()
    cfg = WrenchEstimatorConfig(
        ft_convention="parent_on_child", rfrr_enabled=True, rfrr_learning=True,
        mismatch_link="l_forearm", mismatch_scale=1.1, rfrr_features=200,
        rate_hz=200.0, acceleration_cutoff_hz=20.0,
    )
    est = WrenchEstimator(cfg)
    rng = np.random.default_rng(7)
    q0 = icub.posture("rest")
    freqs = rng.uniform(0.2, 0.6, icub.nq)
    amp = 0.25

    def sample(t):
        w = 2 * np.pi * freqs
        q = q0 + amp * np.sin(w * t)
        v = amp * w * np.cos(w * t)
        a = -amp * w * w * np.sin(w * t)
        return q, v, truth.rnea(q, v, a).sensor

    t = 0.0
    for _ in range(3000):  # training: 15 s of a slow motion sampled every 5 ms
        q, v, ft = sample(t)
        est.update(t, q, v, ft)
        t += 0.005
    est.rfrr_learning = False
    err_model, err_rfrr, meas = [], [], []
    for _ in range(500):  # test: the continuation of the motion
        q, v, fts = sample(t)
        ft = fts["left"]
        e = est.update(t, q, v, fts)
        model_only = est.predict_ft(e.state.q, e.state.v, e.state.a)["left"]
        err_model.append(ft - model_only)
        err_rfrr.append(ft - e.ft_predicted["left"])
        meas.append(ft)
        t += 0.005
    var = np.var(np.array(meas), axis=0)
    nmse_model = np.mean(np.mean(np.array(err_model) ** 2, axis=0) / var)
    nmse_rfrr = np.mean(np.mean(np.array(err_rfrr) ** 2, axis=0) / var)
    assert nmse_rfrr < 0.25 * nmse_model
