"""damped_least_squares_step: the DLS iteration shared by the PMP and Cartesian baselines."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.kinematics.dls_step import damped_least_squares_step


@pytest.mark.parametrize("m,n", [(3, 7), (6, 10), (6, 4)])
def test_step_is_the_damped_least_squares_solution(m, n):
    """dq minimises |J dq - e|^2 + mu^2 |dq|^2 (lstsq of [J; mu I] dq = [e; 0])."""
    rng = np.random.default_rng(m * 100 + n)
    J = rng.normal(size=(m, n))
    e = rng.normal(size=m) * 0.01
    mu = 0.05
    dq = damped_least_squares_step(J, e, mu, max_step=10.0)
    expected = np.linalg.lstsq(np.vstack([J, mu * np.eye(n)]),
                               np.concatenate([e, np.zeros(n)]), rcond=None)[0]
    np.testing.assert_allclose(dq, expected, atol=1e-12)


def test_step_is_capped_in_norm_keeping_its_direction():
    rng = np.random.default_rng(1)
    J = rng.normal(size=(3, 7))
    e = np.array([1.0, -2.0, 0.5])
    free = damped_least_squares_step(J, e, 0.02, max_step=1e9)
    capped = damped_least_squares_step(J, e, 0.02, max_step=0.1)
    assert np.linalg.norm(free) > 0.1
    assert np.linalg.norm(capped) == pytest.approx(0.1)
    np.testing.assert_allclose(capped / 0.1, free / np.linalg.norm(free), atol=1e-12)


def test_singular_jacobian_gives_a_finite_damped_step():
    """A rank-deficient J (a stretched-out arm) still gives a finite, bounded step."""
    J = np.zeros((3, 7))
    J[0, :] = 1.0  # rank 1
    dq = damped_least_squares_step(J, np.array([0.01, 0.02, -0.01]), 0.02, max_step=0.5)
    assert np.all(np.isfinite(dq))
    assert np.linalg.norm(dq) <= 0.5 + 1e-12
