"""TableScene: the simulator's own scene (iCub, table, box, cylinder) rendered by its eye cameras
with the objects and the head posed kinematically, for tests and benchmarks of the stereo
target.

Unlike :mod:`.sequence_generator` (a textured room and a floating ball), this is exactly what
the ``sim_bridge`` node renders: the same :class:`~icub_sim_bridge.simulator.Simulator` model
and :class:`~icub_sim_bridge.camera_renderer.CameraRenderer`, with MuJoCo's segmentation for
the objects' true pixels. Nothing is stepped: :meth:`pose` sets the joints and the objects,
:meth:`render` renders both eyes.
"""

from __future__ import annotations

import dataclasses
import os
from typing import TYPE_CHECKING, Mapping, Sequence

import numpy as np

from icub_pmp.vision.head_cameras import CameraPoses, HeadCameras

if TYPE_CHECKING:
    from icub_sim_bridge.realism_config import RealismConfig

__all__ = ["TableScene", "SceneFrame"]


@dataclasses.dataclass(frozen=True)
class SceneFrame:
    """Both eyes' images of one posed scene.

    Attributes:
        left, right: (H, W, 3) uint8 RGB images.
        masks: object name -> {'left': (H, W) bool, 'right': (H, W) bool} true pixels.
        poses: camera poses from the head/eye kinematics at the joints.
        joints: joint name -> position [rad] (as /joint_states has them).
        objects: object name -> (3,) true centre in root_link [m].
    """

    left: np.ndarray
    right: np.ndarray
    masks: dict
    poses: CameraPoses
    joints: dict
    objects: dict


class TableScene:
    """Pose and render the simulator's scene (module doc)."""

    def __init__(self, realism: "RealismConfig | None" = None, config=None) -> None:
        """``realism``: the simulator's imperfections (camera miscalibration and pixel noise
        as ``sim_bridge`` renders them; None = the ideal cameras); ``config``: the
        simulator's :class:`~icub_sim_bridge.sim_config.SimConfig` (None = the defaults; e.g.
        another ``hand_marker_offset``: a marker on a held tool)."""
        os.environ.setdefault("MUJOCO_GL", "egl")
        import mujoco

        from icub_sim_bridge.camera_renderer import CameraRenderer
        from icub_sim_bridge.model_builder import EYE_CAMERAS, GROUP_OBJECTS, GROUP_VISUAL
        from icub_sim_bridge.sim_config import SimConfig
        from icub_sim_bridge.simulator import Simulator

        self._mj = mujoco
        self._eye_cameras = EYE_CAMERAS
        self.sim = Simulator(config or SimConfig(), realism=realism)
        self.camera = self.sim.built.camera
        self._renderer = CameraRenderer(self.sim.model, self.camera, threaded=False)
        self._seg = mujoco.Renderer(self.sim.model, self.camera.height, self.camera.width)
        self._seg.enable_segmentation_rendering()
        self._opt = mujoco.MjvOption()
        self._opt.geomgroup[:] = 0
        self._opt.geomgroup[GROUP_VISUAL] = 1
        self._opt.geomgroup[GROUP_OBJECTS] = 1
        self._geoms = {o: mujoco.mj_name2id(self.sim.model, mujoco.mjtObj.mjOBJ_GEOM,
                                            f"{o}_geom") for o in self.sim.object_names}
        self.head = HeadCameras()
        self._placed: dict[str, np.ndarray] = {}

    def pose(self, joints: Mapping[str, float], objects: Mapping[str, Sequence[float]]) -> None:
        """Robot at the rest posture with ``joints`` {name: rad} changed; objects upright at
        the given centres [m] (the others where they were last put, at first their home)."""
        q = dict(self.sim.spec.posture("rest"))
        q.update(joints)
        self._placed.update({n: np.asarray(p, float) for n, p in objects.items()})
        self.sim.reset(q={k: v for k, v in q.items() if k in self.sim.joint_names})
        for name, p in self._placed.items():
            self.sim.set_object_pose(name, p)

    def table_away(self, away: bool = True) -> None:
        """Take the table out of the cameras' view (``away``: 2 m down) or put it back where
        the scene has it (a babbling robot's hand below the table top is then seen)."""
        mj = self._mj
        body = mj.mj_name2id(self.sim.model, mj.mjtObj.mjOBJ_BODY, "table")
        if not hasattr(self, "_table_pos"):
            self._table_pos = self.sim.model.body_pos[body].copy()
        self.sim.model.body_pos[body] = self._table_pos + (0.0, 0.0, -2.0 if away else 0.0)
        mj.mj_forward(self.sim.model, self.sim.data)

    def render_eyes(self) -> dict[str, np.ndarray]:
        """Both eyes' images {'left', 'right': (H, W, 3) uint8 RGB} as ``sim_bridge`` publishes
        them (with the realism's pixel noise), without the objects' masks."""
        images = self._renderer.render(self.sim.data)
        imp = self.sim.imperfections
        if imp is not None:  # realism: pixel noise, as sim_bridge publishes the images
            images = {side: imp.noisy_image(img) for side, img in images.items()}
        return images

    def render(self) -> SceneFrame:
        """Render both eyes and the objects' true pixels."""
        mj = self._mj
        images = self.render_eyes()
        masks: dict[str, dict[str, np.ndarray]] = {o: {} for o in self._geoms}
        for side in ("left", "right"):
            self._seg.update_scene(self.sim.data, camera=self._eye_cameras[side],
                                   scene_option=self._opt)
            seg = self._seg.render()
            is_geom = seg[:, :, 1] == int(mj.mjtObj.mjOBJ_GEOM)
            for o, g in self._geoms.items():
                masks[o][side] = (seg[:, :, 0] == g) & is_geom
        js = self.sim.joint_state()
        joints = dict(zip(self.sim.joint_names, js.position.tolist()))
        objects = {o: self.sim.object_pose(o).position for o in self._geoms}
        return SceneFrame(images["left"], images["right"], masks, self.head.poses(joints),
                          joints, objects)

    def close(self) -> None:
        """Free the GL contexts."""
        self._seg.close()
