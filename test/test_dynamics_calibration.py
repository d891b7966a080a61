"""FtOffsetCalibration: the mean FT residual of the last N still samples, refused with the
reason when the robot moved or too few samples came."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.dynamics import CalibrationError, FtOffsetCalibration


def _cal(n: int = 50) -> FtOffsetCalibration:
    return FtOffsetCalibration(n, 3, 2, 0.01, ("a", "b", "c"))


def test_mean_residual_of_the_last_window():
    """Offsets = mean residual of the last N samples (older ones are forgotten)."""
    cal = _cal()
    rng = np.random.default_rng(0)
    for _ in range(30):
        cal.add(np.zeros(3), np.full((2, 6), 100.0))  # pushed out of the window
    offset = rng.normal(size=(2, 6))
    for _ in range(50):
        cal.add(np.zeros(3), offset + rng.normal(scale=0.1, size=(2, 6)))
    r = cal.calibrate()
    assert r.samples == 50 and r.spread == 0.0
    assert np.allclose(r.offsets, offset, atol=5 * 0.1 / np.sqrt(50))


def test_too_few_samples_is_refused():
    """Before N samples the calibration says how many it has."""
    cal = _cal()
    for _ in range(10):
        cal.add(np.zeros(3), np.zeros((2, 6)))
    with pytest.raises(CalibrationError, match="only 10 of the 50"):
        cal.calibrate()


def test_motion_is_refused_naming_the_joint():
    """A joint moving more than the tolerance in the window refuses the calibration."""
    cal = _cal()
    for k in range(50):
        cal.add(np.array([0.0, 0.001 * k, 0.0]), np.zeros((2, 6)))
    with pytest.raises(CalibrationError, match="joint b by 2.81 deg"):
        cal.calibrate()
