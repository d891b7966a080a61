"""FtDynamicsModel: the upper-body dynamics graph cut by the arm FT sensors (Fig. 4b, eqs 8-10).

The paper propagates kinematics from the base (eq 8) and wrenches from the sensors (eqs 9-10):
these are the recursive Newton-Euler equations, computed here by pinocchio's RNEA. To read the
wrench that crosses each arm FT sensor straight out of RNEA, the URDF fixed joints
``l_arm_ft_sensor`` / ``r_arm_ft_sensor`` (``l_shoulder_3`` -> ``l_upper_arm``) are turned into
revolute joints held at q = v = a = 0: pinocchio then keeps the upper arm as a separate body and
``data.f[ft_joint]`` is the wrench that the proximal side (shoulder) applies to the distal side
(upper arm, forearm, hand) through the sensor, in the sensor frame (``l_arm_ft``), about its
origin. That wrench is what the sensor measures, in this module's sign convention
("parent on child"; the estimator converts other conventions).

Legs are locked at 0 (fixed mainstay); the leg FT sensors are not modelled.
Units: m, rad, kg, N, N m. Wrenches are (6,) = [force (3), torque (3)].
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Mapping, NamedTuple, Sequence

import numpy as np
import pinocchio as pin

from icub_pmp.errors import InvalidInput, ModelError, UnknownName
from icub_pmp.kinematics.name_index import name_indices
from icub_pmp.kinematics.robot_spec import HANDS, RobotSpec, urdf_path

__all__ = ["FtDynamicsModel", "SensorWrenches", "FT_JOINTS"]

#: URDF fixed joint that carries each arm FT sensor (joint frame == sensor frame ``*_arm_ft``).
FT_JOINTS: Mapping[str, str] = {"left": "l_arm_ft_sensor", "right": "r_arm_ft_sensor"}


class SensorWrenches(NamedTuple):
    """Result of one RNEA pass: per hand, the wrench through the arm FT sensor.

    ``sensor``: {hand: (6,)} wrench the shoulder applies to the distal arm, sensor frame [N, N m];
    ``tau``: joint torques (nq,) [N m] over :attr:`FtDynamicsModel.joint_names`.
    """

    sensor: dict[str, np.ndarray]
    tau: np.ndarray


class FtDynamicsModel:
    """pinocchio model of the upper body with the arm FT sensors as (motionless) joints.

    ``q, v, a`` vectors have the 20 upper-body joints in :attr:`joint_names` order (the same
    order as :class:`~icub_pmp.kinematics.IcubModel`). ``link_mass_scale`` multiplies the mass
    and inertia of named URDF links (e.g. ``{"l_forearm": 1.1}``): a deliberate model mismatch.
    ``gravity`` is the gravity vector in root_link [m/s^2] (changeable with
    :meth:`set_gravity`, e.g. from the IMU).
    """

    def __init__(
        self,
        spec: RobotSpec | None = None,
        link_mass_scale: Mapping[str, float] | None = None,
    ):
        self.spec = spec or RobotSpec.load()
        self.urdf = urdf_path(self.spec.model_name)
        xml, self._link_masses = _prepare_urdf(self.urdf.read_text(), dict(link_mass_scale or {}))
        try:
            full = pin.buildModelFromXML(xml)
        except Exception as exc:  # pinocchio raises plain RuntimeError/ValueError
            raise ModelError(
                f"pinocchio cannot load the FT-cut model of {self.urdf}: {exc}") from exc
        keep = set(self.spec.upper_body_joints) | set(FT_JOINTS.values())
        lock = [full.getJointId(n) for n in full.names[1:] if n not in keep]
        self.model: pin.Model = pin.buildReducedModel(full, lock, pin.neutral(full))
        self.data: pin.Data = self.model.createData()
        names = list(self.model.names[1:])
        self.joint_names: tuple[str, ...] = tuple(n for n in names if n not in FT_JOINTS.values())
        self.nq = len(self.joint_names)
        #: positions of the 20 actuated joints inside the 22-dof pinocchio vectors
        self._act = np.array([names.index(n) for n in self.joint_names])
        self._ft_joint = {h: self.model.getJointId(j) for h, j in FT_JOINTS.items()}
        self._hand_frame = {h: self.model.getFrameId(self.spec.hand_frame(h)) for h in HANDS}
        self._sensor_frame = {
            h: self.model.getFrameId(self.spec.arm_ft_frames[h]) for h in HANDS
        }
        self._q = pin.neutral(self.model)
        self._v = np.zeros(self.model.nv)
        self._a = np.zeros(self.model.nv)
        self._fext = pin.StdVec_Force()
        for _ in range(self.model.njoints):
            self._fext.append(pin.Force.Zero())
        self._ft_ids = [(h, j) for h, j in self._ft_joint.items()]
        # joint-local placement of each hand frame (to apply hand wrenches as f_ext)
        self._hand_in_joint = {
            h: self.model.frames[f].placement for h, f in self._hand_frame.items()
        }
        self._hand_joint = {
            h: self.model.frames[f].parentJoint for h, f in self._hand_frame.items()
        }
        self._fext_hands = pin.StdVec_Force()
        for _ in range(self.model.njoints):
            self._fext_hands.append(pin.Force.Zero())
        self._passes = [_HandPass.create(h, self) for h in HANDS]
        self.lower = np.array(self.model.lowerPositionLimit[self._act])
        self.upper = np.array(self.model.upperPositionLimit[self._act])

    # ------------------------------------------------------------------ configuration
    @property
    def gravity(self) -> np.ndarray:
        """Gravity in root_link (3,) [m/s^2]."""
        return np.array(self.model.gravity.linear)

    def set_gravity(self, g: Sequence[float]) -> None:
        """Set the gravity vector (3,) in root_link [m/s^2] (finite, 5..15 m/s^2 in norm)."""
        g = np.asarray(g, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise InvalidInput(f"gravity: expected 3 finite values, got {g!r}")
        if not 5.0 <= float(np.linalg.norm(g)) <= 15.0:
            raise InvalidInput(f"gravity: norm {np.linalg.norm(g):.2f} m/s^2 outside 5..15")
        self.model.gravity = pin.Motion(g, np.zeros(3))

    def indices(self, names: Sequence[str]) -> np.ndarray:
        """Positions of URDF joints ``names`` in the (nq,) vectors (raises UnknownName)."""
        index = {n: i for i, n in enumerate(self.joint_names)}
        return name_indices(names, index, self.joint_names)

    def _load(self, q: np.ndarray, v: np.ndarray | None, a: np.ndarray | None) -> None:
        self._q[self._act] = q
        self._v[self._act] = 0.0 if v is None else v
        self._a[self._act] = 0.0 if a is None else a

    # ------------------------------------------------------------------ dynamics
    def rnea(
        self,
        q: np.ndarray,
        v: np.ndarray | None = None,
        a: np.ndarray | None = None,
        hand_wrenches: Mapping[str, np.ndarray] | None = None,
    ) -> SensorWrenches:
        """RNEA (eqs 8-10) with optional external wrenches on the hands.

        ``hand_wrenches``: {hand: (6,)} wrench the environment applies to the hand, in the
        hand frame (``l_hand_dh_frame``), about its origin [N, N m]. Returns the wrench across
        each FT sensor and the joint torques (the torques the motors must supply). Also leaves
        the joint placements of ``q`` ready for :meth:`hand_placements`.
        """
        self._load(q, v, a)
        if hand_wrenches:
            for hand in hand_wrenches:
                if hand not in self._hand_joint:
                    raise UnknownName("hand", hand, HANDS)
            hand_wrenches = {h: np.asarray(w, dtype=float) for h, w in hand_wrenches.items()}
        tau = self._rnea_loaded(hand_wrenches)
        pin.forwardKinematics(self.model, self.data, self._q)
        return SensorWrenches(sensor=self.sensor_wrenches(), tau=tau)

    def _rnea_loaded(self, hand_wrenches: Mapping[str, np.ndarray] | None) -> np.ndarray:
        """RNEA on the loaded 22-dof vectors; returns the 20 actuated torques."""
        if hand_wrenches:
            fext = self._fext
            for hand, w in hand_wrenches.items():
                j = self._hand_joint[hand]
                fext[j] = self._hand_in_joint[hand].act(pin.Force(w))
            tau = pin.rnea(self.model, self.data, self._q, self._v, self._a, fext)
            for hand in hand_wrenches:
                fext[self._hand_joint[hand]] = pin.Force.Zero()
        else:
            tau = pin.rnea(self.model, self.data, self._q, self._v, self._a)
        return tau[self._act]

    def free_sensor_wrenches(
        self, q: np.ndarray, v: np.ndarray, a: np.ndarray
    ) -> dict[str, np.ndarray]:
        """The estimator's first pass: RNEA (eqs 8-10) with no external wrench for the state
        ``q, v, a`` (nq,) (validated by the caller), and the forward kinematics of ``q``.
        Returns {hand: (6,)} the wrench through each FT sensor (parent on child, sensor frame)
        and keeps the state loaded for :meth:`torques_with_sensor_excess`."""
        act = self._act
        self._q[act] = q
        self._v[act] = v
        self._a[act] = a
        pin.rnea(self.model, self.data, self._q, self._v, self._a)
        out = {}
        for hp in self._passes:
            out[hp.hand] = hp.sensor_wrench.copy()
        pin.forwardKinematics(self.model, self.data, self._q)
        return out

    def torques_with_sensor_excess(
        self, excess: Mapping[str, np.ndarray]
    ) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
        """The estimator's second pass (eqs 2-3) for the state of the last
        :meth:`free_sensor_wrenches`: ``excess`` {hand: (6,)} = predicted internal minus
        measured sensor wrench (sensor frame, about its origin) = the external wrench on the
        distal arm. Returns the joint torques (nq,) with those external wrenches applied at the
        hands (RNEA), and the wrenches {hand: (6,)} about the hand origin in hand-frame axes
        and in root_link axes. Every hand in :data:`HANDS` must be given."""
        fext = self._fext_hands  # both hand entries are overwritten on every call
        model, data = self.model, self.data
        ext_hand, ext_root = {}, {}
        for hp in self._passes:
            hp.excess_vector[:] = excess[hp.hand]
            f_root = hp.sensor_pose.act(hp.excess)  # in root_link, about the root origin
            f_joint = hp.joint_pose.actInv(f_root)  # RNEA takes f_ext in the joint's frame
            fext[hp.joint] = f_joint
            ext_hand[hp.hand] = hp.joint_in_hand.act(f_joint).vector
            pin.updateFramePlacement(model, data, hp.frame)  # the hand frame in root_link
            hp.shift_translation[:] = hp.hand_translation
            ext_root[hp.hand] = hp.shift.actInv(f_root).vector
        tau = pin.rnea(self.model, self.data, self._q, self._v, self._a, fext)
        return tau[self._act], ext_hand, ext_root

    def sensor_wrenches(self) -> dict[str, np.ndarray]:
        """{hand: (6,)} wrench through each FT sensor after the last RNEA (parent on child,
        sensor frame) [N, N m]."""
        f = self.data.f
        return {h: f[j].vector.copy() for h, j in self._ft_ids}

    def hand_placements(self, hand: str) -> tuple[pin.SE3, pin.SE3]:
        """(``T_sensor_hand``, ``T_root_hand``) for the configuration of the last
        :meth:`rnea` or :meth:`forward` call."""
        if hand not in self._hand_frame:
            raise UnknownName("hand", hand, HANDS)
        o_mi = self.data.oMi
        o_h = o_mi[self._hand_joint[hand]] * self._hand_in_joint[hand]
        # the sensor frame is the FT joint's frame (at q = 0)
        return o_mi[self._ft_joint[hand]].actInv(o_h), o_h

    def forward(self, q: np.ndarray) -> None:
        """Forward kinematics for ``q`` (nq,) [rad] (frames updated)."""
        self._load(q, None, None)
        pin.forwardKinematics(self.model, self.data, self._q)

    def frame_rotation(self, frame: str) -> np.ndarray:
        """Rotation ``R_root_frame`` (3, 3) for the configuration of the last :meth:`rnea` or
        :meth:`forward` call."""
        if not self.model.existFrame(frame):
            raise UnknownName("frame", frame, [f.name for f in self.model.frames])
        fid = self.model.getFrameId(frame)
        return pin.updateFramePlacement(self.model, self.data, fid).rotation.copy()

    def link_mass(self, link: str) -> float:
        """Mass [kg] of URDF link ``link`` in this model (after any scaling)."""
        if link not in self._link_masses:
            raise UnknownName("link", link, self._link_masses)
        return self._link_masses[link]


def _prepare_urdf(xml: str, link_mass_scale: dict[str, float]) -> tuple[str, dict[str, float]]:
    """The URDF text with the arm FT fixed joints made revolute and some link masses scaled,
    and the link masses [kg] of the result."""
    root = ET.fromstring(xml)
    joints = {j.get("name"): j for j in root.iter("joint")}
    for name in FT_JOINTS.values():
        j = joints.get(name)
        if j is None:
            raise ModelError(f"URDF has no FT sensor joint {name!r}")
        j.set("type", "revolute")
        ET.SubElement(j, "axis", {"xyz": "0 0 1"})
        ET.SubElement(j, "limit", {"lower": "0", "upper": "0", "effort": "0", "velocity": "0"})
    links = {lk.get("name"): lk for lk in root.iter("link")}
    for link, s in link_mass_scale.items():
        if link not in links:
            raise UnknownName("link", link, [n for n in links if n])
        if not (np.isfinite(s) and s > 0):
            raise InvalidInput(f"link_mass_scale[{link!r}] = {s}: expected a positive number")
        inertial = links[link].find("inertial")
        if inertial is None:
            raise ModelError(f"URDF link {link!r} has no inertial element")
        m = inertial.find("mass")
        m.set("value", repr(float(m.get("value")) * s))
        ine = inertial.find("inertia")
        for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
            ine.set(k, repr(float(ine.get(k)) * s))
    masses = {}
    for name, lk in links.items():
        m = lk.find("inertial/mass")
        masses[name] = float(m.get("value")) if m is not None else 0.0
    return ET.tostring(root, encoding="unicode"), masses


class _HandPass:
    """Per hand, what the estimator's two passes touch at 1 kHz, bound once: numpy views into
    pinocchio's data (the FT joint's RNEA wrench, the hand joint's placement) and preallocated
    objects written in place. Converting numpy <-> pinocchio objects costs a few microseconds
    per call right after a physics step; reading and writing these views costs a numpy copy.
    (The views stay valid: ``data`` is never reallocated.) Side effect of the second pass:
    ``data.oMf`` of the hand frames is updated."""

    __slots__ = ("hand", "joint", "frame", "sensor_wrench", "sensor_pose", "joint_pose",
                 "hand_translation", "joint_in_hand", "excess", "excess_vector", "shift",
                 "shift_translation")

    @classmethod
    def create(cls, hand: str, m: "FtDynamicsModel") -> "_HandPass":
        hp = cls()
        hp.hand = hand
        j_ft, hp.joint = m._ft_joint[hand], m._hand_joint[hand]
        hp.sensor_wrench = m.data.f[j_ft].vector  # view: the wrench through the sensor
        hp.sensor_pose = m.data.oMi[j_ft]  # reference: the sensor frame in root_link
        hp.joint_pose = m.data.oMi[hp.joint]  # reference: the hand's parent joint frame
        hp.frame = m._hand_frame[hand]
        hp.hand_translation = m.data.oMf[hp.frame].translation  # view: hand origin in root
        hp.joint_in_hand = m._hand_in_joint[hand].inverse()
        hp.excess = pin.Force.Zero()
        hp.excess_vector = hp.excess.vector  # writable view
        hp.shift = pin.SE3.Identity()  # root_link axes at the hand origin
        hp.shift_translation = hp.shift.translation  # writable view
        return hp
