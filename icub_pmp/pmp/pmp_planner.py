"""PmpPlanner: the planner facade. A ReachGoal and a start posture in, a ReachPlan out.

It assembles the PMP network of the task (Fig 5 for the arms and trunk, Fig 8 with a held
object, the fields of eqs 1 and 6, obstacles, Sect. 2.3's saturation), relaxes it to
equilibrium in the TBG's relaxation time (:mod:`relaxation`), and puts the result on the TBG's
clock (:mod:`tbg_timing`). Planning never executes anything: it is the mental simulation of
Sect. 4, whose residuals say whether (and by how much) the goal is out of reach.

Steps of :meth:`PmpPlanner.plan`:

1. relax from the start posture;
2. if the hands stay further from the targets than the success tolerance, recall from the
   posture memory the babbled postures whose hands came nearest and, nearest first, relax
   again from the start with a fading field toward each until one succeeds (at most
   ``posture_memory_attempts``); keep the best relaxation (:mod:`posture_memory`);
3. with target forces, continue the relaxation with the torque-limit field of Sect. 2.3
   (null-space settling);
4. sample the path at the TBG's times (Hermite, :mod:`tbg_timing`) and compute the residuals by
   forward kinematics; the predicted hand paths are computed when first asked for.
"""

from __future__ import annotations

import functools
import time
from typing import Mapping

import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS, RobotSpec
from icub_pmp.pmp.body_volume import BodyVolume
from icub_pmp.pmp.branch_network import BranchNetwork
from icub_pmp.pmp.force_field import ForceField
from icub_pmp.pmp.idle_hand_hold import hold_idle_hand
from icub_pmp.pmp.jacobian_provider import JacobianProvider
from icub_pmp.pmp.joint_limit_field import JointLimitField
from icub_pmp.pmp.orientation_field import OrientationField
from icub_pmp.pmp.pmp_config import PmpConfig
from icub_pmp.pmp.pmp_network import PmpNetwork, PostureField
from icub_pmp.pmp.posture_memory import PostureMemory
from icub_pmp.pmp.reach_goal import ReachGoal
from icub_pmp.pmp.reach_plan import ReachPlan
from icub_pmp.pmp.relaxation import Relaxation, RelaxationSettings, RelaxationTrace
from icub_pmp.pmp.tbg_timing import TbgTiming
from icub_pmp.pmp.time_base_generator import TimeBaseGenerator
from icub_pmp.pmp.torque_limit_field import TorqueLimitField

__all__ = ["PmpPlanner"]


class PmpPlanner:
    """Plans reaches with PMP networks on a body model.

    Args:
        config: gains, timing and tolerances (default: :class:`PmpConfig` defaults).
        provider: body model; default the iCub URDF through pinocchio.
        spec: robot facts (joint sets, hand frames, torque ratings); default robot.yaml.
    """

    def __init__(
        self,
        config: PmpConfig | None = None,
        provider: JacobianProvider | None = None,
        spec: RobotSpec | None = None,
    ):
        self.config = config or PmpConfig()
        self.spec = spec or RobotSpec.load()
        if provider is None:
            from icub_pmp.pmp.pinocchio_provider import PinocchioJacobianProvider

            provider = PinocchioJacobianProvider()
        self.provider = provider
        self._names = provider.joint_names
        self._index = {n: i for i, n in enumerate(self._names)}
        for j in self.spec.torso_joints + self.spec.left_arm_joints + self.spec.right_arm_joints:
            if j not in self._names:
                raise UnknownName("joint of the body model", j, self._names)
        self._range = provider.upper - provider.lower
        self._ref_range = float(np.mean(self._range))
        self._memories: dict[tuple, PostureMemory] = {}
        self._branch_cache: dict[tuple, BranchNetwork] = {}
        self._limit_cache: dict[tuple, JointLimitField] = {}
        self._volume_cache: dict[str, BodyVolume | None] = {}
        c = self.config
        self._field = ForceField(np.zeros(3), np.array(c.stiffness), c.curl, c.curl_axis)
        self._relax = Relaxation(self._settings(self.config.max_steps))
        self._relax_obstacles = Relaxation(self._settings(
            self.config.max_steps, max_displacement=self.config.obstacle_step or None))
        self._settle = Relaxation(self._settings(
            self.config.settle_max_steps, normalise=False, max_step=self.config.settle_max_step))

    def _settings(self, max_steps: int, normalise: bool = True,
                  max_step: float | None = None, max_displacement: float | None = None
                  ) -> RelaxationSettings:
        c = self.config
        return RelaxationSettings(
            initial_step=c.initial_step, step_growth=c.step_growth,
            max_step=c.max_step if max_step is None else max_step,
            max_displacement=c.max_displacement if max_displacement is None
            else max_displacement,
            max_steps=max_steps, stall_steps=c.stall_steps, tolerance=c.convergence_tolerance,
            rotation_tolerance=c.rotation_tolerance, boundary_fraction=c.boundary_fraction,
            normalise_rate=normalise, balance_hands=normalise and c.balance_hands,
            synchronise=c.synchronise_hands if normalise else 0.0,
        )

    # ------------------------------------------------------------------ inputs
    def start_configuration(self, q_start: np.ndarray | Mapping[str, float] | None) -> np.ndarray:
        """Full configuration (nq,) from an array, a {joint: angle} dict (missing joints at the
        rest posture) or None (the rest posture)."""
        rest = self.spec.posture("rest")
        base = np.array([rest.get(n, 0.0) for n in self._names])
        if q_start is None:
            return base
        if isinstance(q_start, Mapping):
            for n, v in q_start.items():
                if n in self._names:
                    base[self._names.index(n)] = float(v)
            q = base
        else:
            q = np.array(q_start, dtype=float).reshape(-1)
            if q.shape != (len(self._names),):
                raise InvalidInput(f"start: expected {len(self._names)} joint angles, got {q.size}")
        if not np.all(np.isfinite(q)):
            raise InvalidInput("start: contains NaN or infinite joint angles")
        return q

    def build_network(
        self, goal: ReachGoal, q_start: np.ndarray, posture: PostureField | None = None,
        body_volumes: bool = True,
    ) -> PmpNetwork:
        """The PMP network of ``goal`` on the body model (validates the goal); with
        ``body_volumes`` the obstacle fields also act on the arms' volumes
        (``obstacle_body_links``), else on the hand frames only."""
        c = self.config
        for h in goal.hands:
            if h not in HANDS:
                raise UnknownName("hand", h, HANDS)
        if goal.tau is not None and goal.tau > c.max_tau:
            raise InvalidInput(f"tau: {goal.tau} s exceeds the planner's max_tau {c.max_tau} s")
        for j in (tuple(goal.frozen_joints) + tuple(goal.joint_limits)
                  + tuple(goal.torque_limits) + tuple(goal.admittance_scales)):
            if j not in self._names:
                raise UnknownName("joint", j, self._names)
        branches = self._branches(goal)
        key = (branches.joint_names, tuple(sorted(goal.joint_limits.items())))
        limits = self._limit_cache.get(key)
        if limits is None:
            idx = [self._names.index(j) for j in branches.joint_names]
            lower = self.provider.lower[idx].copy()
            upper = self.provider.upper[idx].copy()
            for j, (lo, hi) in goal.joint_limits.items():
                if j in branches.joint_names:
                    k = branches.joint_names.index(j)
                    lower[k], upper[k] = lo, hi
            limits = JointLimitField(lower, upper, c.joint_limit_alpha)
            if len(self._limit_cache) > 64:
                self._limit_cache.clear()
            self._limit_cache[key] = limits
        lower, upper = limits.lower, limits.upper
        idx = [self._index[j] for j in branches.joint_names]
        qs = q_start[idx]
        tol = c.start_tolerance
        outside = (qs < lower - tol) | (qs > upper + tol)
        if np.any(outside):
            bad = [f"{branches.joint_names[i]}={qs[i]:.3f} not in [{lower[i]:.3f}, {upper[i]:.3f}]"
                   for i in np.flatnonzero(outside)]
            raise InvalidInput(f"start posture outside the joint limits: {', '.join(bad)}")
        targets = {h: self._field.retarget(p) for h, p in goal.targets.items()}
        orientations = {
            h: OrientationField(r, c.rotation_stiffness) for h, r in goal.orientations.items()
        }
        finals = [t.target for t in targets.values()]
        if goal.held_object is not None:
            finals += list(goal.held_object.hand_targets().values())
        # obstacle fields do not reach the targets (the equilibrium stays on them)
        obstacles = [ob.clear_of(finals) for ob in goal.obstacles]
        volumes = self._volumes(goal.hands) if obstacles and body_volumes else {}
        return PmpNetwork(
            self.provider, branches, {h: self.spec.hand_frame(h) for h in goal.hands}, q_start,
            targets, orientations, obstacles, limits, goal.held_object, posture,
            volumes=volumes, volume_null_distance=c.obstacle_body_null_distance,
        )

    def _volumes(self, hands) -> dict[str, BodyVolume]:
        """hand -> the spheres covering its ``obstacle_body_links`` (built once); none when
        the body model lacks those link frames (the hand frame alone is kept clear then)."""
        links = tuple(lk for lk in self.config.obstacle_body_links if lk)
        out = {}
        for h in hands:
            if h not in self._volume_cache:
                vol = None
                prefix = self.spec.arm_joints(h)[0][:2]
                if links and all(prefix + lk in self.provider.frame_names() for lk in links):
                    vol = BodyVolume.from_urdf(self.provider, h, links, self.spec)
                self._volume_cache[h] = vol
            if self._volume_cache[h] is not None:
                out[h] = self._volume_cache[h]
        return out

    def _branches(self, goal: ReachGoal) -> BranchNetwork:
        """The branching network of the goal's hands, trunk and admittance modulation."""
        key = (goal.hands, goal.use_torso, goal.trunk_admittance_scale, goal.frozen_joints,
               tuple(sorted(goal.admittance_scales.items())))
        branches = self._branch_cache.get(key)
        if branches is not None:
            return branches
        c = self.config
        trunk = self.spec.torso_joints if goal.use_torso else ()
        arms = {h: self.spec.arm_joints(h) for h in goal.hands}
        trunk_a = np.array(c.trunk_admittance)[: len(trunk)] * goal.trunk_admittance_scale
        arm_a = {h: np.array(c.arm_admittance) for h in goal.hands}
        if c.range_normalised_admittance:  # eq 6's normalised joint angles, equal admittance
            trunk_a = trunk_a * self._range_factor(trunk)
            arm_a = {h: a * self._range_factor(arms[h]) for h, a in arm_a.items()}
        branches = BranchNetwork(trunk, arms, trunk_a, arm_a)
        frozen = set(goal.frozen_joints)
        if frozen or goal.admittance_scales:
            a = branches.admittance.copy()
            for i, j in enumerate(branches.joint_names):
                a[i] *= goal.admittance_scales.get(j, 1.0)
                if j in frozen:
                    a[i] = 0.0
            branches = branches.with_admittance(
                a[: len(trunk)], {h: a[branches.branch_slices[h]] for h in goal.hands}
            )
        if len(self._branch_cache) > 64:
            self._branch_cache.clear()
        self._branch_cache[key] = branches
        return branches

    def _range_factor(self, joints) -> np.ndarray:
        idx = [self._names.index(j) for j in joints]
        return (self._range[idx] / self._ref_range) ** 2

    # ------------------------------------------------------------------ planning
    def plan(
        self, goal: ReachGoal, q_start: np.ndarray | Mapping[str, float] | None = None
    ) -> ReachPlan:
        """Plan ``goal`` from ``q_start`` (see :meth:`start_configuration`)."""
        t0 = time.perf_counter()
        q0 = self.start_configuration(q_start)
        net = self.build_network(goal, q0)
        trace, attempts, used_memory = self._relax_recalling(goal, q0, net, True)
        body_net = None
        if net.volumes and not self._reached(trace):
            # decision 0063: the arms' volumes kept clear is best effort; when the plan with
            # them does not reach, the hand frames alone keep the clearance (the contract of
            # the request, and the planner's before the volumes) and the answer says how close
            # the arm's volume comes
            hand_net = self.build_network(goal, q0, body_volumes=False)
            trace2, more, memory2 = self._relax_recalling(goal, q0, hand_net, False)
            attempts += more
            if self._reached(trace2):
                body_net, net, trace, used_memory = net, hand_net, trace2, memory2
        null_space = np.zeros(trace.steps, dtype=bool)
        torque_field = None
        if goal.target_forces or goal.torque_limits:
            trace, null_space, torque_field = self._settle_torques(goal, net, trace)
        return self._make_plan(goal, net, trace, null_space, torque_field, attempts,
                               used_memory, t0, body_net)

    def _relax_recalling(self, goal: ReachGoal, q0: np.ndarray, net: PmpNetwork,
                         body_volumes: bool) -> tuple[RelaxationTrace, int, bool]:
        """Relax ``net``; when it does not reach, again from recalled postures (the posture
        memory): (the best trace, relaxations run, whether a recall gave it)."""
        c = self.config
        relax = self._relax_obstacles if goal.obstacles else self._relax
        trace = relax.run(net)
        attempts, used_memory = 1, False
        if not self._reached(trace) and c.posture_memory_size > 0:
            recalls = self._memory(net).recall(
                np.array([net.final_target(h) for h in net.hands]), c.posture_memory_attempts
            )
            for recall in recalls:
                field = PostureField(recall.q, c.posture_field_gain, c.posture_field_decay)
                trace2 = relax.run(self.build_network(goal, q0, posture=field,
                                                      body_volumes=body_volumes))
                attempts += 1
                if self._score(trace2) < self._score(trace):
                    trace, used_memory = trace2, True
                if self._reached(trace):
                    break
        return trace, attempts, used_memory

    def _reached(self, trace: RelaxationTrace) -> bool:
        c = self.config
        return bool(
            np.all(trace.position_errors[-1] <= c.success_tolerance)
            and np.all(trace.rotation_errors[-1] <= c.rotation_success_tolerance)
        )

    def _score(self, trace: RelaxationTrace) -> float:
        return float(np.max(trace.position_errors[-1], initial=0.0)
                     + 0.1 * np.max(trace.rotation_errors[-1], initial=0.0))

    def _memory(self, net: PmpNetwork) -> PostureMemory:
        """The posture memory of this network's joints (built once, then cached)."""
        fixed = sorted(
            {j for f in net.frames for j in self.provider.ancestors(f)}
            - set(net.branches.joint_names)
        )
        q = net.q_full(net.initial_state())
        lower, upper = net.lower.copy(), net.upper.copy()
        frozen = net.branches.admittance == 0  # frozen joints stay where they start
        lower[frozen] = upper[frozen] = q[net.joint_index][frozen]
        key = (
            net.branches.joint_names, net.frames,
            tuple(np.round(lower, 6)), tuple(np.round(upper, 6)),
            tuple(round(float(q[self._names.index(j)]), 4) for j in fixed),
        )
        mem = self._memories.get(key)
        if mem is None:
            if len(self._memories) >= 16:
                self._memories.pop(next(iter(self._memories)))
            mem = self._memories[key] = PostureMemory(
                self.provider, net.joint_index, net.frames, q, lower, upper,
                self.config.posture_memory_size, self.config.posture_memory_seed,
            )
        return mem

    def warm_up(self, hands=HANDS, use_torso: bool = True, q_start=None) -> None:
        """Build the posture memory of a network ahead of the first plan that needs it."""
        if self.config.posture_memory_size <= 0:
            return
        q0 = self.start_configuration(q_start)
        goal = ReachGoal(targets={h: np.zeros(3) for h in hands}, use_torso=use_torso)
        self._memory(self.build_network(goal, q0))

    def _settle_torques(self, goal: ReachGoal, net: PmpNetwork, trace: RelaxationTrace):
        """Sect. 2.3: from the equilibrium, relax with the saturation field (null space)."""
        c = self.config
        hands = tuple(h for h in net.hands if h in goal.target_forces)
        limits = np.array([goal.torque_limits.get(j) or self.spec.torque_limit(j)
                           for j in self._names])
        field = TorqueLimitField(
            self.provider, [self.spec.hand_frame(h) for h in hands],
            np.array([goal.target_forces[h] for h in hands]).reshape(len(hands), 3), limits,
            net.joint_index,
            gravity=c.torque_gravity, margin=c.torque_limit_margin,
        )
        net2 = PmpNetwork(
            self.provider, net.branches, dict(zip(net.hands, net.frames)), net.q_full(
                trace.z[-1]), net.targets, net.orientations, net.obstacles, net.joint_limits,
            net.held_object, None, field, volumes=net.volumes,
            volume_null_distance=net.volume_null_distance,
        )
        scale = trace.rate_scale
        net2.admittance = net2.admittance * scale  # same time scale as the reach
        settle = self._settle.run(net2, trace.z[-1])
        s_off = trace.s[-1]
        merged = RelaxationTrace(
            s=np.concatenate([trace.s, s_off + settle.s[1:]]),
            z=np.concatenate([trace.z, settle.z[1:]]),
            hand_positions=np.concatenate([trace.hand_positions, settle.hand_positions[1:]]),
            hand_rotations=np.concatenate([trace.hand_rotations, settle.hand_rotations[1:]]),
            position_errors=np.concatenate([trace.position_errors, settle.position_errors[1:]]),
            rotation_errors=np.concatenate([trace.rotation_errors, settle.rotation_errors[1:]]),
            converged=trace.converged and settle.converged,
            stop_reason=settle.stop_reason,
            rate_scale=scale,
        )
        null_space = np.r_[np.zeros(trace.steps, dtype=bool), np.ones(settle.steps, dtype=bool)]
        return merged, null_space, field

    # ------------------------------------------------------------------ result
    def _make_plan(self, goal, net, trace, null_space, torque_field, attempts, used_memory, t0,
                   body_net: PmpNetwork | None = None):
        """The sampled plan of ``trace``; ``body_net``: the network with the arms' volumes
        when ``net`` (hand frames only) replaced it (their clearance is then reported)."""
        c = self.config
        tau = goal.tau if goal.tau is not None else c.tau
        tbg = TimeBaseGenerator(tau)
        timing = TbgTiming(tbg, c.time_parametrisation, c.rotation_length_scale,
                           c.progress_joint_floor)
        z_nodes, s_nodes = trace.z, trace.s
        pos_nodes, rot_nodes = trace.hand_positions, trace.hand_rotations
        if len(s_nodes) < 2:  # already at the target: a still trajectory
            z_nodes = np.repeat(z_nodes, 2, axis=0)
            s_nodes = np.array([0.0, 1.0])
            pos_nodes = np.repeat(pos_nodes, 2, axis=0)
            rot_nodes = np.repeat(rot_nodes, 2, axis=0)
            null_space = np.zeros(1, dtype=bool)
        progress = timing.progress(
            pos_nodes, rot_nodes, z_nodes[:, : net.n], null_space, bool(goal.orientations)
        )
        times = tbg.sample_times(c.sample_period)
        k, phi = timing.locate(times, s_nodes, progress)
        axis = s_nodes if timing.mode == "gamma" else progress
        z = timing.interpolate_smooth(z_nodes, axis, k, phi)
        # no overshoot beyond what the relaxation visited (its nodes are strictly inside the
        # joint limits, so the sampled trajectory is too)
        z = np.minimum(np.maximum(z, z_nodes.min(axis=0)), z_nodes.max(axis=0))
        z[0] = z_nodes[0]
        z[-1] = z_nodes[-1]
        joints = z[:, : net.n]
        q_full = np.repeat(net.q_full(z_nodes[0])[None, :], len(times), axis=0)
        q_full[:, net.joint_index] = joints
        names = net.branches.joint_names
        idle = self._idle_arm_joints(goal, net, joints)
        if idle:  # decision 0056: the idle hands stay where they were
            dt = float(np.min(np.diff(times))) if len(times) > 1 else c.sample_period
            for frame, arm in idle:
                # at most half the joints' velocity and acceleration limits
                vmax = np.array([self.spec.velocity_limit(self._names[i]) for i in arm])
                amax = np.array([self.spec.acceleration_limit(self._names[i]) for i in arm])
                q_full[:, arm] = hold_idle_hand(
                    self.provider, frame, arm, q_full, c.idle_hand_margin,
                    max_step=0.5 * vmax * dt, max_step_change=0.5 * amax * dt * dt)
            extra = [i for _, arm in idle for i in arm]
            names = names + tuple(self._names[i] for i in extra)
            joints = np.hstack([joints, q_full[:, extra]])
        vel = np.zeros_like(joints)  # central differences, zero at both ends
        vel[1:-1] = (joints[2:] - joints[:-2]) / (times[2:] - times[:-2])[:, None]
        q_final = q_full[-1].copy()
        final = self.provider.kinematics(q_final, net.frames)
        residuals, rot_res = {}, {}
        for i, h in enumerate(net.hands):
            residuals[h] = float(np.linalg.norm(final.positions[i] - net.final_target(h)))
            rot_res[h] = (
                float(np.linalg.norm(net.orientations[h].error(final.rotations[i])))
                if h in net.orientations else 0.0
            )
        ok = all(r <= c.success_tolerance for r in residuals.values()) and all(
            r <= c.rotation_success_tolerance for r in rot_res.values()
        )
        torque_ratio, final_torques, torque_limits = None, None, None
        if torque_field is not None:
            torque_ratio = torque_field.violation(q_final)
            ok = ok and torque_ratio <= 1.0
            final_torques = torque_field.required_torques(q_final)[net.joint_index]
            torque_limits = torque_field.limits[net.joint_index].copy()
        hand_paths = functools.lru_cache(maxsize=1)(
            lambda: self._hand_paths(net.hands, net.frames, q_full))
        clearance, kept = None, True
        if net.obstacles:  # judged on the sampled plan, not only the relaxation's nodes, on
            # the hands and their body volumes; a body that starts within the clearance must
            # not come closer than it started
            surface, grown = net.body_clearances(q_full)
            clearance = float(surface.min())
            kept = float(grown.min()) >= min(0.0, float(grown[0]))
            ok = ok and kept
        message = self._message(net.hands, residuals, rot_res, ok, torque_ratio, used_memory,
                                not kept, bool(net.obstacles))
        if clearance is not None:
            message += f"; obstacle clearance {clearance * 1e3:.1f} mm"
        if body_net is not None and clearance is not None:
            body = float(body_net.body_clearances(q_full)[0].min())
            message += (f" (hand frames only: with the arm's volume kept clear the plan did not "
                        f"reach; the arm's volume comes within {body * 1e3:.1f} mm)")
        plan = ReachPlan(
            hands=net.hands,
            joint_names=names,
            t=times,
            positions=joints,
            velocities=vel,
            residuals=residuals,
            rotation_residuals=rot_res,
            success=ok,
            message=message + f" ({(time.perf_counter() - t0) * 1e3:.1f} ms)",
            tau=tau,
            q_start=q_full[0].copy(),
            q_final=q_final,
            trace=trace,
            object_path=z[:, net.n:].copy() if net.held_object is not None else None,
            torque_ratio=torque_ratio,
            attempts=attempts,
            used_memory=used_memory,
            path_function=hand_paths,
            obstacle_clearance=clearance,
            final_torques=final_torques,
            torque_limits=torque_limits,
            hand_frames_only=body_net is not None,
        )
        return plan

    def _idle_arm_joints(self, goal: ReachGoal, net: PmpNetwork, joints: np.ndarray
                         ) -> list[tuple[str, list[int]]]:
        """(hand frame, arm joint indices in the provider's q) of every hand that takes no
        part in ``goal`` while the trunk moves (``hold_idle_hands``); frozen joints and joints
        the body model lacks are left out."""
        trunk = net.branches.trunk_slice
        if (not self.config.hold_idle_hands or not net.branches.trunk_joints
                or np.ptp(joints[:, trunk], axis=0).max(initial=0.0) <= 0.0):
            return []
        frames = set(self.provider.frame_names())
        out = []
        for h in HANDS:
            frame = self.spec.hand_frame(h)
            if h in net.hands or frame not in frames:
                continue
            arm = [self._index[j] for j in self.spec.arm_joints(h)
                   if j in self._index and j not in goal.frozen_joints]
            if arm:
                out.append((frame, arm))
        return out

    def _hand_paths(self, hands, frames, q_full: np.ndarray) -> dict[str, np.ndarray]:
        paths = np.array([self.provider.positions(q, frames) for q in q_full])
        return {h: paths[:, i, :].copy() for i, h in enumerate(hands)}

    def _message(self, hands, residuals, rot_res, ok, torque_ratio, used_memory,
                 blocked=False, obstacles=False) -> str:
        c = self.config
        parts = [f"{h} {residuals[h] * 1e3:.2f} mm" for h in hands]
        text = "residuals " + ", ".join(parts)
        if any(rot_res.values()):
            text += "; orientation " + ", ".join(f"{h} {rot_res[h]:.4f} rad" for h in hands)
        if ok:
            head = "planned (mental simulation reaches the target)"
        else:
            short = [h for h in hands if residuals[h] > c.success_tolerance]
            if short:
                worst = max(short, key=lambda h: residuals[h])
                head = f"{worst} hand ends {residuals[worst] * 1e3:.1f} mm from its target"
                head = (f"out of reach or blocked by the obstacles (no path found that keeps "
                        f"the clearance): {head}" if obstacles else
                        f"out of reach: {head} (a tool that long would be needed)")
            elif blocked:
                head = ("blocked: no path found that keeps the asked clearance from the "
                        "obstacles")
            elif torque_ratio is not None and torque_ratio > 1.0:
                head = f"torque limits exceeded by a factor {torque_ratio:.2f} after settling"
            else:
                head = "orientation not reached"
        if torque_ratio is not None:
            text += f"; max torque/limit {torque_ratio:.2f}"
        if used_memory:
            text += "; via posture memory"
        return f"{head}: {text}"
