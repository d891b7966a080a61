"""The simulated iCub: MuJoCo model built in code from the icub-models URDF, and its simulator.

No ROS in the package's core modules: :mod:`icub_sim_bridge.sim_bridge_node` is the thin rclpy
node on top (executable ``sim_bridge``), :mod:`icub_sim_bridge.harness` the in-process loops and
rendered sequences of the tests and benchmarks. The simulator uses the robot description of
:mod:`icub_pmp.kinematics`; nothing in ``icub_pmp``'s cores imports this package.

- :class:`ModelBuilder` -> :class:`BuiltModel` (the ``MjModel`` and its facts)
- :class:`Simulator`: step, effort commands, joint state, FT, IMU, ground-truth wrenches,
  objects, scripted wrenches
- :class:`CameraRenderer`: the two eye cameras (offscreen, optionally on a worker thread)
- :class:`SimConfig`: the parameters (``config/sim_bridge.yaml``); :class:`RealismConfig`:
  the ``realism.*`` ones (the real robot's imperfections, ``ideal`` | ``icub`` preset)
- :class:`~icub_sim_bridge.command_watchdog.CommandWatchdog`: hold the robot when the
  controller stops answering; :class:`~icub_sim_bridge.lockstep_gate.LockstepGate`,
  :class:`~icub_sim_bridge.step_pacer.StepPacer`: the node's stepping
"""

from icub_sim_bridge.camera_renderer import CameraRenderer
from icub_sim_bridge.model_builder import BuiltModel, ModelBuilder
from icub_sim_bridge.realism_config import RealismConfig
from icub_sim_bridge.sim_config import SimConfig
from icub_sim_bridge.simulator import FT_SENSORS, FT_SIGN_CONVENTION, Simulator

__all__ = [
    "BuiltModel",
    "CameraRenderer",
    "FT_SENSORS",
    "FT_SIGN_CONVENTION",
    "ModelBuilder",
    "RealismConfig",
    "SimConfig",
    "Simulator",
]
