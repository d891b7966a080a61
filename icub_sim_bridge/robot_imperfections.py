"""RobotImperfections: everything the ``realism`` settings add to the simulated iCub, in one
place the :class:`~icub_sim_bridge.simulator.Simulator` calls.

Built only when an imperfection is on (``RealismSettings.active``); the ``ideal`` preset
builds none, so the simulator then runs exactly its ideal code path. Each part draws from
its own child of ``numpy.random.SeedSequence(seed)``: the same seed gives the same robot
(masses, offsets, biases) and the same noise sequence, and changing one part's figures leaves
the others' draws unchanged.

- :class:`~icub_sim_bridge.model_mismatch.ModelMismatch` (applied to the simulator's copy of
  the model), :class:`~icub_sim_bridge.joint_friction.JointFriction`,
  :class:`~icub_sim_bridge.actuator_dynamics.ActuatorDynamics`;
- :class:`~icub_sim_bridge.sensor_noise.FtSensorModel` (sampled once per physics step, after
  it), :class:`~icub_sim_bridge.sensor_noise.EncoderModel`,
  :class:`~icub_sim_bridge.sensor_noise.ImuModel` (sampled when read).
"""

from __future__ import annotations

import mujoco
import numpy as np

from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics
from icub_sim_bridge.actuator_dynamics import ActuatorDynamics
from icub_sim_bridge.camera_perturbation import CameraPerturbation, add_image_noise
from icub_sim_bridge.joint_friction import JointFriction
from icub_sim_bridge.model_mismatch import ModelMismatch, robot_bodies
from icub_sim_bridge.realism_config import RealismSettings
from icub_sim_bridge.sensor_noise import EncoderModel, FtSensorModel, ImuModel

__all__ = ["RobotImperfections"]

#: child seed streams, in this order (never reorder: seeds would give other robots)
_STREAMS = ("mismatch", "ft", "encoder", "imu", "camera")


class RobotImperfections:
    """The imperfections of one simulated robot (module doc).

    Args:
        settings: the figures (``RealismConfig.resolved()``).
        model: the simulator's own ``MjModel`` (changed in place: mismatch, friction).
        root_body: the robot's root body (its tree gets the mass mismatch).
        joints, dofs: the hinge joints (names) and their dof addresses for friction.
        n_actuated: length of the simulator's torque command.
        n_ft: number of FT sensors.
        dt: physics step [s].
    """

    def __init__(self, settings: RealismSettings, model: mujoco.MjModel, root_body: str,
                 joints: list[str], dofs: np.ndarray, n_actuated: int, n_ft: int, dt: float):
        self.settings = s = settings
        rngs = {k: np.random.default_rng(c) for k, c in
                zip(_STREAMS, np.random.SeedSequence(s.seed).spawn(len(_STREAMS)))}
        self.camera_rng = rngs["camera"]
        self._image_rng = np.random.default_rng(self.camera_rng.integers(2**63))
        self.mismatch: ModelMismatch | None = None
        if s.mass_error > 0 or s.com_error > 0:
            self.mismatch = ModelMismatch.draw(robot_bodies(model, root_body), s.mass_error,
                                               s.com_error, rngs["mismatch"])
            self.mismatch.apply(model)
        self.friction: JointFriction | None = None
        if s.friction_active:
            self.friction = JointFriction(joints, dofs, s.friction_coulomb,
                                          s.friction_stiction, s.friction_viscous,
                                          s.friction_stribeck_velocity)
            self.friction.install(model)
        self.actuators: ActuatorDynamics | None = None
        if s.actuator_delay_steps > 0 or s.actuator_bandwidth_hz > 0:
            self.actuators = ActuatorDynamics(n_actuated, s.actuator_delay_steps,
                                              s.actuator_bandwidth_hz, dt)
        self.ft = FtSensorModel(n_ft, s, rngs["ft"], dt) if s.ft_active else None
        self.encoders = EncoderModel(s, rngs["encoder"]) if (
            s.encoder_resolution > 0 or s.velocity_noise_std > 0) else None
        self.imu = ImuModel(s, rngs["imu"]) if any(
            (s.imu_acc_noise_std, s.imu_acc_bias, s.imu_gyro_noise_std, s.imu_gyro_bias)) \
            else None
        self.cameras: dict[str, CameraPerturbation] = {}

    def perturb_cameras(self, model: mujoco.MjModel, camera_ids: dict[str, int],
                        nominal: CameraIntrinsics) -> None:
        """Draw and apply each camera's calibration error ({side: MuJoCo camera id})."""
        s = self.settings
        if not any((s.camera_focal_error, s.camera_principal_error,
                    s.camera_rotation_error_deg)):
            return
        for side, cid in sorted(camera_ids.items()):
            p = CameraPerturbation.draw(s.camera_focal_error, s.camera_principal_error,
                                        s.camera_rotation_error_deg, self.camera_rng)
            p.apply(model, cid, nominal)
            self.cameras[side] = p

    def noisy_image(self, image: np.ndarray) -> np.ndarray:
        """``image`` with the camera pixel noise (unchanged when it is 0); call from one
        thread (the camera worker)."""
        if self.settings.camera_noise_std <= 0:
            return image
        return add_image_noise(image, self.settings.camera_noise_std, self._image_rng)
