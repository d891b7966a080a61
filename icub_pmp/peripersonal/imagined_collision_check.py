"""ImaginedCollisionCheck: mental simulation of two arm reaches, their collisions and schedule.

Bhat and Mohan 2018, "Coupled interaction between internal models of body and space": each
robot imagines its reach with its PMP body model; "the 3D locations of the two distal joints
(nearest to the end-effector) of both the robots are computed at multiple points along the
two anticipated motion trajectories ... If the calculated distance between the joints ... is
below a threshold value any time during simulated motion, a possible collision is
detected". Without a collision both motions run in parallel; with one they are serialised:
"alternately allowing one of the robots to complete its movement (a sub-task) while keeping
the other robot away from the shared workspace area at an initialized location".

On the iCub the two arms are the two agents (the trunk, which both would move, stays still:
``use_torso`` false in every imagined reach). Two iCub arms can also hit each other with the
forearm or upper arm, which two separate robots could not, so besides the paper's distal
test each arm's link hulls (:class:`ArmBodyModel`: the convex hulls the physics collides,
found through bounding capsules first) are compared with the other arm's.

Steps of :meth:`ImaginedCollisionCheck.plan_pair`:

1. imagine each arm's reach from the start posture (:class:`~icub_pmp.pmp.PmpPlanner` on the
   body model: the URDF, or the body networks learned from babbling, the paper's "mental
   simulation" on the learned internal model, :meth:`ImaginedCollisionCheck.learned`);
2. sample both motions on a common clock every ``check_period`` (an arm that finished holds
   its final posture) and compare them (:meth:`compare`): distal test and capsule test;
3. clear: a parallel schedule; else serial: the first arm reaches while the second holds its
   posture, or, when that posture is in the way, first moves to the safe posture
   (``safe_posture`` of ``config/robot.yaml``); then the second reaches (re-imagined from
   the safe posture when it went there), after the first moved to the safe posture if its
   final posture is in the way. Every step is checked the same way.
"""

from __future__ import annotations

import time
from typing import Mapping, Sequence

import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS, RobotSpec
from icub_pmp.peripersonal.arm_body_model import ArmBodyModel
from icub_pmp.peripersonal.collision_check_config import CollisionCheckConfig
from icub_pmp.peripersonal.collision_verdict import CollisionVerdict
from icub_pmp.peripersonal.growing_neural_gas import as_points
from icub_pmp.peripersonal.pair_plan import PairPlan, PairSchedule, ScheduleStep
from icub_pmp.peripersonal.segment_distance import segment_distance
from icub_pmp.pmp.pmp_planner import PmpPlanner
from icub_pmp.pmp.reach_goal import ReachGoal
from icub_pmp.pmp.reach_plan import ReachPlan
from icub_pmp.pmp.time_base_generator import TimeBaseGenerator

__all__ = ["ImaginedCollisionCheck", "ArmMotion"]

#: an arm's motion: (times (N,) [s], joint names (n,), positions (N, n) [rad])
ArmMotion = tuple[np.ndarray, Sequence[str], np.ndarray]


def _other(arm: str) -> str:
    return "right" if arm == "left" else "left"


class ImaginedCollisionCheck:
    """Imagined reaches of both arms, their collision verdict and schedule (module doc).

    Args:
        config: thresholds, timing, safe posture (:class:`CollisionCheckConfig`).
        planner: the PMP planner on the body model (default: URDF through pinocchio).
        body: the arms' distal frames and capsules (default: fitted to the URDF meshes).
            Its provider may be another body model than the planner's (a learned body model
            imagines the joint motions, whose link geometry it does not know): the imagined
            joints are then posed on the body's provider, its other joints at rest.
        frozen_joints: joints that no imagined reach moves (default none).
    """

    def __init__(self, config: CollisionCheckConfig | None = None,
                 planner: PmpPlanner | None = None, body: ArmBodyModel | None = None,
                 frozen_joints: Sequence[str] = ()):
        self.config = config or CollisionCheckConfig()
        #: joints every imagined reach keeps still (e.g. the wrists of a pick-and-place)
        self.frozen_joints = tuple(frozen_joints)
        self.planner = planner or PmpPlanner()
        self.spec: RobotSpec = self.planner.spec
        self.provider = self.planner.provider
        c = self.config
        self.body = body or ArmBodyModel.from_urdf(self.provider, self.spec, c.capsule_links,
                                                   c.distal_frames, c.hull_spacing)
        self._names = self.provider.joint_names
        body_names = list(self.body.provider.joint_names)
        # the planner's joints among the body model's (identity when they are the same model)
        self._to_body: np.ndarray | None = None
        if list(self._names) != body_names:
            missing = [n for n in self._names if n not in body_names]
            if missing:
                raise InvalidInput(f"body: the body model has no joints {missing} of the "
                                   "planner's configuration")
            rest = self.spec.posture("rest")
            self._body_rest = np.array([rest.get(n, 0.0) for n in body_names])
            self._to_body = np.array([body_names.index(n) for n in self._names])
        self._arm_idx = {a: np.array([self._names.index(j) for j in self.spec.arm_joints(a)])
                         for a in HANDS}
        park = self.spec.posture(c.safe_posture)  # raises UnknownName for a bad posture
        self._park = {a: np.array([park.get(j, 0.0) for j in self.spec.arm_joints(a)])
                      for a in HANDS}

    # ------------------------------------------------------------------ inputs
    def _targets(self, targets: Mapping[str, object]) -> dict[str, np.ndarray]:
        if not isinstance(targets, Mapping):
            raise InvalidInput(f"targets: expected {{arm: (3,) point}}, got {targets!r}")
        for a in targets:
            if a not in HANDS:
                raise UnknownName("arm", a, HANDS)
        missing = [a for a in HANDS if a not in targets]
        if missing:
            raise InvalidInput(f"targets: a target for each arm is needed, missing {missing}")
        return {a: as_points(targets[a], f"targets[{a!r}]")[0] for a in HANDS}

    def safe_posture(self, arm: str) -> np.ndarray:
        """Joint angles (7,) [rad] of ``arm`` at the safe posture."""
        if arm not in HANDS:
            raise UnknownName("arm", arm, HANDS)
        return self._park[arm].copy()

    # ------------------------------------------------------------------ imagination
    def imagine(self, arm: str, target: object, q_start: np.ndarray | Mapping[str, float] | None
                = None) -> ReachPlan:
        """Imagined PMP reach of ``arm`` to ``target`` (3,) [m, root_link] from ``q_start``
        (full configuration or {joint: angle}; default the rest posture), trunk still."""
        if arm not in HANDS:
            raise UnknownName("arm", arm, HANDS)
        p = as_points(target, "target")[0]
        goal = ReachGoal(targets={arm: p}, use_torso=False, tau=self.config.reach_tau,
                         frozen_joints=self.frozen_joints)
        return self.planner.plan(goal, q_start)

    def park_motion(self, arm: str, q_from: np.ndarray) -> ArmMotion:
        """Minimum-jerk joint motion (the TBG profile) of ``arm`` from its joints in the full
        configuration ``q_from`` to the safe posture in ``park_duration``."""
        c = self.config
        tbg = TimeBaseGenerator(c.park_duration)
        t = tbg.sample_times(self.planner.config.sample_period)
        q0 = np.asarray(q_from, dtype=float)[self._arm_idx[arm]]
        d = self._park[arm] - q0
        pos = q0 + tbg.xi(t)[:, None] * d
        return t, self.spec.arm_joints(arm), pos

    # ------------------------------------------------------------------ the check
    def compare(self, q_base: np.ndarray, motions: Mapping[str, ArmMotion]) -> CollisionVerdict:
        """Compare the two arms while they move as ``motions`` {arm: (t, names, positions)}
        from the same instant (an arm without a motion, or after its motion ended, holds
        its joints of ``q_base`` (nq,) [rad] resp. its last sample)."""
        c = self.config
        q_base = np.asarray(q_base, dtype=float)
        if q_base.shape != (len(self._names),) or not np.all(np.isfinite(q_base)):
            raise InvalidInput(f"q_base: expected finite ({len(self._names)},) [rad], got "
                               f"{q_base.shape}")
        t_end = max([float(m[0][-1]) for m in motions.values()], default=0.0)
        grid = np.unique(np.r_[np.arange(0.0, t_end, c.check_period), t_end])
        Q = np.repeat(q_base[None], len(grid), axis=0)
        for arm, (t, names, pos) in motions.items():
            if arm not in HANDS:
                raise UnknownName("arm", arm, HANDS)
            t = np.asarray(t, dtype=float)
            pos = np.asarray(pos, dtype=float)
            for j, name in enumerate(names):
                Q[:, self._names.index(name)] = np.interp(grid, t, pos[:, j])
        b = self.body
        Q = self._on_body(Q)
        dl, dr = b.distal_points("left", Q), b.distal_points("right", Q)
        dd = np.linalg.norm(dl[:, :, None, :] - dr[:, None, :, :], axis=3)  # (K, D, D)
        dmin_k = dd.reshape(len(grid), -1).min(axis=1)
        k_d = int(np.argmin(dmin_k))
        min_distal = float(dmin_k[k_d])
        distal_hit = bool(min_distal < c.distal_threshold)
        if c.body_check:
            min_clear, (k_c, i, j) = self._hull_clearance(Q)
            body_hit = bool(min_clear < c.margin)
            links = (b.link_names("left")[i], b.link_names("right")[j])
            t_close = float(grid[k_c])
        else:
            min_clear, body_hit = float("inf"), False
            i, j = np.unravel_index(int(np.argmin(dd[k_d])), dd.shape[1:])
            links = (b.distal_frames["left"][i], b.distal_frames["right"][j])
            t_close = float(grid[k_d])
        return CollisionVerdict(distal_hit or body_hit, distal_hit, body_hit, min_distal,
                                min_clear, t_close, links)

    def _on_body(self, Q: np.ndarray) -> np.ndarray:
        """Configurations (K, nq) of the planner as the body model's (K, nq_body)."""
        if self._to_body is None:
            return Q
        out = np.repeat(self._body_rest[None], len(Q), axis=0)
        out[:, self._to_body] = Q
        return out

    @classmethod
    def learned(cls, models: Mapping[str, str], config: CollisionCheckConfig | None = None,
                frozen_joints: Sequence[str] = ()) -> "ImaginedCollisionCheck":
        """The check with the reaches imagined on body networks learned from babbling
        (:class:`~icub_pmp.body_schema.LearnedJacobianProvider`; ``models`` {arm: .npz file},
        one per arm: both arms are imagined) and the arms' link geometry posed on the URDF
        (a hand-position network knows no link shapes)."""
        from icub_pmp.body_schema.learned_jacobian_provider import LearnedJacobianProvider
        from icub_pmp.pmp.pinocchio_provider import PinocchioJacobianProvider

        missing = [a for a in HANDS if not models.get(a)]
        if missing:
            raise InvalidInput(f"models: a learned body model per arm is needed, missing "
                               f"{missing}")
        c = config or CollisionCheckConfig()
        urdf = PinocchioJacobianProvider()
        planner = PmpPlanner(provider=LearnedJacobianProvider.from_files(
            {a: models[a] for a in HANDS}))
        body = ArmBodyModel.from_urdf(urdf, urdf.icub.spec, c.capsule_links, c.distal_frames,
                                      c.hull_spacing)
        return cls(c, planner, body, frozen_joints)

    def _hull_clearance(self, Q: np.ndarray) -> tuple[float, tuple[int, int, int]]:
        """Smallest distance [m] between a left and a right link hull over the samples Q
        (K, nq), and where: (sample, left link, right link).

        Broad phase: the capsules (they contain the hulls, so a capsule gap is a lower bound
        of the hull distance) of every link pair at every sample. Narrow phase: the hulls of
        the pairs whose capsule gap is below ``max(margin, 0) + broad_phase``, smallest gap
        first, until no remaining gap can beat the best distance found (branch and bound);
        pairs never compared count with their capsule gap (a lower bound).
        """
        b, c = self.body, self.config
        Rl, pl = b.poses("left", Q)
        Rr, pr = b.poses("right", Q)
        cl = b.capsules_at("left", Q, (Rl, pl))
        cr = b.capsules_at("right", Q, (Rr, pr))
        gap = segment_distance(cl[:, :, None, 0], cl[:, :, None, 1], cr[:, None, :, 0],
                               cr[:, None, :, 1])
        gap -= b.radii("left")[None, :, None] + b.radii("right")[None, None, :]
        ol, orr = b.capsule_links("left"), b.capsule_links("right")
        link_gap = np.full((len(Q), len(b.hulls["left"]), len(b.hulls["right"])), np.inf)
        for ci, li in enumerate(ol):
            for cj, lj in enumerate(orr):
                np.minimum(link_gap[:, li, lj], gap[:, ci, cj], out=link_gap[:, li, lj])
        bound = max(c.margin, 0.0) + c.broad_phase
        far = link_gap >= bound
        if far.all():
            k = np.unravel_index(int(np.argmin(link_gap)), link_gap.shape)
            return float(link_gap[k]), tuple(int(x) for x in k)
        best, where = np.inf, (0, 0, 0)
        if far.any():
            masked = np.where(far, link_gap, np.inf)
            where = tuple(int(x) for x in np.unravel_index(int(np.argmin(masked)), masked.shape))
            best = float(masked[where])
        cand = np.argwhere(~far)
        cand = cand[np.argsort(link_gap[~far], kind="stable")]
        hl, hr = b.hulls["left"], b.hulls["right"]
        resolution = 0.5 * min(h.spacing for h in hl + hr)
        for k, i, j in cand:
            if link_gap[k, i, j] >= best or best <= resolution:
                break
            d = hl[i].distance(Rl[k, i], pl[k, i], hr[j], Rr[k, j], pr[k, j], best)
            if d < best:
                best, where = d, (int(k), int(i), int(j))
        return best, where

    @staticmethod
    def _motion(plan: ReachPlan) -> ArmMotion:
        return plan.t, plan.joint_names, plan.positions

    def _step(self, arm: str, action: str, start: float, motion: ArmMotion,
              verdict: CollisionVerdict, velocities: np.ndarray | None = None) -> ScheduleStep:
        """A schedule step; velocities [rad/s] by finite differences unless given."""
        t, names, pos = motion
        pos = np.asarray(pos, dtype=float)
        if velocities is None:
            velocities = np.gradient(pos, t, axis=0) if len(t) > 1 else np.zeros_like(pos)
            velocities[0] = velocities[-1] = 0.0
        return ScheduleStep(arm, action, float(start), tuple(names), np.asarray(t, float), pos,
                            np.asarray(velocities, dtype=float), verdict)

    # ------------------------------------------------------------------ pairs
    def plan_pair(self, targets: Mapping[str, object],
                  q_start: np.ndarray | Mapping[str, float] | None = None,
                  first: str | None = None) -> PairPlan:
        """Imagine both reaches to ``targets`` {'left': (3,), 'right': (3,)} [m, root_link]
        from ``q_start`` and schedule them (module doc). ``first``: the arm that goes first
        when they must be serialised (default: left)."""
        t0 = time.perf_counter()
        goals = self._targets(targets)
        first = first or "left"
        if first not in HANDS:
            raise UnknownName("arm", first, HANDS)
        q0 = self.planner.start_configuration(q_start)
        plans = {a: self.imagine(a, goals[a], q0) for a in HANDS}
        verdict = self.compare(q0, {a: self._motion(p) for a, p in plans.items()})
        if not verdict.collides:
            steps = tuple(self._step(a, "reach", 0.0, self._motion(plans[a]), verdict,
                                     plans[a].velocities) for a in HANDS)
            schedule = PairSchedule("parallel", steps, max(s.end for s in steps), True)
        else:
            schedule = self._serial(first, goals, plans, q0)
        return PairPlan(plans, verdict, schedule, time.perf_counter() - t0)

    def _make_room(self, mover: str, motion: ArmMotion, q: np.ndarray, t: float,
                   steps: list[ScheduleStep]) -> tuple[CollisionVerdict, float]:
        """The verdict of ``mover``'s motion against the other arm held at ``q``. When they
        collide, the other arm first moves to the safe posture: a park step is appended at
        ``t``, ``q`` is updated and the motion is checked again. Returns (verdict, the time
        the motion can start)."""
        v = self.compare(q, {mover: motion})
        if v.collides:
            other = _other(mover)
            park = self.park_motion(other, q)
            steps.append(self._step(other, "park", t, park, self.compare(q, {other: park})))
            t = steps[-1].end
            q[self._arm_idx[other]] = park[2][-1]
            v = self.compare(q, {mover: motion})
        return v, t

    def _serial(self, first: str, goals: dict[str, np.ndarray], plans: dict[str, ReachPlan],
                q0: np.ndarray) -> PairSchedule:
        """One arm after the other, the waiting one at the safe posture when in the way."""
        second = _other(first)
        steps: list[ScheduleStep] = []
        q = q0.copy()
        # 1. the first arm's reach against the second arm where it is (or parked)
        plan1 = plans[first]
        m1 = self._motion(plan1)
        v1, t = self._make_room(first, m1, q, 0.0, steps)
        steps.append(self._step(first, "reach", t, m1, v1, plan1.velocities))
        t = steps[-1].end
        q[self._arm_idx[first]] = m1[2][-1]
        # 2. the second arm's reach (re-imagined if it was parked) against the first arm's
        # final posture (or the first arm parked)
        plan2 = plans[second]
        if steps[0].action == "park":
            plan2 = self.imagine(second, goals[second], q)
        m2 = self._motion(plan2)
        v2, t = self._make_room(second, m2, q, t, steps)
        steps.append(self._step(second, "reach", t, m2, v2, plan2.velocities))
        safe = not any(s.clearance.collides for s in steps)
        return PairSchedule("serial", tuple(steps), steps[-1].end, safe)
