"""The node parameters that go with a simulator realism preset.

The simulator's ``realism.preset`` (``config/sim_bridge.yaml``) is a property of the robot the
graph runs on, and two other nodes are configured for that robot: the impedance controller
adds back the joint friction the ``icub`` robot has (``friction_compensation``, eqs 4-5 of the
force paper; on the frictionless ``ideal`` simulator that is a model error), and the motion
segmenter triangulates with the eyes as calibrated (``eye_calibration_file``: the ``icub``
preset's cameras differ from camera_info; docs/decisions/0057). The shipped config files are
for ``icub`` (docs/decisions/0062); a graph on ``ideal`` needs the other two turned back, which
:func:`realism_parameters` gives. No rclpy import.
"""

from __future__ import annotations

__all__ = ["ICUB_EYE_CALIBRATION", "PRESETS", "realism_parameters", "with_realism"]

#: the eye calibration of the ``icub`` preset's robot (seed 0), relative to the repository
ICUB_EYE_CALIBRATION = "config/eye_calibration/icub_seed0.yaml"

PRESETS = ("ideal", "icub")


def realism_parameters(preset: str) -> dict[str, dict[str, object]]:
    """{node: {parameter: value}} for a graph on the simulator's ``preset`` (``ideal`` or
    ``icub``): the simulator's preset, the controller's friction compensation and the motion
    segmenter's eye calibration. Raises ValueError for another preset."""
    if preset not in PRESETS:
        raise ValueError(f"unknown realism preset {preset!r}: expected one of {PRESETS}")
    icub = preset == "icub"
    return {
        "sim_bridge": {"realism.preset": preset},
        "impedance_controller": {"friction_compensation": icub},
        "motion_segmenter": {"eye_calibration_file": ICUB_EYE_CALIBRATION if icub else ""},
    }


def with_realism(preset: str, params: dict[str, dict[str, object]] | None = None,
                 nodes: list[str] | tuple[str, ...] | None = None
                 ) -> dict[str, dict[str, object]]:
    """``params`` ({node: {parameter: value}}, not changed) with :func:`realism_parameters`
    of ``preset`` under them (``params`` win where both set a parameter), for the nodes in
    ``nodes`` (default: every node of the preset's parameters and of ``params``)."""
    out: dict[str, dict[str, object]] = {}
    for node, values in realism_parameters(preset).items():
        if nodes is None or node in nodes:
            out[node] = dict(values)
    for node, values in (params or {}).items():
        out.setdefault(node, {}).update(values)
    return out
