"""Control: the 1 kHz joint impedance controller of the iCub boards (eqs 4-7 of the
force-control paper): torque PID, impedance law, set-points from trajectories, velocity
commands and holds, safety, and the lockstep estimate gate of the node. No ROS imports;
:mod:`icub_sim_bridge.harness.sim_loop` closes the loop in-process with the simulator and the
wrench estimator."""

from icub_pmp.control.estimate_gate import EstimateGate
from icub_pmp.control.impedance_controller import STATUSES, ControlOutput, ImpedanceController
from icub_pmp.control.impedance_controller_config import (
    FEEDFORWARDS,
    MODES,
    ImpedanceControllerConfig,
)
from icub_pmp.control.joint_trajectory import JointTrajectory, TrajectorySample
from icub_pmp.control.setpoint_generator import Setpoint, SetpointGenerator
from icub_pmp.control.torque_pid import TorquePid

__all__ = [
    "EstimateGate",
    "STATUSES",
    "ControlOutput",
    "ImpedanceController",
    "FEEDFORWARDS",
    "MODES",
    "ImpedanceControllerConfig",
    "JointTrajectory",
    "TrajectorySample",
    "Setpoint",
    "SetpointGenerator",
    "TorquePid",
]
