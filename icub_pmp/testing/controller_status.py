"""The impedance controller's status (/impedance_controller/status) read by a test probe."""

from __future__ import annotations

import time

from icub_interfaces.msg import ControllerStatus
from icub_pmp.ros.probe import RosProbe
from icub_pmp.ros.qos import LATCHED_QOS

__all__ = ["controller_status", "controller_status_after", "assert_stopped_estimator_holds"]


def controller_status(probe: RosProbe) -> ControllerStatus:
    """The latest /impedance_controller/status (AssertionError when none within 30 s)."""
    s = probe.collect("/impedance_controller/status", ControllerStatus, 1, 30.0,
                      qos=LATCHED_QOS)
    assert s, "no /impedance_controller/status"
    return s[0]


def _stamp(s: ControllerStatus) -> float:
    return s.header.stamp.sec + s.header.stamp.nanosec * 1e-9


def controller_status_after(probe: RosProbe, s0: ControllerStatus, dt: float,
                            timeout: float = 120.0) -> ControllerStatus:
    """The first status stamped ``dt`` s of simulated time after ``s0`` (the status is
    republished once per wall second: on a fast loop two reads close together are the same
    message)."""
    deadline = time.monotonic() + timeout
    s = controller_status(probe)
    while _stamp(s) - _stamp(s0) < dt and time.monotonic() < deadline:
        time.sleep(0.2)
        s = controller_status(probe)
    assert _stamp(s) - _stamp(s0) >= dt, f"no status {dt} s after {_stamp(s0):.3f} s"
    return s


def assert_stopped_estimator_holds(probe: RosProbe, proc) -> None:  # noqa: ANN001 - NodeProcess
    """Stop the wrench estimator on purpose (its live ``enabled: false``: no sample
    processed, nothing published) and check what the controller must do: latch the
    estimator-lost safe hold, say it in ``proc``'s log (the process hosting the controller)
    and on its status topic, and keep answering the simulator."""
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters
    from sensor_msgs.msg import JointState

    value = ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=False)
    req = SetParameters.Request(parameters=[Parameter(name="enabled", value=value)])
    res = probe.call("/wrench_estimator/set_parameters", SetParameters, req)
    assert res.results[0].successful, res.results[0].reason
    assert proc.wait_for_output("estimator lost", 60.0), proc.output()[-3000:]
    assert probe.wait_for(lambda: controller_status(probe).status == "safe_hold", 30.0)
    assert "estimator lost" in controller_status(probe).safe_hold_reason
    assert not probe.collect("/estimated_joint_torques", JointState, 1, 2.0)
    assert len(probe.collect("/effort_command", JointState, 20, 30.0)) == 20
