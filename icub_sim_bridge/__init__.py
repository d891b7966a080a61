"""The simulated iCub: MuJoCo model built in code from the icub-models URDF, and its simulator.

No ROS here: ``icub_pmp.nodes.sim_bridge`` is the thin rclpy node on top.

- :class:`ModelBuilder` -> :class:`BuiltModel` (the ``MjModel`` and its facts)
- :class:`Simulator`: step, effort commands, joint state, FT, IMU, ground-truth wrenches,
  objects, scripted wrenches
- :class:`CameraRenderer`: the two eye cameras (offscreen, optionally on a worker thread)
- :class:`SimConfig`: the parameters (``config/sim_bridge.yaml``)
"""

from icub_sim_bridge.camera_renderer import CameraRenderer
from icub_sim_bridge.model_builder import BuiltModel, ModelBuilder
from icub_sim_bridge.sim_config import SimConfig
from icub_sim_bridge.simulator import FT_SENSORS, FT_SIGN_CONVENTION, Simulator

__all__ = [
    "BuiltModel",
    "CameraRenderer",
    "FT_SENSORS",
    "FT_SIGN_CONVENTION",
    "ModelBuilder",
    "SimConfig",
    "Simulator",
]
