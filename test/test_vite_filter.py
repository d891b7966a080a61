"""ViteFilter (the VITE dynamics of Table 2's baseline): the paper's alpha 0.008 and beta
0.002 per ms make a critically damped reach that covers 90 % of a step in about 0.97 s without
overshoot; bad settings are refused."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.cartesian.vite_filter import ViteFilter
from icub_pmp.errors import InvalidInput


def test_a_step_is_covered_critically_damped_in_about_a_second():
    Ts = 0.001
    f = ViteFilter(2, Ts)
    x, target = np.zeros(2), np.array([0.1, -0.2])
    xs = []
    for _ in range(4000):
        x = x + Ts * f.step(target - x)
        xs.append(x.copy())
    xs = np.array(xs)
    frac = xs / target
    t90 = (np.argmax(frac[:, 0] >= 0.9) + 1) * Ts
    assert 0.9 < t90 < 1.05, t90
    assert frac.max() <= 1.0 + 1e-3  # no overshoot
    assert np.allclose(xs[-1], target, atol=1e-4)


@pytest.mark.parametrize("kw", [{"Ts": 0.0}, {"alpha": -1.0}, {"beta": float("nan")},
                                {"Ts": 0.2}])
def test_bad_settings_are_refused(kw):
    args = {"n": 3, "Ts": 0.01} | kw
    with pytest.raises(InvalidInput):
        ViteFilter(**args)
