"""SequenceGenerator: evaluation sequences for the motion segmenter from the simulator's cameras.

The scene is the simulator's own MuJoCo model (:class:`icub_sim_bridge.model_builder.
ModelBuilder`: the iCub with its eye cameras, 320x240, fx = fy = 343.12, the table, a box and a
cylinder), to which this module adds, in its own copy of the ``MjSpec``:

- textures (a lab-like backdrop wall, floor and table top) so that LK has something to track,
  as in a real room; the simulator's own scene is flat-coloured;
- ``motion_target``: a textured 8 cm ball on a mocap body, the independently moving object.

Frames are posed kinematically (no physics): the neck and eye joints and the target position
are set for each frame time, ``mj_forward`` runs and both eye cameras render RGB and
MuJoCo's segmentation (geom ids); the ground-truth mask is the target's pixels. Sequences
(the issue's evaluation set) follow :class:`SequenceSpec`: the target moves at a constant speed
[m/s], parallel or orthogonal to the image plane, back and forth about a point above the table,
while the head is still or rotates (neck yaw or pitch) back and forth at a constant rate
[deg/s]. Nothing is stored: sequences are generated on demand (about 10 ms per camera frame).
"""

from __future__ import annotations

import dataclasses
import math
import os
from typing import Iterator, Mapping

import numpy as np

from icub_pmp.baselines.synthetic_sequence import textured_image, triangle_wave
from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics

__all__ = ["SequenceGenerator", "SequenceSpec", "SequenceFrame", "DIRECTIONS", "HEAD_AXES"]

DIRECTIONS = ("none", "parallel", "orthogonal")
HEAD_AXES = ("yaw", "pitch")
TARGET_BODY = "motion_target"
#: head posture of the sequences [rad]: looking down at the table.
_NECK_PITCH = math.radians(-25.0)
#: fixation point in root_link [m] (above the table centre) and the target's radius [m].
FIXATION = (-0.45, 0.0, 0.02)
TARGET_RADIUS = 0.04


@dataclasses.dataclass(frozen=True)
class SequenceSpec:
    """One evaluation sequence.

    Attributes:
        speed: target speed [m/s] (0 with direction 'none': static scene).
        direction: 'parallel' (along the image x axis), 'orthogonal' (along the optical axis)
            or 'none' (no target in view).
        head_rate: head rotation speed [deg/s] (0: still head).
        head_axis: 'yaw' (neck_yaw) or 'pitch' (neck_pitch).
        n_frames: frames at 30 Hz.
        seed: phase of the target and head sweeps.
        amplitude: half range of the target's back-and-forth motion [m].
        head_sweep: half range of the head's back-and-forth rotation [deg].
        lead_in: first frames without the target (hidden below the floor), so background
            models (MOG2) can learn the scene; the target's motion starts at frame lead_in.
    """

    speed: float = 0.4
    direction: str = "parallel"
    head_rate: float = 0.0
    head_axis: str = "yaw"
    n_frames: int = 30
    seed: int = 0
    amplitude: float = 0.08
    head_sweep: float = 8.0
    lead_in: int = 0

    def __post_init__(self) -> None:
        if self.direction not in DIRECTIONS:
            raise UnknownName("direction", self.direction, DIRECTIONS)
        if self.head_axis not in HEAD_AXES:
            raise UnknownName("head axis", self.head_axis, HEAD_AXES)
        if (self.speed < 0 or self.head_rate < 0 or self.n_frames < 1 or self.amplitude <= 0
                or self.lead_in < 0):
            raise InvalidInput(
                f"SequenceSpec: need speed, head_rate, lead_in >= 0, n_frames >= 1, amplitude > 0;"
                f" got {self.speed}, {self.head_rate}, {self.lead_in}, {self.n_frames}, "
                f"{self.amplitude}"
            )

    @property
    def name(self) -> str:
        """Short label, e.g. 'parallel_40cm_yaw20'."""
        head = f"{self.head_axis}{self.head_rate:g}" if self.head_rate > 0 else "still"
        if self.direction == "none":
            return f"static_{head}"
        return f"{self.direction}_{100 * self.speed:g}cm_{head}"


@dataclasses.dataclass(frozen=True)
class SequenceFrame:
    """One stereo frame with ground truth.

    Attributes:
        index: frame index; time = index / 30 [s].
        left, right: (H, W, 3) uint8 RGB images.
        left_mask, right_mask: (H, W) bool target pixels (MuJoCo segmentation).
        T_root_left, T_root_right: (4, 4) optical frames in root_link (from MuJoCo).
        target_position: (3,) target centre in root_link [m] (NaN when hidden).
        joints: joint name -> position [rad] of the head and eyes (as /joint_states has them).
    """

    index: int
    left: np.ndarray
    right: np.ndarray
    left_mask: np.ndarray
    right_mask: np.ndarray
    T_root_left: np.ndarray
    T_root_right: np.ndarray
    target_position: np.ndarray
    joints: dict


class SequenceGenerator:
    """Render evaluation sequences from the simulator's eye cameras (module doc).

    Args:
        fps: frame rate [frames/s].
        right_camera: also render the right eye (stereo tests).
    """

    def __init__(self, fps: float = 30.0, right_camera: bool = True):
        os.environ.setdefault("MUJOCO_GL", "egl")
        import mujoco

        from icub_sim_bridge.model_builder import EYE_CAMERAS, ModelBuilder

        self._mj = mujoco
        self.fps = fps
        self.right_camera = right_camera
        built = ModelBuilder().build()
        self.camera: CameraIntrinsics = built.camera
        spec = built.spec
        self._decorate(spec)
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        m = self.model
        self._cam = {side: m.camera(name).id for side, name in EYE_CAMERAS.items()}
        self._qadr = {m.joint(j).name: int(m.joint(j).qposadr[0]) for j in range(m.njnt)}
        body = m.body(TARGET_BODY)
        self._mocap = int(body.mocapid[0])
        self._target_geoms = np.array(
            [g for g in range(m.ngeom) if m.geom_bodyid[g] == body.id], np.int32
        )
        self._renderer = mujoco.Renderer(m, self.camera.height, self.camera.width)
        self._seg = mujoco.Renderer(m, self.camera.height, self.camera.width)
        self._seg.enable_segmentation_rendering()
        self._base_q = self._rest_posture()
        self._fixate(np.array(FIXATION))

    # ------------------------------------------------------------------ scene
    def _decorate(self, spec) -> None:
        """Add textures and the mocap target to the simulator's spec (our copy only)."""
        mj = self._mj

        def texture(name: str, img: np.ndarray, repeat: tuple[float, float]) -> str:
            h, w, _ = img.shape
            t = spec.add_texture(name=f"{name}_tex", type=mj.mjtTexture.mjTEXTURE_2D,
                                 width=w, height=h, nchannel=3)
            t.data = np.ascontiguousarray(img).tobytes()
            mat = spec.add_material(name=f"{name}_mat")
            mat.textures[mj.mjtTextureRole.mjTEXROLE_RGB] = f"{name}_tex"
            mat.texrepeat = list(repeat)
            mat.texuniform = True
            return f"{name}_mat"

        def tinted(seed: int, tint: tuple[float, float, float], size: int = 256,
                   scales: tuple[float, ...] = (1.5, 4.0, 12.0)) -> np.ndarray:
            g = textured_image(size, size, seed, scales).astype(np.float32) / 255.0
            rgb = np.stack([g * t for t in tint], axis=-1)
            return np.clip(255 * rgb, 0, 255).astype(np.uint8)

        geoms = {spec.geoms[i].name: spec.geoms[i] for i in range(len(spec.geoms))}
        if "table_top" in geoms:
            geoms["table_top"].material = texture("table", tinted(11, (1.0, 0.78, 0.55)), (3, 3))
            geoms["table_top"].rgba = [1, 1, 1, 1]
        if "floor" in geoms:
            geoms["floor"].material = texture("floor", tinted(12, (0.8, 0.8, 0.85)), (1, 1))
            geoms["floor"].rgba = [1, 1, 1, 1]
        wb = spec.worldbody
        wall_mat = texture("wall", tinted(13, (0.9, 0.95, 1.0), 512, (2.0, 6.0, 20.0)), (0.5, 0.5))
        r2 = math.sqrt(0.5)
        for name, pos, quat in (  # planes facing the robot (plane normal = local +z)
            ("backdrop_front", [-2.2, 0.0, 0.3], [r2, 0.0, r2, 0.0]),
            ("backdrop_left", [-1.0, -1.8, 0.3], [r2, -r2, 0.0, 0.0]),
            ("backdrop_right", [-1.0, 1.8, 0.3], [r2, r2, 0.0, 0.0]),
        ):
            g = wb.add_geom(name=name, type=mj.mjtGeom.mjGEOM_PLANE, pos=pos, quat=quat,
                            size=[2.5, 2.5, 0.1], material=wall_mat, rgba=[1, 1, 1, 1])
            g.contype = g.conaffinity = 0
            g.group = 1
        tgt = wb.add_body(name=TARGET_BODY, pos=[0.0, 0.0, -5.0], mocap=True)
        g = tgt.add_geom(name=f"{TARGET_BODY}_geom", type=mj.mjtGeom.mjGEOM_SPHERE,
                         size=[TARGET_RADIUS, 0, 0],
                         material=texture("target", tinted(14, (1.0, 0.5, 0.2), 128, (1.0, 2.5)),
                                          (12, 12)),
                         rgba=[1, 1, 1, 1])
        g.contype = g.conaffinity = 0
        g.group = 1

    def _rest_posture(self) -> np.ndarray:
        from icub_pmp.kinematics.robot_spec import RobotSpec

        q = self.data.qpos.copy()
        for j, v in RobotSpec.load().postures["rest"].items():
            if j in self._qadr:
                q[self._qadr[j]] = v
        q[self._qadr["neck_pitch"]] = _NECK_PITCH
        return q

    def _set_head(self, q: np.ndarray, tilt: float, version: float, vergence: float) -> None:
        q[self._qadr["eyes_tilt"]] = tilt
        q[self._qadr["l_eye_pan"]] = version + 0.5 * vergence
        q[self._qadr["r_eye_pan"]] = version - 0.5 * vergence

    def _fixate(self, p: np.ndarray) -> None:
        """Choose eye tilt, version and vergence so both cameras centre ``p`` [m]."""
        from scipy.optimize import least_squares

        def resid(x: np.ndarray) -> np.ndarray:
            q = self._base_q.copy()
            self._set_head(q, *x)
            self.data.qpos[:] = q
            self._kinematics()
            r = []
            for side in ("left", "right"):
                T = self.camera_pose(side)
                pc = T[:3, :3].T @ (p - T[:3, 3])
                r += [pc[0] / pc[2], pc[1] / pc[2]]
            return np.array(r)

        sol = least_squares(resid, np.array([0.0, 0.0, 0.1]))
        self._set_head(self._base_q, *sol.x)
        self.eye_angles = tuple(float(v) for v in sol.x)

    # ------------------------------------------------------------------ posing
    def _kinematics(self) -> None:
        """Body and camera poses of the current qpos."""
        self._mj.mj_kinematics(self.model, self.data)
        self._mj.mj_comPos(self.model, self.data)
        self._mj.mj_camlight(self.model, self.data)

    def camera_pose(self, side: str) -> np.ndarray:
        """(4, 4) REP-103 optical frame of ``side``'s eye camera in root_link (MuJoCo's
        camera looks along -z with +y up: rotate pi about x)."""
        cid = self._cam[side]
        T = np.eye(4)
        T[:3, :3] = self.data.cam_xmat[cid].reshape(3, 3) @ np.diag([1.0, -1.0, -1.0])
        T[:3, 3] = self.data.cam_xpos[cid]
        return T

    def _pose(self, spec: SequenceSpec, k: int) -> np.ndarray:
        """Set qpos and the target for frame k; return the target position [m]."""
        rng = np.random.default_rng(spec.seed)
        phase_t, phase_h = rng.uniform(0, 1, 2)
        t = k / self.fps
        q = self._base_q.copy()
        head = math.radians(triangle_wave(t, spec.head_rate, spec.head_sweep, phase_h))
        joint = "neck_yaw" if spec.head_axis == "yaw" else "neck_pitch"
        q[self._qadr[joint]] += head
        self.data.qpos[:] = q
        hidden = spec.direction == "none" or k < spec.lead_in
        if hidden:
            pos = np.array([0.0, 0.0, -5.0])
        else:
            # motion axes from the head at rest (the object moves in the world, not with it)
            axis = self._axes[spec.direction]
            s = triangle_wave((k - spec.lead_in) / self.fps, spec.speed, spec.amplitude, phase_t)
            pos = np.array(FIXATION) + s * axis
        self.data.mocap_pos[self._mocap] = pos
        self._mj.mj_forward(self.model, self.data)
        return np.full(3, np.nan) if hidden else pos

    @property
    def _axes(self) -> dict[str, np.ndarray]:
        if not hasattr(self, "_axes_cache"):
            self.data.qpos[:] = self._base_q
            self._kinematics()
            T = self.camera_pose("left")
            x_img = T[:3, 0]
            z_opt = T[:3, 2]
            self._axes_cache = {"parallel": x_img / np.linalg.norm(x_img),
                                "orthogonal": z_opt / np.linalg.norm(z_opt)}
        return self._axes_cache

    def _render(self, side: str) -> tuple[np.ndarray, np.ndarray]:
        cam = self._cam[side]
        self._renderer.update_scene(self.data, camera=cam)
        rgb = self._renderer.render().copy()
        self._seg.update_scene(self.data, camera=cam)
        seg = self._seg.render()
        mask = np.isin(seg[:, :, 0], self._target_geoms) & (seg[:, :, 1] == int(
            self._mj.mjtObj.mjOBJ_GEOM))
        return rgb, mask

    # ------------------------------------------------------------------ public
    def frames(self, spec: SequenceSpec) -> Iterator[SequenceFrame]:
        """Yield the frames of ``spec`` one by one (rendered on demand)."""
        for k in range(spec.n_frames):
            pos = self._pose(spec, k)
            yield self._capture(k, pos)

    def frame_at(self, joints: Mapping[str, float], target_position: np.ndarray | None,
                 index: int = 0) -> SequenceFrame:
        """Render one frame with the robot at ``joints`` {name: rad} (e.g. a simulation's joint
        states: the joints named take these values, the others keep the sequences' head-down
        rest posture; the eyes as tilt, version, vergence) and the target ball at
        ``target_position`` (3,) [m] in root_link (None: hidden)."""
        q = self._base_q.copy()
        for name, value in joints.items():
            if name in self._qadr:
                q[self._qadr[name]] = float(value)
        if all(n in joints for n in ("eyes_tilt", "eyes_version", "eyes_vergence")):
            self._set_head(q, float(joints["eyes_tilt"]), float(joints["eyes_version"]),
                           float(joints["eyes_vergence"]))
        self.data.qpos[:] = q
        hidden = target_position is None
        pos = np.array([0.0, 0.0, -5.0]) if hidden else np.asarray(target_position, float)
        self.data.mocap_pos[self._mocap] = pos
        self._mj.mj_forward(self.model, self.data)
        return self._capture(index, np.full(3, np.nan) if hidden else pos)

    def _capture(self, k: int, pos: np.ndarray) -> SequenceFrame:
        """Render the current pose as frame ``k`` (target at ``pos``, NaN when hidden)."""
        names = ("torso_pitch", "torso_roll", "torso_yaw", "neck_pitch", "neck_roll",
                 "neck_yaw", "eyes_tilt")
        left, lmask = self._render("left")
        if self.right_camera:
            right, rmask = self._render("right")
        else:
            right, rmask = np.zeros_like(left), np.zeros_like(lmask)
        joints = {n: float(self.data.qpos[self._qadr[n]]) for n in names}
        pl = float(self.data.qpos[self._qadr["l_eye_pan"]])
        pr = float(self.data.qpos[self._qadr["r_eye_pan"]])
        joints["eyes_version"] = 0.5 * (pl + pr)
        joints["eyes_vergence"] = pl - pr
        return SequenceFrame(
            index=k,
            left=left,
            right=right,
            left_mask=lmask,
            right_mask=rmask,
            T_root_left=self.camera_pose("left"),
            T_root_right=self.camera_pose("right"),
            target_position=pos,
            joints=joints,
        )

    def close(self) -> None:
        """Free the renderers' GL contexts."""
        self._renderer.close()
        self._seg.close()
