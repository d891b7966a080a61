"""The node parameters that go with a realism preset (icub_pmp.graph.realism_parameters)."""

from __future__ import annotations

import pytest

from icub_pmp.config import repo_root
from icub_pmp.graph import ICUB_EYE_CALIBRATION, realism_parameters, with_realism


def test_each_preset_sets_the_simulator_the_friction_compensation_and_the_eyes():
    icub, ideal = realism_parameters("icub"), realism_parameters("ideal")
    assert icub["sim_bridge"]["realism.preset"] == "icub"
    assert icub["impedance_controller"]["friction_compensation"] is True
    assert icub["motion_segmenter"]["eye_calibration_file"] == ICUB_EYE_CALIBRATION
    assert (repo_root() / ICUB_EYE_CALIBRATION).is_file()
    assert ideal["sim_bridge"]["realism.preset"] == "ideal"
    assert ideal["impedance_controller"]["friction_compensation"] is False
    assert ideal["motion_segmenter"]["eye_calibration_file"] == ""


def test_given_parameters_win_and_are_not_changed():
    given = {"sim_bridge": {"mode": "lockstep"},
             "impedance_controller": {"friction_compensation": True}}
    out = with_realism("ideal", given)
    assert out["sim_bridge"] == {"realism.preset": "ideal", "mode": "lockstep"}
    assert out["impedance_controller"]["friction_compensation"] is True
    assert given == {"sim_bridge": {"mode": "lockstep"},
                     "impedance_controller": {"friction_compensation": True}}
    assert set(with_realism("icub", nodes=["sim_bridge"])) == {"sim_bridge"}


def test_an_unknown_preset_is_refused_by_name():
    with pytest.raises(ValueError, match="real"):
        realism_parameters("real")
