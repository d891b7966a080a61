"""SimConfig: every parameter of the simulated iCub (``config/sim_bridge.yaml``).

Field names equal the ``sim_bridge`` ROS parameter names. Positions are in ``root_link``
(x backward, y to the robot's right, z up) [m]; the table stands in front of the robot (x < 0).
"""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["SimConfig", "MODES"]

MODES = ("free_run", "lockstep")


@dataclasses.dataclass(frozen=True)
class SimConfig(ConfigBase):
    """Simulation, node and scene parameters (units in brackets on each field)."""

    # --- stepping ---------------------------------------------------------------------------
    timestep: float = 0.001  # physics step [s]
    mode: str = "free_run"  # free_run | lockstep
    real_time_factor: float = 1.0  # free_run pacing: sim s per wall s; 0 = as fast as possible
    lockstep_timeout: float = 0.5  # [s] wall time to wait for the answering command
    initial_posture: str = "rest"  # named posture of config/robot.yaml
    start_paused: bool = False
    # --- publishing -------------------------------------------------------------------------
    clock_decimation: int = 10  # publish /clock every N steps (10: 100 Hz of simulated time)
    imu_decimation: int = 1  # publish the IMU every N steps
    ground_truth_decimation: int = 1  # publish ground-truth wrenches and object poses every N
    # --- cameras ----------------------------------------------------------------------------
    cameras_enabled: bool = True
    camera_rate: float = 30.0  # [Hz] of simulated time
    camera_width: int = 320  # [px]
    camera_height: int = 240  # [px]
    camera_fx: float = 343.12  # [px] (50 deg horizontal field of view at 320 px)
    camera_fy: float = 343.12  # [px]
    camera_cx: float = 160.0  # [px]
    camera_cy: float = 120.0  # [px]
    camera_threaded: bool = True  # render off the physics thread
    # --- hand markers (body-schema babbling: the coloured marker the cameras track) ----------
    hand_marker_radius: float = 0.015  # [m] sphere on each hand, visual only; 0 = none
    hand_marker_offset: tuple[float, ...] = (-0.02, -0.02, 0.04)  # [m] in the hand_dh_frame
    visual_mesh_cell: float = 0.008  # [m] vertex-clustering cell of the rendered meshes
    # --- joint physics (see icub_sim_bridge/model_builder.py for sources) --------------------
    joint_damping: float = -1.0  # [N m s/rad]; < 0: the URDF <dynamics damping> (1.0)
    joint_frictionloss: float = 0.0  # [N m] dry friction (URDF <dynamics friction> is 0)
    armature_large: float = 0.05  # [kg m^2] 40 N m joints (torso, shoulder pitch/roll)
    armature_medium: float = 0.03  # [kg m^2] 20 N m joints (shoulder yaw, elbow)
    armature_small: float = 0.01  # [kg m^2] 11 N m and below (wrist, neck)
    armature_eyes: float = 0.001  # [kg m^2] eye joints
    # --- scene ------------------------------------------------------------------------------
    table_position: tuple[float, ...] = (-0.42, 0.0, -0.09)  # centre of the top surface [m]
    table_size: tuple[float, ...] = (0.40, 0.90, 0.04)  # depth x, width y, top thickness [m]
    box_position: tuple[float, ...] = (-0.33, 0.0, -0.05)  # centre [m] (resting on the table)
    box_size: tuple[float, ...] = (0.08, 0.20, 0.08)  # full extents x, y, z [m]
    box_mass: float = 0.2  # [kg]
    cylinder_position: tuple[float, ...] = (-0.30, 0.28, -0.03)  # centre [m]
    cylinder_radius: float = 0.03  # [m]
    cylinder_height: float = 0.12  # [m]
    cylinder_mass: float = 0.1  # [kg]
    object_friction: float = 1.0  # sliding friction of hands, objects and table
    # tabletop task (issue 19): small cubes, none by default (the demo's scene unchanged)
    #: cubes as "name:x,y,z name:x,y,z" (centres [m]); "" = none. One string: a ROS list
    #: parameter cannot be empty
    tabletop_objects: str = ""
    tabletop_cube_size: float = 0.04  # edge of every cube [m]
    tabletop_cube_mass: float = 0.05  # [kg]
    # --- safety: bounds on scripted requests, divergence guard, missing commands ------------
    max_wrench_force: float = 100.0  # [N] largest |force| of a scripted wrench
    max_wrench_torque: float = 10.0  # [N m] largest |torque| of a scripted wrench
    max_wrench_duration: float = 60.0  # [s] longest scripted wrench (simulated time)
    object_workspace_radius: float = 1.5  # [m] objects go within it, above the floor
    divergence_speed: float = 1000.0  # [rad/s, m/s] a dof this fast: the simulation diverged
    pause_on_divergence: bool = False  # after recovering from a divergence, pause (node)
    command_timeout: float = 0.5  # [s] wall time without /effort_command in free_run: hold

    def validate(self) -> None:
        """Range checks (raise :class:`ConfigError` naming the field)."""
        if self.mode not in MODES:
            raise ConfigError(f"SimConfig.mode: {self.mode!r} is not one of {MODES}")
        if not 0.0 < self.timestep <= 0.01:
            raise ConfigError(f"SimConfig.timestep: expected (0, 0.01] s, got {self.timestep}")
        if self.real_time_factor < 0.0:
            raise ConfigError(f"SimConfig.real_time_factor: expected >= 0, got "
                              f"{self.real_time_factor}")
        for name in ("max_wrench_force", "max_wrench_torque", "max_wrench_duration",
                     "object_workspace_radius", "divergence_speed", "command_timeout"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0.0):
                raise ConfigError(f"SimConfig.{name}: expected a finite value > 0, got {v}")
        if self.lockstep_timeout <= 0.0:
            raise ConfigError(f"SimConfig.lockstep_timeout: expected > 0 s, got "
                              f"{self.lockstep_timeout}")
        for name in ("clock_decimation", "imu_decimation", "ground_truth_decimation",
                     "camera_width", "camera_height"):
            if getattr(self, name) < 1:
                raise ConfigError(f"SimConfig.{name}: expected >= 1, got {getattr(self, name)}")
        if self.camera_rate <= 0.0:
            raise ConfigError(f"SimConfig.camera_rate: expected > 0 Hz, got {self.camera_rate}")
        for name in ("table_position", "table_size", "box_position", "box_size",
                     "cylinder_position"):
            v = getattr(self, name)
            if len(v) != 3:
                raise ConfigError(f"SimConfig.{name}: expected 3 values [m], got {list(v)}")
        for name in ("box_mass", "cylinder_mass", "cylinder_radius", "cylinder_height",
                     "camera_fx", "camera_fy", "armature_large", "armature_medium",
                     "armature_small", "armature_eyes"):
            if getattr(self, name) <= 0.0:
                raise ConfigError(f"SimConfig.{name}: expected > 0, got {getattr(self, name)}")
        if self.hand_marker_radius < 0.0 or len(self.hand_marker_offset) != 3:
            raise ConfigError(f"SimConfig.hand_marker_radius/offset: expected a radius >= 0 [m] "
                              f"and 3 offsets [m], got {self.hand_marker_radius}, "
                              f"{list(self.hand_marker_offset)}")
        if min(self.table_size) <= 0 or min(self.box_size) <= 0:
            raise ConfigError("SimConfig.table_size/box_size: extents must be > 0")
        self._validate_tabletop()

    def _validate_tabletop(self) -> None:
        """The tabletop cubes: unique new names, 3 finite coordinates each, sizes > 0."""
        self.tabletop()
        for name in ("tabletop_cube_size", "tabletop_cube_mass"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0.0):
                raise ConfigError(f"SimConfig.{name}: expected a finite value > 0, got {v}")

    def tabletop(self) -> dict[str, tuple[float, float, float]]:
        """{cube name: centre (x, y, z) [m]} parsed from ``tabletop_objects`` (raises
        :class:`ConfigError` naming the bad entry)."""
        out: dict[str, tuple[float, float, float]] = {}
        reserved = ("box", "cylinder", "table")
        for entry in self.tabletop_objects.split():
            name, sep, xyz = entry.partition(":")
            try:
                p = tuple(float(v) for v in xyz.split(","))
            except ValueError:
                p = ()
            if (not sep or not name or name in reserved or name in out or len(p) != 3
                    or not all(math.isfinite(v) for v in p)):
                raise ConfigError(
                    f"SimConfig.tabletop_objects: bad entry {entry!r}: expected "
                    f"'name:x,y,z' with a unique name other than {list(reserved)} and 3 finite "
                    f"coordinates [m]")
            out[name] = (p[0], p[1], p[2])
        return out
