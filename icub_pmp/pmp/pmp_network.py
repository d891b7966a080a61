"""PmpNetwork: one assembled PMP network (fields + branches + body model) for one task.

It evaluates, at a state ``z`` (the network's joint angles, plus the held object's position
when there is one), everything a relaxation step needs (Appendix A, eq A1):

- the extrinsic forces ``F`` of every task row (eq 1: targets, orientation, obstacles, object
  goal and grasp coupling of Sect. 3.2), stacked (m,);
- the stacked Jacobian ``G`` (m, nz) of the task values w.r.t. ``z`` (hand rows from the body
  model, eq 2/4; object rows from the device Jacobian ``J_D``);
- the internal torques on ``z`` (eq 6 joint-limit field, the posture field of the posture
  memory, the torque-limit field of Sect. 2.3) and their diagonal stiffness;
- the admittance diagonal ``A`` (nz,) of the branching network (Sect. 2.5/3.1) and ``A_E``.

The relaxation (:mod:`relaxation`) then integrates ``z' = A (G^T F + T_int)``.
"""

from __future__ import annotations

from typing import Mapping, NamedTuple, Sequence, cast

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.pmp.body_volume import BodyVolume
from icub_pmp.pmp.branch_network import BranchNetwork
from icub_pmp.pmp.force_field import ForceField
from icub_pmp.pmp.held_object import HeldObject
from icub_pmp.pmp.jacobian_provider import JacobianProvider
from icub_pmp.pmp.joint_limit_field import JointLimitField
from icub_pmp.pmp.obstacle_field import ObstacleField
from icub_pmp.pmp.orientation_field import OrientationField
from icub_pmp.pmp.torque_limit_field import TorqueLimitField

__all__ = ["PmpNetwork", "NetworkState", "PostureField"]


class PostureField(NamedTuple):
    """Intrinsic attractor toward a remembered posture, fading with relaxation time s:
    ``T = k0 exp(-s / decay) (q_ref - q)`` (the DARWIN PMP's ``K_int (q_ref - q)`` field)."""

    q_ref: np.ndarray  # (n,) [rad] over the network joints
    gain: float  # k0 [N m/rad]
    decay: float  # [relaxation time s]


class NetworkState(NamedTuple):
    """Everything one relaxation step needs at a state z."""

    force: np.ndarray  # (m,) stacked extrinsic forces [N | N m]
    jacobian: np.ndarray  # (m, nz)
    torque: np.ndarray  # (nz,) internal torques
    stiffness: np.ndarray  # (nz,) diagonal of -d torque / dz (>= 0)
    hand_positions: np.ndarray  # (k, 3) [m]
    hand_rotations: np.ndarray  # (k, 3, 3)
    position_errors: np.ndarray  # (k,) [m] distance of each hand to its final target
    rotation_errors: np.ndarray  # (k,) [rad] (0 for position-only hands)
    clearance: float  # smallest hand clearance to an obstacle [m] (inf without obstacles)
    torque_excess: float  # max |excess torque| / rating over the joints (0 without a limit field)


class PmpNetwork:
    """A PMP network for k hands on a body model.

    Args:
        provider: the body model (forward kinematics + Jacobians).
        branches: joints and admittances (trunk + one branch per hand).
        frames: hand -> end-effector frame of the body model.
        q_start: full configuration (provider.nq,); joints outside the network stay there.
        targets: hand -> position field (eq 1), for hands not coupled to ``held_object``.
        orientations: hand -> orientation field (optional per hand).
        obstacles: repulsive fields acting on every hand.
        joint_limits: eq 6 field over the network joints (its limits bound z).
        held_object: object coupled to its grasping hands (Sect. 3.2), or None.
        posture: posture field (from the posture memory), or None.
        torque_field: saturation field of Sect. 2.3, or None.
        volumes: hand -> spheres covering its arm's links (:class:`BodyVolume`): the
            obstacle fields also act on them (their torques join the internal ones) and the
            clearance counts them; hands without one are kept clear at their frame only.
        volume_null_distance: [m] within this distance of its target a hand's volume
            fields act in the null space of its position only (0 = never).
    """

    def __init__(
        self,
        provider: JacobianProvider,
        branches: BranchNetwork,
        frames: Mapping[str, str],
        q_start: np.ndarray,
        targets: Mapping[str, ForceField],
        orientations: Mapping[str, OrientationField] | None = None,
        obstacles: Sequence[ObstacleField] = (),
        joint_limits: JointLimitField | None = None,
        held_object: HeldObject | None = None,
        posture: PostureField | None = None,
        torque_field: TorqueLimitField | None = None,
        volumes: Mapping[str, BodyVolume] | None = None,
        volume_null_distance: float = 0.0,
    ):
        self.provider = provider
        self.branches = branches
        self.hands: tuple[str, ...] = tuple(branches.branches)
        missing = [h for h in self.hands if h not in frames]
        if missing:
            raise InvalidInput(f"no end-effector frame for hand(s) {missing}")
        self.frames = tuple(frames[h] for h in self.hands)
        self._q_start = np.array(q_start, dtype=float)
        if self._q_start.shape != (provider.nq,):
            raise InvalidInput(f"q_start: expected ({provider.nq},), got {self._q_start.shape}")
        self.joint_index = np.array(
            [provider.joint_names.index(j) for j in branches.joint_names], dtype=int
        )
        self.n = branches.n
        self.orientations = dict(orientations or {})
        self.obstacles = tuple(obstacles)
        self.held_object = held_object
        self.posture = posture
        self.torque_field = torque_field
        self.volumes = {h: v for h, v in (volumes or {}).items() if h in self.hands}
        self.volume_null_distance = float(volume_null_distance)
        coupled = set(held_object.hands) if held_object else set()
        for h in coupled:
            if h not in self.hands:
                raise InvalidInput(f"held object: grasping hand {h!r} is not in the network")
        for h in self.hands:
            if h not in coupled and h not in targets:
                raise InvalidInput(f"no target field for hand {h!r}")
        self.targets = {h: targets[h] for h in self.hands if h not in coupled}
        if joint_limits is None:
            idx = self.joint_index
            joint_limits = JointLimitField(provider.lower[idx], provider.upper[idx], 0.0)
        if joint_limits.lower.shape != (self.n,):
            raise InvalidInput(f"joint limits: expected {self.n} joints")
        self.joint_limits = joint_limits
        self.nz = self.n + (3 if held_object else 0)
        a = [branches.admittance] + ([np.full(3, held_object.admittance)] if held_object else [])
        #: admittance diagonal (nz,)
        self.admittance = np.concatenate(a)
        self._build_rows(coupled)

    # ------------------------------------------------------------------ layout
    def _build_rows(self, coupled: set[str]) -> None:
        """Row layout of the stacked task space and its constant field stiffness K (m, m)."""
        rows: list[tuple[str, str, int]] = []  # (kind, hand, first row)
        blocks: list[np.ndarray] = []
        r = 0
        for h in self.hands:
            if h in coupled:
                rows.append(("grasp", h, r))
                blocks.append(np.eye(3) * cast(HeldObject, self.held_object).grasp_stiffness)
            else:
                rows.append(("position", h, r))
                blocks.append(self.targets[h].jacobian)
            r += 3
            if h in self.orientations:
                rows.append(("orientation", h, r))
                blocks.append(np.eye(3) * self.orientations[h].stiffness)
                r += 3
        if self.held_object is not None:
            rows.append(("object", "", r))
            blocks.append(np.eye(3) * self.held_object.goal_stiffness)
            r += 3
        self.m = r
        self._rows = rows
        self._hand_rows = {
            hand: np.concatenate([np.arange(r0, r0 + 3) for _, h, r0 in rows if h == hand])
            for hand in self.hands
        }
        k = np.zeros((r, r))
        for (_, _, r0), b in zip(rows, blocks):
            k[r0:r0 + 3, r0:r0 + 3] = b
        self._base_stiffness = k
        self._row_gain = np.ones(r)
        self._balance_gain = np.ones(r)
        #: -dF/dy of the attractive fields (m, m); obstacles are applied explicitly
        self.field_stiffness = k.copy()
        self.field_stiffness.setflags(write=False)
        self._final_targets = np.array([self.final_target(h) for h in self.hands])
        self._fast = self.held_object is None and not self.orientations
        if self._fast:  # position-only hands: F = K (y_T - y) in one product
            self._y_target = self._final_targets.reshape(-1)
        self._zero_rot = np.zeros(len(self.hands))
        self._zero_rot.setflags(write=False)

    def hand_rows(self, hand: str) -> np.ndarray:
        """Task rows (position, orientation, grasp) belonging to ``hand``."""
        return self._hand_rows[hand]

    def balance_hands(self, state: NetworkState) -> np.ndarray:
        """Scale each hand's field stiffness so all hands start relaxing at the same rate.

        The rate of hand i (Appendix A's gamma, eq A2) is ``|G_i^T F_i|^2_A / F_i^T K_i^-1
        F_i``; hands whose arm is less mobile along their target direction get a
        proportionally stiffer field (an anisotropy between the branches' K_ext, eq 1), so
        under one TBG they progress alike. Returns the gains (k,) (1 = unchanged).
        """
        rates = np.zeros(len(self.hands))
        for i, h in enumerate(self.hands):
            rows = self.hand_rows(h)
            f = state.force[rows]
            gf = state.jacobian[rows].T @ f
            kinv_f = np.linalg.lstsq(self._base_stiffness[np.ix_(rows, rows)], f, rcond=None)[0]
            den = float(f @ kinv_f)
            num = float(gf @ (self.admittance * gf))
            rates[i] = num / den if den > 0 and num > 0 else 0.0
        gains = np.ones(len(self.hands))
        live = rates > 0
        if live.sum() >= 2:
            mean = float(np.exp(np.mean(np.log(rates[live]))))
            gains[live] = mean / rates[live]
        row_gain = np.ones(self.m)
        for i, h in enumerate(self.hands):
            row_gain[self.hand_rows(h)] = gains[i]
        self._balance_gain = row_gain
        self._apply_row_gain(row_gain)
        return gains

    def _apply_row_gain(self, row_gain: np.ndarray) -> None:
        self._row_gain = row_gain
        k = row_gain[:, None] * self._base_stiffness
        k.setflags(write=False)
        self.field_stiffness = k

    @property
    def can_synchronise(self) -> bool:
        """Whether :meth:`synchronise_hands` applies (several hands, no held object)."""
        return self.held_object is None and len(self.hands) > 1

    def synchronise_hands(self, state: NetworkState, initial_errors: np.ndarray,
                          exponent: float) -> NetworkState:
        """Re-weight the hands' fields by their relative progress; returns ``state`` with its
        forces rescaled accordingly.

        An extension to the paper's network (which synchronises the branches through the
        shared TBG only): hand i's field is multiplied (on top of :meth:`balance_hands`) by
        ``(f_i / mean f)^exponent``, f_i = its error over its initial error, clipped to
        [0.25, 4]: a hand that lags gets a stronger pull, one that leads a weaker one, so
        both cover the same fraction of their way at the same relaxation time (and hence,
        under one TBG, at the same instant). The equilibrium is unchanged.
        """
        err = state.position_errors + 0.1 * state.rotation_errors
        live = initial_errors > 1e-6
        if live.sum() < 2:
            return state
        f = err[live] / initial_errors[live]
        gains = np.ones(len(self.hands))
        gains[live] = np.clip((f / max(float(f.mean()), 1e-12)) ** exponent, 0.25, 4.0)
        row_gain = self._balance_gain.copy()
        for i, h in enumerate(self.hands):
            row_gain[self._hand_rows[h]] *= gains[i]
        old = self._row_gain
        self._apply_row_gain(row_gain)
        return state._replace(force=state.force * (row_gain / old))

    def final_target(self, hand: str) -> np.ndarray:
        """Where ``hand`` must be at equilibrium (3,) [m]."""
        if self.held_object is not None and hand in self.held_object.grasp_offsets:
            return self.held_object.hand_targets()[hand]
        return self.targets[hand].target

    # ------------------------------------------------------------------ state
    @property
    def lower(self) -> np.ndarray:
        """Joint lower limits of the network joints (n,) [rad]."""
        return self.joint_limits.lower

    @property
    def upper(self) -> np.ndarray:
        """Joint upper limits of the network joints (n,) [rad]."""
        return self.joint_limits.upper

    def initial_state(self) -> np.ndarray:
        """z at the start: network joints of q_start (+ the object's start position)."""
        z = self._q_start[self.joint_index]
        if self.held_object is not None:
            z = np.concatenate([z, self.held_object.position])
        return z

    def q_full(self, z: np.ndarray) -> np.ndarray:
        """The full configuration (provider.nq,) with the network joints taken from z."""
        q = self._q_start.copy()
        q[self.joint_index] = z[: self.n]
        return q

    def hand_positions(self, z: np.ndarray) -> np.ndarray:
        """Hand positions (k, 3) [m] at z (forward kinematics only)."""
        return self.provider.positions(self.q_full(z), self.frames)

    # ------------------------------------------------------------------ evaluation
    def evaluate(self, z: np.ndarray, s: float = 0.0) -> NetworkState:
        """Fields, Jacobian and internal torques at state z and relaxation time s."""
        q = self._q_start.copy()
        q[self.joint_index] = z[: self.n]
        kin = self.provider.kinematics(q, self.frames)
        pos, rot = kin.positions, kin.rotations
        k = len(self.hands)
        if self._fast:
            g = kin.jacobians[:, :3, self.joint_index].reshape(3 * k, self.n)
            force = self.field_stiffness @ (self._y_target - pos.reshape(-1))
            rot_err = self._zero_rot
        else:
            jac = kin.jacobians[:, :, self.joint_index]  # (k, 6, n)
            g = np.zeros((self.m, self.nz))
            force = np.empty(self.m)
            rot_err = np.zeros(k)
            ho = cast(HeldObject, self.held_object)  # only read by grasp/object rows
            obj = z[self.n:]
            for kind, hand, r0 in self._rows:
                i = self.hands.index(hand) if hand else -1
                if kind == "position":
                    g[r0:r0 + 3, : self.n] = jac[i, :3]
                    force[r0:r0 + 3] = self.targets[hand].force(pos[i])
                elif kind == "orientation":
                    g[r0:r0 + 3, : self.n] = jac[i, 3:]
                    err = self.orientations[hand].error(rot[i])
                    rot_err[i] = float(np.linalg.norm(err))
                    force[r0:r0 + 3] = self.orientations[hand].stiffness * err
                elif kind == "grasp":  # task value y = x_i - x_o, target r_i
                    g[r0:r0 + 3, : self.n] = jac[i, :3]
                    g[r0:r0 + 3, self.n:] = -np.eye(3)
                    force[r0:r0 + 3] = ho.grasp_stiffness * (
                        ho.grasp_offsets[hand] - (pos[i] - obj)
                    )
                else:  # object goal: task value y = x_o
                    g[r0:r0 + 3, self.n:] = np.eye(3)
                    force[r0:r0 + 3] = ho.goal_stiffness * (ho.goal - obj)
            force = force * self._row_gain
        clearance = np.inf
        if self.obstacles:
            force = force.copy()
            for i in range(k):
                r0 = self._position_row(i)
                for ob in self.obstacles:
                    force[r0:r0 + 3] += ob.force(pos[i])
                    clearance = min(clearance, float(ob.clearance(pos[i])))
        torque, stiff, excess = self._internal(z, q, s)
        if self.obstacles and self.volumes:
            body_torque, body_stiff, body_clearance = self._volume_fields(q, kin, pos)
            torque = torque.copy()
            torque[: self.n] += body_torque
            stiff = stiff.copy()
            stiff[: self.n] += body_stiff
            clearance = min(clearance, body_clearance)
        d = self._final_targets - pos
        pos_err = np.sqrt((d * d).sum(axis=1))
        return NetworkState(
            force, g, torque, stiff, pos, rot, pos_err, rot_err, clearance, excess
        )

    def _volume_fields(self, q: np.ndarray, kin, pos: np.ndarray  # noqa: ANN001
                       ) -> tuple[np.ndarray, np.ndarray, float]:
        """Torques (n,) of the obstacle fields on the body volumes' spheres at ``q``, their
        diagonal joint stiffness (n,) and the smallest sphere clearance [m] (to the grown
        obstacles). From twice
        ``volume_null_distance`` of its target to that distance, a hand's volume torques fade
        into the null space of its position task
        (``T - J^T (J A J^T)^-1 J A T``): the arm still turns its fingers and forearm away, but
        no longer pushes the hand off the target (the equilibrium stays on it, as
        :meth:`ObstacleField.clear_of` keeps it for the hand frame)."""
        torque = np.zeros(self.n)
        stiffness = np.zeros(self.n)
        clearance = np.inf
        a = self.admittance[: self.n]
        for hand, vol in self.volumes.items():
            vk = self.provider.kinematics(q, vol.frames)
            pts = vol.positions(vk)
            forces = np.zeros_like(pts)
            k_normal = []
            for ob in self.obstacles:
                f, rho, k = ob.sphere_forces(pts, vol.radii)
                forces += f
                k_normal.append((f, k))
                clearance = min(clearance, float(rho.min()))
            if not np.any(forces):
                continue
            t = vol.torques(vk, forces)[self.joint_index]
            # the fields' stiffness along their normals, on the joints' diagonal (the implicit
            # step then slides along the obstacle instead of bouncing off it)
            jp = vol.jacobians(vk)[:, :, self.joint_index]  # (n, 3, joints)
            for f, k in k_normal:
                live = k > 0
                if np.any(live):
                    nrm = f[live] / np.maximum(np.linalg.norm(f[live], axis=1), 1e-12)[:, None]
                    proj = np.einsum("ni,nij->nj", nrm, jp[live])
                    stiffness += (k[live][:, None] * proj**2).sum(axis=0)
            i = self.hands.index(hand)
            err = float(np.linalg.norm(self._final_targets[i] - pos[i]))
            d = self.volume_null_distance
            w = min(max(err / d - 1.0, 0.0), 1.0) if d > 0 else 1.0
            if w < 1.0:
                jac = kin.jacobians[i, :3][:, self.joint_index]
                m = (jac * a) @ jac.T
                try:
                    null = t - jac.T @ np.linalg.solve(m, jac @ (a * t))
                except np.linalg.LinAlgError:
                    null = t
                t = w * t + (1.0 - w) * null
            torque += t
        return torque, stiffness, clearance

    def body_clearances(self, q_samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """At each configuration of ``q_samples`` (K, nq): the smallest distance [m] of every
        hand point and volume sphere to the obstacles' real surfaces (K,), and to their
        surfaces grown by the clearance to keep (K,) (< 0: not kept); inf without obstacles."""
        surface = np.full(len(q_samples), np.inf)
        kept = np.full(len(q_samples), np.inf)
        if not self.obstacles:
            return surface, kept
        for j, q in enumerate(q_samples):
            pts = [self.provider.positions(q, self.frames)]
            radii = [np.zeros(len(self.frames))]
            for vol in self.volumes.values():
                pts.append(vol.positions(self.provider.kinematics(q, vol.frames)))
                radii.append(vol.radii)
            p, r = np.vstack(pts), np.concatenate(radii)
            for ob in self.obstacles:
                d = float(np.min(ob.surface_distance(p) - r))
                surface[j] = min(surface[j], d)
                kept[j] = min(kept[j], d - ob.inflation)
        return surface, kept

    def _position_row(self, i: int) -> int:
        hand = self.hands[i]
        return next(r0 for kind, h, r0 in self._rows if h == hand and kind != "orientation")

    def _internal(
        self, z: np.ndarray, q: np.ndarray, s: float
    ) -> tuple[np.ndarray, np.ndarray, float]:
        """Internal torques (nz,), their diagonal stiffness (nz,), normalised torque excess."""
        qn = z[: self.n]
        t, d = self.joint_limits.torques_and_stiffness(qn)
        if self.posture is not None:
            w = self.posture.gain * np.exp(-s / self.posture.decay)
            t = t + w * (self.posture.q_ref - qn)
            d = d + w
        excess = 0.0
        if self.torque_field is not None:
            ts, ds, excess = self.torque_field.torques_and_stiffness(q)
            t = t + ts
            d = d + ds
        if self.nz > self.n:
            t = np.concatenate([t, np.zeros(self.nz - self.n)])
            d = np.concatenate([d, np.zeros(self.nz - self.n)])
        return t, d, excess
