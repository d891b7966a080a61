"""Simulator: the simulated iCub (MuJoCo) behind a small numpy API; no ROS.

One :class:`Simulator` owns an ``MjModel``/``MjData`` built by :class:`ModelBuilder` and
advances it in fixed steps (``SimConfig.timestep``, 1 ms). Units: m, rad, N, N m, s.
Frames: world == ``root_link`` (x backward, y right, z up).

Joints (``joint_names`` = ``RobotSpec.actuated_joints``: torso 3, left arm 7, right arm 7,
neck 3, eyes 3): ``q``/``v``/``tau`` arrays follow that order. The eye coordinates
``eyes_version`` / ``eyes_vergence`` are tendons over the two eye pans (see ModelBuilder).

Effort commands (:meth:`command`): any subset of joints by name, finite values; values are
saturated at the ``RobotSpec`` torque limits (``config/robot.yaml``). A joint never named in a
command since the last :meth:`reset` is *held*: an internal joint PD to its reset posture plus
gravity compensation (like an iCub joint left in position mode; kp = 5 tau_max [N m/rad],
kd = 0.2 tau_max [N m s/rad], realised as an affine MuJoCo actuator so the damping term is
integrated implicitly). Naming a joint once hands it over to the commanded torque for good
(until the next reset).

Sensors after each :meth:`step` (values of the step's dynamics: state at the start of the
step, torque applied during it):
- :meth:`ft` -- the four 6-axis FT sensors ``l_arm_ft, r_arm_ft, l_leg_ft, r_leg_ft``:
  ``(force (3,) [N], torque (3,) [N m])`` in the URDF FT frame (the child link's frame at the
  sensor joint), **sign convention of the URDF (child_to_parent): the wrench that the child
  (distal) link exerts on the parent (proximal) link**, moment about the frame origin.
  E.g. an arm hanging still reads ``+m_distal * g`` (pointing down in root_link).
- :meth:`imu` -- head IMU at the URDF ``head_imu_0`` frame: orientation (w, x, y, z) of the
  frame in root_link, angular velocity [rad/s] and proper acceleration [m/s^2] (reads
  +9.81 up when still) in the frame.
- :meth:`contact_wrench` -- ground truth: total external wrench on a hand body (contacts +
  applied forces), root_link axes, moment about the hand frame origin (``l_hand_dh_frame``).
- :meth:`self_contacts` -- ground truth: the robot touching itself (left arm against right
  arm, an arm against the torso), one :class:`SelfContact` per MuJoCo contact point.

Scene: :meth:`object_pose`, :meth:`set_object_pose` (``box``, ``cylinder``, the tabletop cubes),
:meth:`move_object` (a constant-velocity motion in simulated time),
:meth:`object_contacts` (ground truth: robot links touching objects), :meth:`grasp` /
:meth:`release` (the emulated grasp of a cube: a weld switched on only on palm contact),
:meth:`apply_wrench` (a scripted external wrench on a body or at a frame for a duration).
Both refuse what is not physically meaningful (``SimConfig``): a force above
``max_wrench_force``, a torque above ``max_wrench_torque``, a duration above
``max_wrench_duration``, an object farther than ``object_workspace_radius`` from root_link or
below the floor.
Cameras: :class:`icub_sim_bridge.camera_renderer.CameraRenderer` renders a snapshot.

Divergence guard: MuJoCo's own reaction to an unstable step (NaN, inf or a huge value in the
accelerations) is to reset the whole state to the model's zero posture *and rewind time to 0*
("auto-reset"); here that is disabled. Instead, after every step a dof faster than
``divergence_speed`` (NaN included) counts as a divergence, and :meth:`step` recovers from it
at once: the last good state (kept every 0.1 s of simulated time: finite, joints within their
limits) is restored at rest, every scripted wrench is cleared, every joint goes on hold at the
restored posture (as after :meth:`reset`) and time goes on from where it was: simulated time
never goes back. :attr:`last_divergence` and :attr:`divergences` tell what happened.

Realism (``realism`` argument, :class:`RealismConfig`; ``ideal`` by default): with the
``icub`` preset the simulator steps a copy of the model whose masses, centres of mass and
inertias differ from the URDF's, with joint friction and a delayed actuation, and the sensor
methods (:meth:`joint_state`, :meth:`ft`, :meth:`ft_all`, :meth:`imu`) give what the real
sensors give: quantised encoders, FT noise + offset + drift + bandwidth, IMU noise + bias
(:class:`~icub_sim_bridge.robot_imperfections.RobotImperfections`). The true values stay
available for evaluation: :meth:`true_joint_state`, :meth:`true_ft_all`. With ``ideal`` the
code path is the one without imperfections.

Missing commands: :meth:`hold` puts every joint on hold at its current posture (what the
simulator does when the controller stops answering); the next command hands the joints it
names back to the commanded torque.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from typing import Iterable, NamedTuple, Sequence

import mujoco
import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.name_index import name_indices
from icub_pmp.kinematics.robot_spec import RobotSpec
from icub_sim_bridge.model_builder import (
    EYE_CAMERAS,
    OBJECT_NAMES,
    BuiltModel,
    ModelBuilder,
    tabletop_names,
)
from icub_sim_bridge.realism_config import RealismConfig
from icub_sim_bridge.robot_imperfections import RobotImperfections
from icub_sim_bridge.sim_config import SimConfig

__all__ = ["Simulator", "JointState", "Wrench", "Pose", "ImuReading", "SelfContact",
           "ObjectContact", "GraspRefused", "Divergence", "FT_SENSORS", "FT_SIGN_CONVENTION",
           "SELF_CONTACT_KINDS"]

FT_SENSORS = ("l_arm_ft", "r_arm_ft", "l_leg_ft", "r_leg_ft")
FT_SIGN_CONVENTION = "child_to_parent"
_HANDS = ("left", "right")
#: arm-arm: a left-arm link against a right-arm link; arm-torso: an arm link against the torso
SELF_CONTACT_KINDS = ("arm-arm", "arm-torso")
#: the kind of :meth:`Simulator.object_contacts` records
_TENDON_JOINTS = ("eyes_version", "eyes_vergence")
#: hold gains per N m of torque limit: kp = 5 * tau_max [N m/rad], kd = 0.2 * tau_max [N m s/rad]
_HOLD_KP_PER_NM = 5.0
_HOLD_KD_PER_NM = 0.2
#: the last good state is kept every this many steps (0.1 s at 1 ms)
_SNAPSHOT_EVERY = 100
#: a kept state has every joint within its limits plus this [rad] (limits are soft in MuJoCo)
_SNAPSHOT_LIMIT_MARGIN = 0.1


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """3-vector cross product (np.cross is ~10x slower on single vectors)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


class JointState(NamedTuple):
    """Joint positions [rad], velocities [rad/s], applied torques [N m], all (n,)."""

    time: float
    position: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray


class Wrench(NamedTuple):
    """Force (3,) [N] and torque (3,) [N m]."""

    force: np.ndarray
    torque: np.ndarray


class Pose(NamedTuple):
    """Position (3,) [m] and orientation quaternion (w, x, y, z)."""

    position: np.ndarray
    quaternion: np.ndarray


class ImuReading(NamedTuple):
    """Orientation (w, x, y, z) in root_link, angular velocity (3,) [rad/s] and proper
    acceleration (3,) [m/s^2] in the IMU frame."""

    orientation: np.ndarray
    angular_velocity: np.ndarray
    linear_acceleration: np.ndarray


class SelfContact(NamedTuple):
    """One contact point between two links of the robot, or a link and a scene object.

    ``body1`` is the left-arm link of an arm-arm contact, the arm link of an arm-torso one,
    the robot's link of a robot-object one;
    ``force`` (3,) [N] is what ``body2`` exerts on ``body1`` (root_link axes), ``normal_force``
    [N] its normal component, ``depth`` [m] the penetration, ``position`` (3,) [m] the
    contact point in root_link."""

    kind: str
    body1: str
    body2: str
    position: np.ndarray
    force: np.ndarray
    normal_force: float
    depth: float


class ObjectContact(NamedTuple):
    """One contact point between a link of the robot and a movable object.

    ``object`` is the object, ``body`` the robot's link, ``arm`` 'left' | 'right' | 'torso',
    ``grasped`` whether the object is welded to that arm's hand (the emulated grasp),
    ``position`` (3,) [m] the contact point in root_link, ``normal_force`` [N]."""

    object: str
    body: str
    arm: str
    grasped: bool
    position: np.ndarray
    normal_force: float


class GraspRefused(InvalidInput):
    """A grasp that the simulator refuses (no palm contact, object already held, ...)."""


class Divergence(NamedTuple):
    """A divergence of the physics and the recovery from it (module doc)."""

    time: float  # simulated time when it was detected [s]
    reason: str  # what was seen, e.g. "speed 2.1e+04 of dof 'r_elbow' > 1000"
    restored_time: float  # simulated time at which the restored state had been kept [s]
    count: int  # divergences so far (this one included)


@dataclasses.dataclass
class _AppliedWrench:
    body: int
    point_body: np.ndarray  # application point in the body frame [m]
    force: np.ndarray  # root_link [N]
    torque: np.ndarray  # root_link [N m]
    until: float  # sim time [s]


@dataclasses.dataclass
class _ObjectMotion:
    start: np.ndarray  # position at t0 [m]
    quaternion: np.ndarray  # (w, x, y, z), kept
    velocity: np.ndarray  # [m/s]
    t0: float  # sim time of the start [s]
    duration: float  # [s]


class Simulator:
    """The simulated iCub (see module doc)."""

    def __init__(self, config: SimConfig | None = None, spec: RobotSpec | None = None,
                 built: BuiltModel | None = None, realism: RealismConfig | None = None):
        self.config = config or SimConfig()
        self.spec = spec or RobotSpec.load()
        self.built = built or ModelBuilder(self.config, self.spec).build()
        self.realism = realism or RealismConfig()
        settings = self.realism.resolved()
        # imperfections change the model: the simulator's own copy (a shared BuiltModel stays
        # the URDF's)
        m = self.model = copy.copy(self.built.model) if settings.active else self.built.model
        # no auto-reset: MuJoCo would rewind time to 0 and put the robot at the zero posture
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
        self.data = mujoco.MjData(m)
        self.joint_names: tuple[str, ...] = tuple(self.spec.actuated_joints)
        self.n = len(self.joint_names)
        self._index = {n: i for i, n in enumerate(self.joint_names)}
        self.torque_limits = np.array([self.spec.torque_limit(j) for j in self.joint_names])
        self.torque_limits.setflags(write=False)
        # joints vs tendons
        self._jidx = np.array([i for i, n in enumerate(self.joint_names)
                               if n not in _TENDON_JOINTS], dtype=int)
        self._tidx = np.array([i for i, n in enumerate(self.joint_names)
                               if n in _TENDON_JOINTS], dtype=int)
        jids = [self._id(mujoco.mjtObj.mjOBJ_JOINT, self.joint_names[i]) for i in self._jidx]
        self._qadr = np.array([m.jnt_qposadr[j] for j in jids], dtype=int)
        self._dadr = np.array([m.jnt_dofadr[j] for j in jids], dtype=int)
        self._tids = np.array([self._id(mujoco.mjtObj.mjOBJ_TENDON, self.joint_names[i])
                               for i in self._tidx], dtype=int)
        self._act = np.array([self._id(mujoco.mjtObj.mjOBJ_ACTUATOR, n)
                              for n in self.joint_names], dtype=int)
        lo = np.empty(self.n)
        hi = np.empty(self.n)
        lo[self._jidx] = [m.jnt_range[j][0] for j in jids]
        hi[self._jidx] = [m.jnt_range[j][1] for j in jids]
        lo[self._tidx] = m.tendon_range[self._tids, 0]
        hi[self._tidx] = m.tendon_range[self._tids, 1]
        self.lower, self.upper = lo, hi
        self.lower.setflags(write=False)
        self.upper.setflags(write=False)
        # sensors
        self._ft_adr = {}
        for name in FT_SENSORS:
            fa = m.sensor_adr[self._id(mujoco.mjtObj.mjOBJ_SENSOR, f"{name}_force")]
            ta = m.sensor_adr[self._id(mujoco.mjtObj.mjOBJ_SENSOR, f"{name}_torque")]
            self._ft_adr[name] = (fa, ta)
        self._ft_index = np.array([a + k for fa, ta in self._ft_adr.values()
                                   for a in (fa, ta) for k in range(3)], dtype=int)
        self._imu_adr = {k: m.sensor_adr[self._id(mujoco.mjtObj.mjOBJ_SENSOR, f"imu_{k}")]
                         for k in ("gyro", "accelerometer", "orientation")}
        self._hand_body = {h: self._id(mujoco.mjtObj.mjOBJ_BODY, self.built.hand_bodies[h])
                           for h in _HANDS}
        self._hand_site = {h: self._id(mujoco.mjtObj.mjOBJ_SITE, self.built.hand_frames[h])
                           for h in _HANDS}
        self._objects = {}
        for name in OBJECT_NAMES + tabletop_names(self.config):
            b = self._id(mujoco.mjtObj.mjOBJ_BODY, name)
            jnt = m.body_jntadr[b]
            self._objects[name] = (b, m.jnt_qposadr[jnt], m.jnt_dofadr[jnt])
        self._object_home = {n: self.data.qpos[a:a + 7].copy()
                             for n, (_, a, _) in self._objects.items()}
        # self contacts: side of each robot geom (0 not the robot, 1 left arm, 2 right arm,
        # 3 torso) by the prefix of its body (URDF link) name
        robot_root = m.body_rootid[self._id(mujoco.mjtObj.mjOBJ_BODY, self.spec.root_frame)]
        self._geom_side = np.zeros(m.ngeom, dtype=int)
        for g in range(m.ngeom):
            b = int(m.geom_bodyid[g])
            if b == 0 or m.body_rootid[b] != robot_root or not (m.geom_contype[g]
                                                                  or m.geom_conaffinity[g]):
                continue
            name = m.body(b).name
            self._geom_side[g] = 1 if name.startswith("l_") else 2 if name.startswith("r_") \
                else 3
        self._f6 = np.zeros(6)
        # objects by geom (-1: not an object), the grasp welds {(hand, object): eq id}
        self._geom_object = np.full(m.ngeom, -1, dtype=int)
        self._object_list = tuple(self._objects)
        for k, (b, _, _) in enumerate(self._objects.values()):
            self._geom_object[m.body_geomadr[b]:m.body_geomadr[b] + m.body_geomnum[b]] = k
        self._welds = {}
        for hand in _HANDS:
            for name in tabletop_names(self.config):
                self._welds[(hand, name)] = self._id(mujoco.mjtObj.mjOBJ_EQUALITY,
                                                     f"grasp_{hand[0]}_{name}")
        self._grasped: dict[str, str] = {}  # hand -> object
        # hold gains (an affine actuator PD, see _set_held) and the dofs for gravity terms
        self._kp = _HOLD_KP_PER_NM * self.torque_limits
        self._kd = _HOLD_KD_PER_NM * self.torque_limits
        self._dof_of = np.full(self.n, -1, dtype=int)
        self._dof_of[self._jidx] = self._dadr
        self._applied: list[_AppliedWrench] = []
        self._motions: dict[str, _ObjectMotion] = {}  # object -> scripted motion (move_object)
        self._xfrc_dirty = False
        self._tau_cmd = np.zeros(self.n)
        self._commanded = np.zeros(self.n, dtype=bool)
        self._q_hold = np.zeros(self.n)
        self._held_act = np.zeros(0, dtype=int)
        self._held_dof = np.zeros(0, dtype=int)
        self._held_base = np.zeros(0)
        self._grav_act = np.zeros(0, dtype=int)
        self._grav_dof = np.zeros(0, dtype=int)
        self._grav_kp = np.zeros(0)
        self.steps = 0
        # divergence guard (module doc)
        self._vmax = float(self.config.divergence_speed)
        self._vmax2 = self._vmax ** 2
        self._good_qpos = self.data.qpos.copy()
        self._good_time = 0.0
        self.divergences = 0
        self.last_divergence: Divergence | None = None
        floor = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "floor")
        self.floor_height = float(m.geom_pos[floor][2]) if floor >= 0 else -np.inf
        self.imperfections: RobotImperfections | None = None
        self._ft_measured: np.ndarray | None = None
        if settings.active:
            self.imperfections = RobotImperfections(
                settings, m, self.spec.root_frame,
                [self.joint_names[i] for i in self._jidx] + ["l_eye_pan", "r_eye_pan"],
                np.r_[self._dadr, [m.jnt_dofadr[self._id(mujoco.mjtObj.mjOBJ_JOINT, j)]
                                   for j in ("l_eye_pan", "r_eye_pan")]].astype(int),
                self.n, len(FT_SENSORS), m.opt.timestep)
            self.imperfections.perturb_cameras(
                m, {side: self._id(mujoco.mjtObj.mjOBJ_CAMERA, cam)
                    for side, cam in EYE_CAMERAS.items()}, self.built.camera)
            self.data = mujoco.MjData(m)  # the perturbed model's constants
        self.reset(self.config.initial_posture)

    # ------------------------------------------------------------------ names
    def _id(self, kind: mujoco.mjtObj, name: str) -> int:
        i = mujoco.mj_name2id(self.model, kind, name)
        if i < 0:
            raise UnknownName(str(kind).split("_")[-1].lower(), name, [])
        return i

    def indices(self, names: Iterable[str]) -> np.ndarray:
        """Positions in ``joint_names`` of ``names`` (raises :class:`UnknownName`)."""
        return name_indices(names, self._index, self.joint_names)

    @property
    def time(self) -> float:
        """Simulated time [s] (monotonic: a reset does not rewind it)."""
        return float(self.data.time)

    # ------------------------------------------------------------------ state
    def reset(self, posture: str | None = None, q: dict[str, float] | None = None) -> None:
        """Put the robot at a named posture (``config/robot.yaml``) or at ``q`` {joint: rad}
        (other joints 0), at rest; objects back home; applied wrenches cleared; every joint
        back on hold (module doc). Time keeps running (``/clock`` never goes back)."""
        values = self.spec.posture(posture or self.config.initial_posture) if q is None \
            else self._posture_dict(q)
        t = self.data.time
        mujoco.mj_resetData(self.model, self.data)
        self.data.time = t
        self._grasped.clear()  # mj_resetData switched the welds back to eq_active0 (off)
        target = np.array([values.get(n, 0.0) for n in self.joint_names])
        target = np.clip(target, self.lower, self.upper)
        self._write_q(target)
        for name, (_, a, _) in self._objects.items():
            self.data.qpos[a:a + 7] = self._object_home[name]
        mujoco.mj_forward(self.model, self.data)
        self._q_hold = target
        self._tau_cmd = np.zeros(self.n)
        self._commanded = np.zeros(self.n, dtype=bool)
        self._set_held()
        self._applied.clear()
        self._motions.clear()
        self._keep_good_state()

    def _posture_dict(self, q: dict[str, float]) -> dict[str, float]:
        for n, v in q.items():
            if n not in self._index:
                raise UnknownName("joint", n, self.joint_names)
            if not np.isfinite(v):
                raise InvalidInput(f"q[{n!r}] = {v} is not finite")
        return dict(q)

    def _write_q(self, q: np.ndarray) -> None:
        """Write actuated positions; eye version/vergence go to the two eye pans."""
        d, m = self.data, self.model
        d.qpos[self._qadr] = q[self._jidx]
        ver = q[self._index["eyes_version"]]
        vg = q[self._index["eyes_vergence"]]
        for name, val in (("l_eye_pan", ver + 0.5 * vg), ("r_eye_pan", ver - 0.5 * vg)):
            d.qpos[m.jnt_qposadr[self._id(mujoco.mjtObj.mjOBJ_JOINT, name)]] = val

    def joint_state(self) -> JointState:
        """Positions, velocities and applied torques of ``joint_names`` as the encoders
        measure them (copies; the true ones without realism imperfections)."""
        st = self.true_joint_state()
        enc = self.imperfections.encoders if self.imperfections else None
        if enc is None:
            return st
        return JointState(st.time, enc.position(st.position), enc.velocity(st.velocity),
                          st.effort)

    def true_joint_state(self) -> JointState:
        """True positions, velocities and applied torques of ``joint_names`` (copies)."""
        d = self.data
        q = np.empty(self.n)
        v = np.empty(self.n)
        q[self._jidx] = d.qpos[self._qadr]
        v[self._jidx] = d.qvel[self._dadr]
        q[self._tidx] = d.ten_length[self._tids]
        v[self._tidx] = d.ten_velocity[self._tids]
        return JointState(float(d.time), q, v, d.actuator_force[self._act].copy())

    # ------------------------------------------------------------------ commands
    def command(self, names: Sequence[str], efforts: Sequence[float]) -> np.ndarray:
        """Set the torque [N m] of the named joints (module doc). Raises
        :class:`InvalidInput` / :class:`UnknownName` and changes nothing on a bad command.
        Returns the saturated torques (len(names),)."""
        names = list(names)
        tau = np.asarray(efforts, dtype=float).reshape(-1)
        if len(names) != tau.size:
            raise InvalidInput(f"effort command: {len(names)} names but {tau.size} efforts")
        if len(set(names)) != len(names):
            raise InvalidInput(f"effort command: duplicate joint names {names}")
        if not np.all(np.isfinite(tau)):
            bad = [n for n, t in zip(names, tau) if not np.isfinite(t)]
            raise InvalidInput(f"effort command: NaN or infinite effort for {bad}")
        return self.command_indices(self.indices(names), tau)

    def command_indices(self, idx: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """:meth:`command` by positions in ``joint_names`` (already validated: unique valid
        indices, finite ``tau`` of the same length). Returns the saturated torques."""
        sat = np.clip(tau, -self.torque_limits[idx], self.torque_limits[idx])
        self._tau_cmd[idx] = sat
        self.data.ctrl[self._act[idx]] = sat
        if not self._commanded[idx].all():
            self._commanded[idx] = True
            self._set_held()
        return sat

    def command_all(self, tau: np.ndarray) -> np.ndarray:
        """Set all torques (n,) [N m] in ``joint_names`` order (fast path, saturated)."""
        tau = np.asarray(tau, dtype=float)
        if tau.shape != (self.n,):
            raise InvalidInput(f"tau: expected shape ({self.n},), got {tau.shape}")
        if not np.all(np.isfinite(tau)):
            raise InvalidInput("tau: contains NaN or infinite values")
        np.clip(tau, -self.torque_limits, self.torque_limits, out=self._tau_cmd)
        self.data.ctrl[self._act] = self._tau_cmd
        if not self._commanded.all():
            self._commanded[:] = True
            self._set_held()
        return self._tau_cmd.copy()

    def hold(self) -> None:
        """Put every joint on the simulator's hold (module doc of the hold: joint PD plus
        gravity compensation) at its current posture; joints already held keep their target.
        The next command hands the joints it names back to the commanded torque."""
        newly = self._commanded.copy()
        if not newly.any():
            return
        q = np.clip(self.true_joint_state().position, self.lower, self.upper)
        self._q_hold[newly] = q[newly]
        self._tau_cmd[:] = 0.0
        self._commanded[:] = False
        self._set_held()

    @property
    def holding(self) -> bool:
        """True when every joint is on the simulator's hold (none under commanded torque)."""
        return not self._commanded.any()

    @property
    def commanded(self) -> np.ndarray:
        """(n,) bool: joints under commanded torque (the others are held)."""
        return self._commanded.copy()

    def _set_held(self) -> None:
        """Make held joints' actuators an affine PD (force = kp ctrl - kp q - kd qdot, with
        ctrl = q_hold + gravity / kp set every step) and commanded ones pure motors."""
        m = self.model
        for i in range(self.n):
            a = self._act[i]
            m.actuator_gainprm[a, 0] = 1.0 if self._commanded[i] else self._kp[i]
            m.actuator_biasprm[a, :3] = 0.0 if self._commanded[i] else (
                0.0, -self._kp[i], -self._kd[i])
            m.actuator_biastype[a] = (mujoco.mjtBias.mjBIAS_NONE if self._commanded[i]
                                      else mujoco.mjtBias.mjBIAS_AFFINE)
        held = np.flatnonzero(~self._commanded)
        grav = held[self._dof_of[held] >= 0]  # tendons (eye pans) get no gravity term
        self._held_act = self._act[held]
        self._held_base = self._q_hold[held]
        self._grav_act = self._act[grav]
        self._grav_dof = self._dof_of[grav]
        self._grav_kp = self._kp[grav]
        self.data.ctrl[self._act[self._commanded]] = self._tau_cmd[self._commanded]
        imp = getattr(self, "imperfections", None)
        if imp is not None and imp.actuators is not None:
            imp.actuators.reset(self._tau_cmd)

    def _update_hold(self) -> None:
        d = self.data
        if self._held_act.size:
            d.ctrl[self._held_act] = self._held_base
            d.ctrl[self._grav_act] += d.qfrc_bias[self._grav_dof] / self._grav_kp

    # ------------------------------------------------------------------ stepping
    def step(self, n: int = 1) -> None:
        """Advance ``n`` physics steps with the current commands and applied wrenches."""
        m, d = self.model, self.data
        imp = self.imperfections
        for _ in range(n):
            self._update_hold()
            if self._applied or self._xfrc_dirty:
                self._update_applied()
            if self._motions:
                self._update_motions()
            if imp is not None:
                self._before_step(imp)
            mujoco.mj_step(m, d)
            self.steps += 1
            if imp is not None and imp.ft is not None:
                self._ft_measured = imp.ft.measure(d.time, self.true_ft_all())
            v = d.qvel
            if not v @ v < self._vmax2:  # cheap pre-check (NaN fails it too)
                self._check_speed()
            elif self.steps % _SNAPSHOT_EVERY == 0:
                self._keep_good_state()

    def _before_step(self, imp: RobotImperfections) -> None:
        """Friction at the current speeds; the delayed/lagged torque of commanded joints."""
        if imp.friction is not None:
            imp.friction.update(self.model, self.data.qvel)
        if imp.actuators is not None:
            applied = imp.actuators.apply(self._tau_cmd)
            c = self._commanded
            self.data.ctrl[self._act[c]] = applied[c]

    # ------------------------------------------------------------------ divergence guard
    def _check_speed(self) -> None:
        """Recover if a dof is faster than ``divergence_speed`` or not finite."""
        v = np.abs(self.data.qvel)
        bad = np.flatnonzero(~(v < self._vmax))
        if bad.size == 0:
            return
        i = int(bad[np.argmax(np.nan_to_num(v[bad], nan=np.inf))])
        name = self.model.joint(int(self.model.dof_jntid[i])).name
        self.recover(f"speed {v[i]:.3g} of dof {i} (joint {name!r}) is beyond "
                     f"divergence_speed {self._vmax:g}")

    def _keep_good_state(self) -> None:
        """Keep the current state as the last good one if it is finite and every joint is
        within its limits (plus a margin)."""
        d = self.data
        q = d.qpos[self._qadr]
        lo, hi = self.lower[self._jidx], self.upper[self._jidx]
        if (np.all(np.isfinite(d.qpos)) and np.all(q > lo - _SNAPSHOT_LIMIT_MARGIN)
                and np.all(q < hi + _SNAPSHOT_LIMIT_MARGIN)):
            np.copyto(self._good_qpos, d.qpos)
            self._good_time = float(d.time)

    def recover(self, reason: str) -> Divergence:
        """Recover from a divergence (module doc): the last good state at rest, scripted
        wrenches cleared, every joint on hold at the restored posture; time goes on.
        Returns the :class:`Divergence` (also in :attr:`last_divergence`)."""
        m, d = self.model, self.data
        t = float(d.time) if np.isfinite(d.time) else self._good_time
        mujoco.mj_resetData(m, d)  # clears velocities, accelerations, warnings, xfrc_applied
        d.time = t
        self._grasped.clear()  # and the grasp welds go off
        np.copyto(d.qpos, self._good_qpos)
        mujoco.mj_forward(m, d)
        self._applied.clear()
        self._motions.clear()
        self._xfrc_dirty = False
        self._q_hold = np.clip(self.true_joint_state().position, self.lower, self.upper)
        self._tau_cmd = np.zeros(self.n)
        self._commanded = np.zeros(self.n, dtype=bool)
        self._set_held()
        self.divergences += 1
        self.last_divergence = Divergence(t, reason, self._good_time, self.divergences)
        return self.last_divergence

    def _update_applied(self) -> None:
        d = self.data
        d.xfrc_applied[:] = 0.0
        self._xfrc_dirty = bool(self._applied)
        if not self._applied:
            return
        t = d.time
        self._applied = [a for a in self._applied if a.until > t]
        for a in self._applied:
            p = d.xpos[a.body] + d.xmat[a.body].reshape(3, 3) @ a.point_body
            d.xfrc_applied[a.body, :3] += a.force
            d.xfrc_applied[a.body, 3:] += a.torque + _cross(p - d.xipos[a.body], a.force)

    def _update_motions(self) -> None:
        """Put every scripted object where its motion is at this step's time (and with its
        velocity, so the step integrates along it); a finished motion leaves it at rest."""
        d = self.data
        t = float(d.time)
        for name, mo in list(self._motions.items()):
            _, qa, da = self._objects[name]
            s = min(max(t - mo.t0, 0.0), mo.duration)
            d.qpos[qa:qa + 3] = mo.start + mo.velocity * s
            d.qpos[qa + 3:qa + 7] = mo.quaternion
            d.qvel[da + 3:da + 6] = 0.0
            if t >= mo.t0 + mo.duration - 1e-12:
                d.qvel[da:da + 3] = 0.0
                del self._motions[name]
            else:
                d.qvel[da:da + 3] = mo.velocity

    # ------------------------------------------------------------------ sensors
    def ft(self, name: str) -> Wrench:
        """FT sensor ``name`` (``FT_SENSORS``) in its frame, child_to_parent (module doc)."""
        if name not in self._ft_adr:
            raise UnknownName("FT sensor", name, FT_SENSORS)
        if self._ft_measured is not None:
            w = self._ft_measured[FT_SENSORS.index(name)]
            return Wrench(w[:3].copy(), w[3:].copy())
        fa, ta = self._ft_adr[name]
        s = self.data.sensordata
        # MuJoCo's force/torque sensors give the wrench the parent exerts on the child's
        # subtree; the URDF sensors measure child_to_parent: the opposite.
        return Wrench(-s[fa:fa + 3].copy(), -s[ta:ta + 3].copy())

    def ft_all(self) -> np.ndarray:
        """All FT sensors as (4, 6) [N, N m] rows (force, torque), ``FT_SENSORS`` order, as
        the sensors measure them (realism: noise, offset, drift, bandwidth)."""
        if self._ft_measured is not None:
            return self._ft_measured.copy()
        return self.true_ft_all()

    def true_ft_all(self) -> np.ndarray:
        """The true FT wrenches (4, 6) (:meth:`ft_all` without sensor imperfections)."""
        return -self.data.sensordata[self._ft_index].reshape(len(FT_SENSORS), 6)

    def imu(self) -> ImuReading:
        """Head IMU (module doc)."""
        s, a = self.data.sensordata, self._imu_adr
        gyro = s[a["gyro"]:a["gyro"] + 3].copy()
        acc = s[a["accelerometer"]:a["accelerometer"] + 3].copy()
        imu = self.imperfections.imu if self.imperfections else None
        if imu is not None:
            gyro, acc = imu.gyro(gyro), imu.accelerometer(acc)
        return ImuReading(s[a["orientation"]:a["orientation"] + 4].copy(), gyro, acc)

    def contact_wrench(self, hand: str) -> Wrench:
        """Ground-truth total external wrench on ``hand``'s body (contacts + applied), in
        root_link, moment about the hand frame origin."""
        if hand not in self._hand_body:
            raise UnknownName("hand", hand, _HANDS)
        d, m = self.data, self.model
        b = self._hand_body[hand]
        # cfrc_ext: (torque, force) about subtree_com of the tree's root body, world axes
        c = d.subtree_com[m.body_rootid[b]]
        tau_c, f = d.cfrc_ext[b, :3], d.cfrc_ext[b, 3:]
        p = d.site_xpos[self._hand_site[hand]]
        return Wrench(f.copy(), tau_c + _cross(c - p, f))

    def self_contacts(self) -> list[SelfContact]:
        """Ground truth: the robot's links touching each other now (class doc of
        :class:`SelfContact`); empty when none do."""
        d = self.data
        if d.ncon == 0:
            return []
        s1 = self._geom_side[d.contact.geom1]
        s2 = self._geom_side[d.contact.geom2]
        out = []
        for i in np.flatnonzero((s1 > 0) & (s2 > 0) & (s1 != s2)):
            k1, k2 = s1[i], s2[i]
            kind = "arm-torso" if 3 in (k1, k2) else "arm-arm"
            # body1: the left arm's link, or the arm's against the torso
            out.append(self._contact(int(i), kind, first_is_geom1=bool(k1 <= k2)))
        return out

    def object_contacts(self) -> list[ObjectContact]:
        """Ground truth: the robot's links touching movable objects now (class doc of
        :class:`ObjectContact`); empty when none do."""
        d, m = self.data, self.model
        if d.ncon == 0:
            return []
        g1, g2 = d.contact.geom1, d.contact.geom2
        o1, o2 = self._geom_object[g1], self._geom_object[g2]
        s1, s2 = self._geom_side[g1], self._geom_side[g2]
        out = []
        for i in np.flatnonzero(((o1 >= 0) & (s2 > 0)) | ((o2 >= 0) & (s1 > 0))):
            obj, side, geom = ((o1[i], s2[i], g2[i]) if o1[i] >= 0 else (o2[i], s1[i], g1[i]))
            mujoco.mj_contactForce(m, d, int(i), self._f6)
            name = self._object_list[obj]
            arm = ("left", "right", "torso")[side - 1]
            out.append(ObjectContact(name, m.body(int(m.geom_bodyid[geom])).name, arm,
                                     self._grasped.get(arm) == name, d.contact[i].pos.copy(),
                                     float(self._f6[0])))
        return out

    @property
    def grasped(self) -> dict[str, str]:
        """{hand: object} welded now (the emulated grasps)."""
        return dict(self._grasped)

    @property
    def graspable(self) -> tuple[str, ...]:
        """The objects a hand can grasp: the tabletop cubes (``SimConfig.tabletop_objects``)."""
        return tabletop_names(self.config)

    def palm_touches(self, hand: str, name: str) -> bool:
        """True when ``hand``'s body (the palm: the model has no fingers) touches object
        ``name`` in the current contacts."""
        body = self.built.hand_bodies[hand]
        return any(c.object == name and c.body == body for c in self.object_contacts())

    def grasp(self, name: str, hand: str) -> None:
        """Attach cube ``name`` to ``hand``'s palm where it is now (a weld switched on, the
        relative pose of this instant). Refused (:class:`GraspRefused`, nothing changes)
        unless the palm touches the cube in the simulator's contacts, or when the hand
        holds another object or the other hand holds this one."""
        if hand not in _HANDS:
            raise UnknownName("hand", hand, _HANDS)
        if name not in self.graspable:
            raise UnknownName("graspable object", name, self.graspable)
        if self._grasped.get(hand) == name:
            return
        if hand in self._grasped:
            raise GraspRefused(f"grasp {name!r}: the {hand} hand already holds "
                               f"{self._grasped[hand]!r}; release it first")
        for h, o in self._grasped.items():
            if o == name:
                raise GraspRefused(f"grasp {name!r}: the {h} hand holds it; release it first")
        if not self.palm_touches(hand, name):
            raise GraspRefused(
                f"grasp {name!r} with the {hand} hand refused: the palm "
                f"({self.built.hand_bodies[hand]}) does not touch it (object at "
                f"{np.round(self.object_pose(name).position, 3).tolist()} m, hand at "
                f"{np.round(self.frame_pose(self.built.hand_frames[hand]).position, 3).tolist()}"
                f" m)")
        m, d = self.model, self.data
        eq = self._welds[(hand, name)]
        b1, b2 = int(m.eq_obj1id[eq]), int(m.eq_obj2id[eq])
        # relpose: body2 (the cube) in body1's (the hand's) frame, now
        R1 = d.xmat[b1].reshape(3, 3)
        pos = R1.T @ (d.xpos[b2] - d.xpos[b1])
        q1inv = np.zeros(4)
        mujoco.mju_negQuat(q1inv, d.xquat[b1])
        quat = np.zeros(4)
        mujoco.mju_mulQuat(quat, q1inv, d.xquat[b2])
        m.eq_data[eq, :] = 0.0
        m.eq_data[eq, 3:6] = pos
        m.eq_data[eq, 6:10] = quat
        m.eq_data[eq, 10] = 1.0  # torquescale
        d.eq_active[eq] = 1
        self._grasped[hand] = name

    def release(self, hand: str) -> str | None:
        """Switch ``hand``'s grasp weld off (the cube is left to the physics where it is);
        returns the object released, None when the hand held nothing."""
        if hand not in _HANDS:
            raise UnknownName("hand", hand, _HANDS)
        name = self._grasped.pop(hand, None)
        if name is not None:
            self.data.eq_active[self._welds[(hand, name)]] = 0
        return name

    def _contact(self, i: int, kind: str, first_is_geom1: bool) -> SelfContact:
        """MuJoCo contact ``i`` as a :class:`SelfContact` whose ``body1`` is the body of geom1
        (``first_is_geom1``) or of geom2, the force being the one exerted on ``body1``."""
        d, m = self.data, self.model
        c = d.contact[i]
        mujoco.mj_contactForce(m, d, i, self._f6)
        # contact frame: first row = normal from geom1 to geom2; the force is on geom2
        on_2 = c.frame.reshape(3, 3).T @ self._f6[:3]
        b1, b2 = int(m.geom_bodyid[c.geom1]), int(m.geom_bodyid[c.geom2])
        if first_is_geom1:
            on_1 = -on_2
        else:
            b1, b2, on_1 = b2, b1, on_2
        return SelfContact(kind, m.body(b1).name, m.body(b2).name, c.pos.copy(), on_1,
                           float(self._f6[0]), float(max(-c.dist, 0.0)))

    def frame_pose(self, name: str) -> Pose:
        """Pose of a site (URDF frame) or body ``name`` in root_link."""
        d, m = self.data, self.model
        sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, name)
        if sid >= 0:
            q = np.zeros(4)
            mujoco.mju_mat2Quat(q, d.site_xmat[sid])
            return Pose(d.site_xpos[sid].copy(), q)
        bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
        if bid < 0:
            raise UnknownName("frame", name, self.frame_names())
        return Pose(d.xpos[bid].copy(), d.xquat[bid].copy())

    def frame_names(self) -> list[str]:
        """Every site (URDF frame) and body name."""
        m = self.model
        return [m.site(i).name for i in range(m.nsite)] + [m.body(i).name
                                                             for i in range(1, m.nbody)]

    # ------------------------------------------------------------------ scene
    @property
    def object_names(self) -> tuple[str, ...]:
        """Movable objects on the table."""
        return tuple(self._objects)

    def object_pose(self, name: str) -> Pose:
        """Pose of object ``name`` in root_link."""
        if name not in self._objects:
            raise UnknownName("object", name, self._objects)
        b = self._objects[name][0]
        return Pose(self.data.xpos[b].copy(), self.data.xquat[b].copy())

    def set_object_pose(self, name: str, position: Sequence[float],
                        quaternion: Sequence[float] = (1.0, 0.0, 0.0, 0.0)) -> None:
        """Teleport object ``name`` to ``position`` [m], ``quaternion`` (w, x, y, z), at rest
        (a scripted motion of it, :meth:`move_object`, ends)."""
        p, q = self._checked_object_pose(name, position, quaternion)
        self._motions.pop(name, None)
        _, qa, da = self._objects[name]
        self.data.qpos[qa:qa + 3] = p
        self.data.qpos[qa + 3:qa + 7] = q
        self.data.qvel[da:da + 6] = 0.0
        mujoco.mj_forward(self.model, self.data)
        self._keep_good_state()

    def move_object(self, name: str, position: Sequence[float], velocity: Sequence[float],
                    duration: float, quaternion: Sequence[float] = (1.0, 0.0, 0.0, 0.0)
                    ) -> tuple[float, float]:
        """Move object ``name`` from ``position`` [m] at constant ``velocity`` [m/s]
        (root_link) for ``duration`` [s] of simulated time, then leave it at rest: each
        :meth:`step` puts it where the motion is at that step's time, so the motion is the same
        however fast the simulation runs. Teleporting it, a reset or another motion of it ends
        the motion. Returns the simulated times [s] of its start (now) and end.

        Raises:
            InvalidInput: a bad start or end pose (as :meth:`set_object_pose`), a velocity that
                is not (3,) finite, a duration outside (0, ``max_wrench_duration``].
        """
        v = np.asarray(velocity, dtype=float).reshape(-1)
        if v.size != 3 or not np.all(np.isfinite(v)):
            raise InvalidInput(f"move_object: velocity must be 3 finite values [m/s], got "
                               f"{v.tolist()}")
        limit = self.config.max_wrench_duration
        if not (math.isfinite(duration) and 0.0 < duration <= limit):
            raise InvalidInput(f"move_object: duration must be in (0, {limit:g}] s "
                               f"(max_wrench_duration), got {duration:g}")
        p, q = self._checked_object_pose(name, position, quaternion)
        self._checked_object_pose(name, p + v * duration, q)
        self.set_object_pose(name, p, q)
        t0 = float(self.data.time)
        self._motions[name] = _ObjectMotion(p, q, v, t0, float(duration))
        return t0, t0 + float(duration)

    def _checked_object_pose(self, name: str, position: Sequence[float],
                             quaternion: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
        """(position (3,), unit quaternion (4,)) of a valid object pose, else InvalidInput."""
        if name not in self._objects:
            raise UnknownName("object", name, self._objects)
        p = np.asarray(position, dtype=float).reshape(-1)
        q = np.asarray(quaternion, dtype=float).reshape(-1)
        if p.size != 3 or q.size != 4 or not (np.all(np.isfinite(p)) and np.all(np.isfinite(q))):
            raise InvalidInput(f"object pose: need finite position (3,) and quaternion (4,), "
                               f"got {p.tolist()}, {q.tolist()}")
        nq = np.linalg.norm(q)
        if nq < 1e-9:
            raise InvalidInput(f"object pose: quaternion {q.tolist()} has zero norm")
        r = float(np.linalg.norm(p))
        if r > self.config.object_workspace_radius:
            raise InvalidInput(
                f"object pose: position {p.tolist()} is {r:.3g} m from root_link; expected "
                f"within object_workspace_radius {self.config.object_workspace_radius:g} m")
        if p[2] < self.floor_height:
            raise InvalidInput(f"object pose: position z = {p[2]:g} m is below the floor "
                               f"(z = {self.floor_height:g} m)")
        return p, q / nq

    def apply_wrench(self, target: str, force: Sequence[float], torque: Sequence[float],
                     duration: float) -> None:
        """Apply ``force`` [N] and ``torque`` [N m] (root_link axes) at the origin of a frame
        (site) or at a body's origin, for ``duration`` [s] of simulated time. Raises
        :class:`InvalidInput` beyond ``max_wrench_force`` / ``max_wrench_torque`` /
        ``max_wrench_duration`` (``SimConfig``) and changes nothing."""
        f = np.asarray(force, dtype=float).reshape(-1)
        tq = np.asarray(torque, dtype=float).reshape(-1)
        if f.size != 3 or tq.size != 3 or not (np.all(np.isfinite(f)) and
                                               np.all(np.isfinite(tq))):
            raise InvalidInput(f"apply_wrench: need finite force (3,) and torque (3,), got "
                               f"{f.tolist()}, {tq.tolist()}")
        cfg = self.config
        if not np.isfinite(duration) or duration <= 0.0 or duration > cfg.max_wrench_duration:
            raise InvalidInput(f"apply_wrench: duration must be in (0, {cfg.max_wrench_duration:g}]"
                               f" s (max_wrench_duration), got {duration:g}")
        for what, vec, limit, unit, param in (
                ("force", f, cfg.max_wrench_force, "N", "max_wrench_force"),
                ("torque", tq, cfg.max_wrench_torque, "N m", "max_wrench_torque")):
            mag = float(np.linalg.norm(vec))
            if mag > limit:
                raise InvalidInput(f"apply_wrench: |{what}| = {mag:.4g} {unit} is beyond "
                                   f"{param} {limit:g} {unit}")
        m, d = self.model, self.data
        sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, target)
        if sid >= 0:
            body = int(m.site_bodyid[sid])
            R = d.xmat[body].reshape(3, 3)
            point = R.T @ (d.site_xpos[sid] - d.xpos[body])
        else:
            body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, target)
            if body <= 0:
                raise UnknownName("frame or body", target, self.frame_names())
            point = np.zeros(3)
        self._applied.append(_AppliedWrench(body, point, f, tq, d.time + duration))

    def clear_applied_wrenches(self) -> None:
        """Remove every scripted wrench."""
        self._applied.clear()
