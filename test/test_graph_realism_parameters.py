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


@pytest.mark.parametrize("preset", ["ideal", "icub"])
def test_each_preset_survives_the_command_line(preset, ros_domain_id):
    """The preset's parameters given as ``-p NAME:=VALUE`` (how NodeGraph and NodeProcess
    start nodes) reach a node with their type and value: the ideal preset's empty
    ``eye_calibration_file`` was a parse error of rcl before it was quoted."""
    import rclpy
    from rclpy.context import Context

    from icub_pmp.graph import param_text

    for node_name, values in realism_parameters(preset).items():
        args = ["--ros-args"] + [a for k, v in values.items()
                                 for a in ("-p", f"{k}:={param_text(v)}")]
        ctx = Context()
        rclpy.init(args=args, context=ctx)
        try:
            node = rclpy.create_node(node_name, context=ctx,
                                     automatically_declare_parameters_from_overrides=True)
            got = {k: node.get_parameter(k).value for k in values}
            node.destroy_node()
        finally:
            rclpy.shutdown(context=ctx)
        assert got == values


@pytest.mark.parametrize("text", ["", "true", "1.5", "null", "it's", "a: b", " x", "[a]"])
def test_string_parameters_keep_their_text(text, ros_domain_id):
    import rclpy
    from rclpy.context import Context

    from icub_pmp.graph import param_text

    ctx = Context()
    rclpy.init(args=["--ros-args", "-p", f"s:={param_text(text)}"], context=ctx)
    try:
        node = rclpy.create_node("param_text_probe", context=ctx,
                                 automatically_declare_parameters_from_overrides=True)
        value = node.get_parameter("s").value
        node.destroy_node()
    finally:
        rclpy.shutdown(context=ctx)
    assert value == text
