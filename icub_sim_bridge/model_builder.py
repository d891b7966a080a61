"""ModelBuilder: the MuJoCo model of the iCub on a mainstay, built in code from the URDF.

Source of truth: the icub-models URDF named in ``config/robot.yaml`` (``iCubGazeboV2_7``: arm
and leg FT sensors, hand DH frames, STL meshes). Nothing is copied: the builder parses the
URDF (:class:`UrdfRobot`) and the installed STL meshes (:class:`TriMesh`) and fills an
``mujoco.MjSpec``. :meth:`ModelBuilder.write_xml` can dump the result to ``urdf/generated/``
(git-ignored) for inspection.

What the model is
- World frame == ``root_link`` (x backward, y right, z up), fixed on a mainstay (visual only).
- Every URDF link with mass or geometry is a body at its URDF pose; pure frame links
  (``l_hand_dh_frame``, ``l_arm_ft``, ``head_imu_0`` ...) are sites of the same name. Bodies
  after a fixed joint stay separate (welded) bodies, so the FT sensors see the joint between
  ``l_shoulder_3`` and ``l_upper_arm``. Leg joints are omitted (legs welded at 0, as in
  :class:`IcubModel`). Inertias are the URDF's (the Gazebo model's inflated ones included, so
  MuJoCo and pinocchio have the same dynamics).
- Hinges for torso 3, arms 2x7, neck 3; eyes added from :class:`EyeKinematics` (iKin DH): one
  tilt hinge and a pan hinge per eye; ``eyes_version`` and ``eyes_vergence`` are fixed tendons
  ``(pan_l + pan_r)/2`` and ``pan_l - pan_r`` so the three iCub eye joints are exact.
- Torque actuators on those 20 joints + 3 eye coordinates, ``forcerange`` = +- ``RobotSpec``
  torque limits (``config/robot.yaml``, the one table). The simulator switches each one
  between a pure motor (gain 1, no bias) and a "hold" (affine PD: gain kp, bias -kp q -kd qdot)
  at run time; MuJoCo clamps the resulting force to ``forcerange`` either way.
- Joint physics for a stable 1 ms step (implicit-fast integrator): damping from the URDF
  ``<dynamics damping="1.0">`` (the value of the icub-models Gazebo models), friction
  from the URDF (0) unless ``joint_frictionloss``; armature (reflected rotor inertia) is NOT
  in any public model: chosen as J_rotor * N^2 with N = 100 (Harmonic Drive 100:1) and
  J_rotor of a few 1e-6 kg m^2 (small frameless motors): 0.05 / 0.03 / 0.01 kg m^2 for the
  40 / 20 / <= 11 N m groups, 0.001 for the eyes (SimConfig).
- Collisions: hands, wrists, forearms, upper arms against the table, the box and the
  cylinder; every link of the left arm against every link of the right arm (the two arms can
  hit each other; the links of one arm never collide with each other); hands, wrists and
  forearms against the chest (the convex hulls of the upper arms and of root_link overlap at
  ordinary postures, so those pairs are left out); objects against table and floor (also the
  tabletop cubes of ``SimConfig.tabletop_objects``, each with an inactive weld per hand that
  the simulator's grasp switches on). Collision
  shapes are convex hulls of the simplified meshes (MuJoCo's mesh collision).
- Sensors: force + torque at the four FT sensor joints (``<ft>_site`` on the child body, at
  the URDF sensor origin), head IMU (``head_imu_0``: gyro, accelerometer, orientation).
- Cameras ``left_eye_camera`` / ``right_eye_camera`` at the eyes' optical frames (MuJoCo looks
  along -z with +y up: optical frame rotated pi about x), ``fovy`` from fy.
- Hand markers: a small green sphere on each hand (visual only, no contact, no mass) at
  ``hand_marker_offset`` in the hand DH frame, the coloured marker iCub babbling experiments
  track; geom ``<l|r>_hand_marker`` (:data:`HAND_MARKER_RGBA`).
- Rendering: simplified visual meshes (vertex clustering, ``visual_mesh_cell``), legs and
  head shell (the eyes sit inside it) and collision hulls in geom groups the eye cameras do
  not draw, one light without shadows.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import mujoco
import numpy as np

from icub_pmp.errors import ModelError
from icub_pmp.kinematics.eye_kinematics import (
    EYE_LIMITS,
    CameraIntrinsics,
    EyeKinematics,
)
from icub_pmp.kinematics.robot_spec import RobotSpec, urdf_path
from icub_pmp.kinematics.tri_mesh import TriMesh
from icub_pmp.kinematics.urdf_robot import UrdfRobot
from icub_sim_bridge.sim_config import SimConfig

__all__ = ["ModelBuilder", "BuiltModel", "GROUP_VISUAL", "GROUP_LEGS", "GROUP_COLLISION",
           "OBJECT_NAMES", "EYE_CAMERAS", "HAND_MARKER_RGBA", "tabletop_names"]

#: geom groups: eye cameras draw groups 0 (robot upper body, scene) and 1 (objects) only.
GROUP_VISUAL = 0
GROUP_OBJECTS = 1
GROUP_LEGS = 2
GROUP_COLLISION = 3
#: collision bits (contype / conaffinity)
_BIT_WORLD = 1  # table, floor, objects
_BIT_LEFT_ARM = 2  # left hand, wrist, forearm, elbow, upper arm
_BIT_TORSO = 4  # root_link, torso, chest
_BIT_RIGHT_ARM = 8  # right hand, wrist, forearm, elbow, upper arm
_BIT_ARM = _BIT_LEFT_ARM | _BIT_RIGHT_ARM
OBJECT_NAMES = ("box", "cylinder")
EYE_CAMERAS = {"left": "left_eye_camera", "right": "right_eye_camera"}
#: colour of the hand markers (a green no other object in the scene has)
HAND_MARKER_RGBA = (0.1, 0.9, 0.1, 1.0)

_ARM_COLLIDE = ("upper_arm", "elbow_1", "forearm", "wrist_1", "hand")
_ARM_TORSO_COLLIDE = ("forearm", "wrist_1", "hand")  # the hulls of the upper arms overlap
_TORSO_COLLIDE = ("chest",)  # the chest hull at every posture: checked only against these
_LEG_PREFIXES = ("l_hip", "r_hip", "l_upper_leg", "r_upper_leg", "l_lower_leg",
                 "r_lower_leg", "l_ankle", "r_ankle", "l_foot", "r_foot", "l_sole", "r_sole",
                 "l_leg", "r_leg")


@dataclasses.dataclass(frozen=True)
class BuiltModel:
    """The compiled model and the facts the simulator needs about it."""

    model: mujoco.MjModel
    spec: mujoco.MjSpec
    actuated_joints: tuple[str, ...]  # RobotSpec.actuated_joints order
    ft_sensors: tuple[str, ...]  # l_arm_ft, r_arm_ft, l_leg_ft, r_leg_ft
    ft_frames: dict[str, str]  # FT name -> site name
    hand_bodies: dict[str, str]  # 'left'/'right' -> body
    hand_frames: dict[str, str]  # 'left'/'right' -> site (l_hand_dh_frame ...)
    eye_kinematics: EyeKinematics
    camera: CameraIntrinsics


def _quat(R: np.ndarray) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).reshape(9))
    return q


def _is_leg(name: str) -> bool:
    return name.startswith(_LEG_PREFIXES)


class ModelBuilder:
    """Builds :class:`BuiltModel` from ``RobotSpec`` + ``SimConfig`` (see module doc)."""

    def __init__(self, config: SimConfig | None = None, spec: RobotSpec | None = None):
        self.config = config or SimConfig()
        self.robot = spec or RobotSpec.load()
        self.urdf_file = urdf_path(self.robot.model_name)
        self.urdf = UrdfRobot(self.urdf_file)
        # share/iCub/robots/<name>/model.urdf -> share/ resolves package://iCub/...
        self.meshes_root = self.urdf_file.parents[3]
        self.camera = CameraIntrinsics(
            self.config.camera_width, self.config.camera_height, self.config.camera_fx,
            self.config.camera_fy, self.config.camera_cx, self.config.camera_cy)
        self._mesh_cache: dict[tuple[str, tuple[float, ...]], str] = {}

    # ------------------------------------------------------------------ public
    def build(self) -> BuiltModel:
        """Compile the model (raises :class:`ModelError` on a URDF/MuJoCo failure)."""
        s = mujoco.MjSpec()
        s.modelname = "icub_pmp_sim"
        s.compiler.degree = False
        s.compiler.autolimits = True
        s.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
        s.option.timestep = self.config.timestep
        s.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        s.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
        s.option.noslip_iterations = 0
        s.visual.quality.shadowsize = 0
        s.visual.global_.offwidth = max(640, self.config.camera_width)
        s.visual.global_.offheight = max(480, self.config.camera_height)
        s.visual.headlight.ambient = [0.4, 0.4, 0.4]
        s.visual.headlight.diffuse = [0.5, 0.5, 0.5]
        self._s = s
        self._actuated = set(self.robot.upper_body_joints)
        root = s.worldbody.add_body(name=self.urdf.root)
        self._add_link(root, self.urdf.root)
        self._add_subtree(root, self.urdf.root, np.eye(4))
        eyes = self._add_eyes(s)
        self._add_actuators(s)
        ft = self._add_ft_sensors(s)
        self._add_imu(s)
        self._add_scene(s)
        self._add_hand_markers(s)
        try:
            model = s.compile()
        except Exception as exc:  # mujoco raises ValueError with the compiler message
            raise ModelError(f"MuJoCo cannot compile the iCub model: {exc}") from exc
        return BuiltModel(
            model=model,
            spec=s,
            actuated_joints=self.robot.actuated_joints,
            ft_sensors=tuple(ft),
            ft_frames=dict(ft),
            hand_bodies={"left": "l_hand", "right": "r_hand"},
            hand_frames=dict(self.robot.hand_frames),
            eye_kinematics=eyes,
            camera=self.camera,
        )

    def write_xml(self, built: BuiltModel, path: str | Path) -> Path:
        """Write the compiled model as MJCF (meshes inline) for inspection, e.g. to
        ``urdf/generated/icub_sim.xml``."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(built.spec.to_xml())
        return path

    # ------------------------------------------------------------------ robot tree
    def _mesh(self, filename: str, scale: tuple[float, float, float]) -> str:
        key = (filename, tuple(scale))
        if key not in self._mesh_cache:
            mesh = TriMesh.from_stl(self.urdf.resolve_mesh(filename, self.meshes_root), scale)
            mesh = mesh.simplified(self.config.visual_mesh_cell)
            name = Path(filename).stem
            m = self._s.add_mesh(name=name)
            m.uservert = mesh.vertices.astype(np.float32).reshape(-1).tolist()
            m.userface = mesh.faces.reshape(-1).tolist()
            m.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
            m.maxhullvert = 64
            self._mesh_cache[key] = name
        return self._mesh_cache[key]

    def _add_link(self, body: mujoco.MjsBody, link_name: str) -> None:
        link = self.urdf.links[link_name]
        if link.inertial is not None and link.inertial.mass > 0:
            body.mass = link.inertial.mass
            body.ipos = link.inertial.T_link_com[:3, 3]
            I = link.inertial.inertia_in_link()
            body.fullinertia = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
            body.explicitinertial = True
        leg = _is_leg(link_name)
        stem = link_name[2:] if link_name[:2] in ("l_", "r_") else link_name
        collide_arm = stem in _ARM_COLLIDE and not leg
        collide_torso = link_name in _TORSO_COLLIDE
        for v in link.visuals:
            if v.kind != "mesh":
                continue  # the few URDF boxes are skin patches: not drawn
            g = body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=self._mesh(
                v.mesh_file, v.scale))
            g.pos = v.T_link_geom[:3, 3]
            g.quat = _quat(v.T_link_geom[:3, :3])
            g.rgba = list(v.rgba)
            g.contype = 0
            g.conaffinity = 0
            # the eyes sit inside the head shell: the eye cameras skip it (and the legs)
            g.group = GROUP_LEGS if (leg or link_name == "head") else GROUP_VISUAL
            g.mass = 0.0
        if collide_arm or collide_torso:
            for c in link.collisions:
                if c.kind != "mesh":
                    continue
                g = body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH,
                                  meshname=self._mesh(c.mesh_file, c.scale))
                g.pos = c.T_link_geom[:3, 3]
                g.quat = _quat(c.T_link_geom[:3, :3])
                g.group = GROUP_COLLISION
                g.rgba = [0.5, 0.5, 0.9, 0.3]
                own, other = ((_BIT_LEFT_ARM, _BIT_RIGHT_ARM) if link_name.startswith("l_")
                              else (_BIT_RIGHT_ARM, _BIT_LEFT_ARM))
                g.contype = own if collide_arm else _BIT_TORSO
                if collide_arm:  # one arm's links never collide with each other
                    g.conaffinity = _BIT_WORLD | other | (
                        _BIT_TORSO if stem in _ARM_TORSO_COLLIDE else 0)
                else:  # the torso only touches what names _BIT_TORSO in its conaffinity
                    g.conaffinity = 0
                g.friction = [self.config.object_friction, 0.005, 0.0001]
                g.condim = 4
                g.name = f"{link_name}_collision"
                g.mass = 0.0

    def _add_subtree(self, body: mujoco.MjsBody, link_name: str, T_body_link: np.ndarray
                     ) -> None:
        """Add the children of ``link_name`` (whose pose in ``body`` is ``T_body_link``)."""
        cfg = self.config
        for j in self.urdf.child_joints[link_name]:
            child = self.urdf.links[j.child]
            T = T_body_link @ j.T_parent_child
            if (child.is_frame and not self.urdf.child_joints[j.child]):
                site = body.add_site(name=j.child, pos=T[:3, 3], quat=_quat(T[:3, :3]))
                site.group = 5
                continue
            cb = body.add_body(name=j.child, pos=T[:3, 3], quat=_quat(T[:3, :3]))
            if j.kind in ("revolute", "continuous") and j.name in self._actuated:
                damping = j.damping if cfg.joint_damping < 0 else cfg.joint_damping
                jt = cb.add_joint(name=j.name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=j.axis)
                jt.range = [j.lower, j.upper]
                jt.limited = mujoco.mjtLimited.mjLIMITED_TRUE
                jt.damping = [damping, 0.0, 0.0]
                jt.frictionloss = max(cfg.joint_frictionloss, j.friction)
                jt.armature = self._armature(j.name)
            elif j.kind not in ("fixed", "revolute", "continuous"):
                raise ModelError(f"URDF joint {j.name}: type {j.kind!r} is not supported")
            self._add_link(cb, j.child)
            self._add_subtree(cb, j.child, np.eye(4))

    def _armature(self, joint: str) -> float:
        tau = self.robot.torque_limit(joint)
        if tau >= 40.0:
            return self.config.armature_large
        if tau >= 20.0:
            return self.config.armature_medium
        return self.config.armature_small

    # ------------------------------------------------------------------ eyes and cameras
    def _add_eyes(self, s: mujoco.MjSpec) -> EyeKinematics:
        """Eyes on the URDF head at ``T_head_eyes`` (see :class:`EyeKinematics`)."""
        from icub_pmp.kinematics.robot_model import IcubModel

        eyes = EyeKinematics.from_model(IcubModel(self.robot))
        head = s.body("head")
        T = eyes.T_head_eyes
        cfg = self.config
        tilt_body = head.add_body(name="eyes_tilt_link", pos=T[:3, 3], quat=_quat(T[:3, :3]))
        tilt_body.mass = 1e-3
        tilt_body.inertia = [1e-7, 1e-7, 1e-7]
        tilt_body.ipos = [0.0, 0.0, 0.0]
        tilt_body.iquat = [1.0, 0.0, 0.0, 0.0]
        tilt_body.explicitinertial = True
        jt = tilt_body.add_joint(name="eyes_tilt", type=mujoco.mjtJoint.mjJNT_HINGE,
                                 axis=[0, 0, 1])
        jt.range = list(EYE_LIMITS["eyes_tilt"])
        jt.limited = mujoco.mjtLimited.mjLIMITED_TRUE
        jt.armature = cfg.armature_eyes
        jt.damping = [0.01, 0.0, 0.0]
        # MuJoCo camera frame = optical frame rotated pi about x (looks along -z, +y up)
        R_opt_cam = np.diag([1.0, -1.0, -1.0])
        for side, prefix in (("left", "l"), ("right", "r")):
            Te = EyeKinematics.T_eyes_eye(side)
            eb = tilt_body.add_body(name=f"{prefix}_eye", pos=Te[:3, 3], quat=_quat(Te[:3, :3]))
            eb.mass = 1e-3
            eb.inertia = [1e-7, 1e-7, 1e-7]
            eb.ipos = [0.0, 0.0, 0.0]
            eb.iquat = [1.0, 0.0, 0.0, 0.0]
            eb.explicitinertial = True
            pj = eb.add_joint(name=f"{prefix}_eye_pan", type=mujoco.mjtJoint.mjJNT_HINGE,
                              axis=[0, 0, 1])
            pj.range = list(EYE_LIMITS["pan"])
            pj.limited = mujoco.mjtLimited.mjLIMITED_TRUE
            pj.armature = cfg.armature_eyes
            pj.damping = [0.01, 0.0, 0.0]
            Tc = EyeKinematics.T_eye_camera(0.0)
            eb.add_site(name=f"{prefix}_eye_optical", pos=Tc[:3, 3], quat=_quat(Tc[:3, :3]))
            eb.add_camera(name=EYE_CAMERAS[side], pos=Tc[:3, 3],
                          quat=_quat(Tc[:3, :3] @ R_opt_cam), fovy=self.camera.fovy_deg)
            ball = eb.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.012, 0, 0])
            ball.rgba = [0.95, 0.95, 0.95, 1]
            ball.contype = ball.conaffinity = 0
            ball.group = GROUP_LEGS  # not drawn by the eye cameras themselves
            ball.mass = 0.0
        for name, coefs in (("eyes_version", (0.5, 0.5)), ("eyes_vergence", (1.0, -1.0))):
            t = s.add_tendon(name=name)
            t.wrap_joint("l_eye_pan", coefs[0])
            t.wrap_joint("r_eye_pan", coefs[1])
            t.range = list(EYE_LIMITS[name])
            t.limited = mujoco.mjtLimited.mjLIMITED_TRUE
        return eyes

    def _add_hand_markers(self, s: mujoco.MjSpec) -> None:
        """A visual-only sphere on each hand at ``hand_marker_offset`` in its DH frame."""
        radius = self.config.hand_marker_radius
        if radius <= 0.0:
            return
        for frame in self.robot.hand_frames.values():
            site = s.site(frame)
            if site is None:
                raise ModelError(f"hand frame {frame!r} is not a site of the model")
            R = np.zeros(9)
            mujoco.mju_quat2Mat(R, np.asarray(site.quat, dtype=float))
            pos = np.asarray(site.pos) + R.reshape(3, 3) @ np.asarray(
                self.config.hand_marker_offset, dtype=float)
            g = site.parent.add_geom(name=f"{frame[:2]}hand_marker",
                                     type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[radius, 0, 0],
                                     pos=pos)
            g.rgba = list(HAND_MARKER_RGBA)
            g.contype = g.conaffinity = 0
            g.group = GROUP_VISUAL
            g.mass = 0.0

    # ------------------------------------------------------------------ actuators, sensors
    def _add_actuators(self, s: mujoco.MjSpec) -> None:
        for name in self.robot.actuated_joints:
            lim = self.robot.torque_limit(name)
            a = s.add_actuator(name=name, target=name)
            a.trntype = (mujoco.mjtTrn.mjTRN_TENDON if name in ("eyes_version", "eyes_vergence")
                         else mujoco.mjtTrn.mjTRN_JOINT)
            a.gear = [1.0, 0, 0, 0, 0, 0]
            a.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE  # ctrl may be a hold target
            a.forcerange = [-lim, lim]
            a.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            a.dyntype = mujoco.mjtDyn.mjDYN_NONE
            a.gaintype = mujoco.mjtGain.mjGAIN_FIXED
            a.gainprm[0] = 1.0
            a.biastype = mujoco.mjtBias.mjBIAS_NONE
        # eye tilt is a joint actuator too (handled above: it is a joint name)

    def _add_ft_sensors(self, s: mujoco.MjSpec) -> list[tuple[str, str]]:
        """FT sites on the child body of each URDF FT sensor joint (``<name>_sensor``)."""
        out = []
        for name in ("l_arm_ft", "r_arm_ft", "l_leg_ft", "r_leg_ft"):
            j = self.urdf.joint(f"{name}_sensor")
            child = s.body(j.child)
            site = child.add_site(name=f"{name}_site", pos=[0, 0, 0], quat=[1, 0, 0, 0])
            site.group = 5
            s.add_sensor(name=f"{name}_force", type=mujoco.mjtSensor.mjSENS_FORCE,
                         objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site.name)
            s.add_sensor(name=f"{name}_torque", type=mujoco.mjtSensor.mjSENS_TORQUE,
                         objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site.name)
            out.append((name, site.name))
        return out

    def _add_imu(self, s: mujoco.MjSpec) -> None:
        for name, kind in (("imu_gyro", mujoco.mjtSensor.mjSENS_GYRO),
                           ("imu_accelerometer", mujoco.mjtSensor.mjSENS_ACCELEROMETER),
                           ("imu_orientation", mujoco.mjtSensor.mjSENS_FRAMEQUAT)):
            s.add_sensor(name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE,
                         objname="head_imu_0")

    # ------------------------------------------------------------------ scene
    @staticmethod
    def _add_textured_material(s: mujoco.MjSpec, name: str, rgb1: list[float],
                               rgb2: list[float], cube: bool, repeat: float) -> str:
        """A procedural checker texture with random speckles (MuJoCo builtin, nothing
        downloaded): surfaces need texture for Lucas-Kanade tracking (motion segmenter)."""
        tex = s.add_texture(
            name=f"scene_{name}_tex",
            type=mujoco.mjtTexture.mjTEXTURE_CUBE if cube else mujoco.mjtTexture.mjTEXTURE_2D,
            builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, rgb1=rgb1, rgb2=rgb2,
            width=128, height=128, mark=mujoco.mjtMark.mjMARK_RANDOM, random=0.25,
            markrgb=[0.5 * c for c in rgb2])
        mat = s.add_material(name=f"scene_{name}_mat")
        mat.textures[int(mujoco.mjtTextureRole.mjTEXROLE_RGB)] = tex.name
        mat.texrepeat = [repeat, repeat]
        mat.texuniform = not cube
        return mat.name

    def _add_scene(self, s: mujoco.MjSpec) -> None:
        cfg = self.config
        wb = s.worldbody
        table_mat = self._add_textured_material(
            s, "table", [0.62, 0.47, 0.3], [0.52, 0.38, 0.23], cube=False, repeat=12.0)
        box_mat = self._add_textured_material(
            s, "box", [0.85, 0.1, 0.1], [0.6, 0.05, 0.05], cube=True, repeat=1.0)
        cyl_mat = self._add_textured_material(
            s, "cylinder", [0.1, 0.3, 0.85], [0.05, 0.15, 0.55], cube=True, repeat=1.0)
        light = wb.add_light(name="sun", pos=[-0.5, 0.0, 1.5], dir=[0.3, 0.0, -1.0])
        light.castshadow = False
        light.diffuse = [0.6, 0.6, 0.6]
        sole_z = -0.62
        floor = wb.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3, 3, 0.1],
                            pos=[0, 0, sole_z], rgba=[0.55, 0.55, 0.5, 1])
        floor.contype = floor.conaffinity = _BIT_WORLD
        floor.group = GROUP_OBJECTS
        mast = wb.add_geom(name="mainstay", type=mujoco.mjtGeom.mjGEOM_BOX,
                           size=[0.03, 0.03, (0.0 - sole_z) / 2], pos=[0.12, 0, sole_z / 2],
                           rgba=[0.3, 0.3, 0.3, 1])
        mast.contype = mast.conaffinity = 0
        mast.group = GROUP_LEGS
        tx, ty, tz = cfg.table_position
        dx, dy, th = cfg.table_size
        table = wb.add_body(name="table", pos=[tx, ty, tz])
        top = table.add_geom(name="table_top", type=mujoco.mjtGeom.mjGEOM_BOX,
                             size=[dx / 2, dy / 2, th / 2], pos=[0, 0, -th / 2],
                             rgba=[1, 1, 1, 1], material=table_mat)
        top.contype = top.conaffinity = _BIT_WORLD
        top.friction = [cfg.object_friction, 0.005, 0.0001]
        top.group = GROUP_OBJECTS
        leg_h = (tz - th) - sole_z
        for sx in (-1, 1):
            for sy in (-1, 1):
                lg = table.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX,
                                    size=[0.02, 0.02, leg_h / 2],
                                    pos=[sx * (dx / 2 - 0.03), sy * (dy / 2 - 0.03),
                                         -th - leg_h / 2], rgba=[0.5, 0.38, 0.25, 1])
                lg.contype = lg.conaffinity = 0
                lg.group = GROUP_OBJECTS
        box = wb.add_body(name="box", pos=list(cfg.box_position))
        box.add_freejoint(name="box_freejoint")
        bg = box.add_geom(name="box_geom", type=mujoco.mjtGeom.mjGEOM_BOX,
                          size=[v / 2 for v in cfg.box_size], rgba=[1, 1, 1, 1],
                          material=box_mat)
        cyl = wb.add_body(name="cylinder", pos=list(cfg.cylinder_position))
        cyl.add_freejoint(name="cylinder_freejoint")
        cg = cyl.add_geom(name="cylinder_geom", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                          size=[cfg.cylinder_radius, cfg.cylinder_height / 2, 0],
                          rgba=[1, 1, 1, 1], material=cyl_mat)
        for g in (bg, cg):
            g.contype = _BIT_WORLD | _BIT_ARM
            g.conaffinity = _BIT_WORLD | _BIT_ARM
            g.friction = [cfg.object_friction, 0.005, 0.0001]
            g.condim = 4
            g.group = GROUP_OBJECTS
        # solid inertias [kg m^2] (inertiafromgeom is off for the robot)
        m, (a, b_, c) = cfg.box_mass, cfg.box_size
        box.mass = m
        box.inertia = [m * (b_**2 + c**2) / 12, m * (a**2 + c**2) / 12, m * (a**2 + b_**2) / 12]
        m, r, h = cfg.cylinder_mass, cfg.cylinder_radius, cfg.cylinder_height
        cyl.mass = m
        cyl.inertia = [m * (3 * r**2 + h**2) / 12, m * (3 * r**2 + h**2) / 12, m * r**2 / 2]
        for b in (box, cyl):  # centre of mass at the body origin
            b.ipos = [0.0, 0.0, 0.0]
            b.iquat = [1.0, 0.0, 0.0, 0.0]
            b.explicitinertial = True
        self._add_tabletop(s)

    def _add_tabletop(self, s: mujoco.MjSpec) -> None:
        """The tabletop cubes (``SimConfig.tabletop_objects``) and, per hand and cube, a weld
        ``grasp_<hand>_<cube>`` created inactive: the simulator switches it on at run time to
        emulate a grasp (the model has no fingers) and sets its relative pose then."""
        cfg = self.config
        e = cfg.tabletop_cube_size
        m = cfg.tabletop_cube_mass
        colours = ((0.95, 0.8, 0.1), (0.1, 0.75, 0.75), (0.8, 0.3, 0.8), (0.95, 0.5, 0.1),
                   (0.4, 0.4, 0.95), (0.6, 0.9, 0.3))
        for k, (name, pos) in enumerate(cfg.tabletop().items()):
            b = s.worldbody.add_body(name=name, pos=list(pos))
            b.add_freejoint(name=f"{name}_freejoint")
            g = b.add_geom(name=f"{name}_geom", type=mujoco.mjtGeom.mjGEOM_BOX,
                           size=[e / 2] * 3, rgba=[*colours[k % len(colours)], 1.0])
            g.contype = g.conaffinity = _BIT_WORLD | _BIT_ARM
            g.friction = [cfg.object_friction, 0.005, 0.0001]
            g.condim = 4
            g.group = GROUP_OBJECTS
            b.mass = m
            b.inertia = [m * e * e / 6] * 3
            b.ipos = [0.0, 0.0, 0.0]
            b.iquat = [1.0, 0.0, 0.0, 0.0]
            b.explicitinertial = True
            for hand in ("l_hand", "r_hand"):
                eq = s.add_equality(name=f"grasp_{hand[0]}_{name}",
                                    type=mujoco.mjtEq.mjEQ_WELD, name1=hand, name2=name,
                                    objtype=mujoco.mjtObj.mjOBJ_BODY)
                eq.active = False


def tabletop_names(config: SimConfig) -> tuple[str, ...]:
    """The tabletop cubes of ``config`` (movable objects besides :data:`OBJECT_NAMES`)."""
    return tuple(config.tabletop())


def main() -> None:
    """Write the generated model to ``urdf/generated/icub_sim.xml`` (git-ignored) for
    inspection: ``scripts/env.sh python -m icub_sim_bridge.model_builder``."""
    from icub_pmp.config import repo_root

    builder = ModelBuilder()
    path = builder.write_xml(builder.build(), repo_root() / "urdf" / "generated" / "icub_sim.xml")
    print(path)


if __name__ == "__main__":
    main()
