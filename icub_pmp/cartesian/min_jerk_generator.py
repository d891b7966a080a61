"""MinJerkGenerator: the multi-referential minimum-jerk trajectory generator (Sect. 4, Fig 8).

Two feedback min-jerk controllers (:class:`MinJerkFilter`, Pattacini et al. 2010) run
concurrently: one in joint space toward the IK solution q_d, one in task space toward the hand
pose x_d = K(q_d). They are kept coherent (x_dot = J q_dot) by the Lagrangian combination of
iKin's MultiRefMinJerkCtrl (icub-main iKinInv.cpp):

    q_dot = q_dot_J + W J^T (I + J W J^T)^-1 (x_dot_task - J q_dot_J)

with W = gamma * diag(w_i), w_i = tanh(d_i / g_i) fading to 0 at a joint limit (d_i distance
to the nearest limit, g_i = 0.25 * guard_ratio * range_i), so a joint near its limit follows
the joint-space plan only. The task is the 6-D hand pose (position [m], rotation vector [rad]
of R_d R^T, root_link axes, Jacobian LOCAL_WORLD_ALIGNED). Feedback on the generator's own
state means a new target can be set at any sample and the motion bends toward it smoothly.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from icub_pmp.cartesian.kinematic_chain import KinematicChain
from icub_pmp.cartesian.min_jerk_config import MinJerkConfig
from icub_pmp.cartesian.min_jerk_filter import MinJerkFilter
from icub_pmp.cartesian.sampled_trajectory import GeneratorState, SampledTrajectory
from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.robot_model import IcubModel

__all__ = ["MinJerkGenerator"]


class MinJerkGenerator:
    """Joint trajectories from the current joints to a joint target, min-jerk in both spaces.

    Args:
        model: the pinocchio model.
        chain: the chain whose joints move (the other joints stay at ``q_hold``).
        config: generator parameters.
        trajectory_time: overrides ``config.trajectory_time`` [s].
    """

    def __init__(
        self,
        model: IcubModel,
        chain: KinematicChain,
        config: MinJerkConfig | None = None,
        trajectory_time: float | None = None,
    ):
        self.model = model
        self.chain = chain
        self.config = config or MinJerkConfig()
        self.T = float(self.config.trajectory_time if trajectory_time is None else trajectory_time)
        Ts = self.config.period
        self._idx = model.indices(chain.joints)
        self._fid = model.frame_id(chain.frame)
        self._lo = model.lower[self._idx]
        self._hi = model.upper[self._idx]
        self._guard = 0.25 * self.config.guard_ratio * (self._hi - self._lo)
        n = chain.n
        self.joint_filter = MinJerkFilter(n, self.T, Ts)
        self.task_filter = MinJerkFilter(6, self.T, Ts)
        self._q_full = model.posture("rest")
        self.q = self._q_full[self._idx].copy()
        self.q_target = self.q.copy()
        self._x_target = np.zeros(3)
        self._R_target = np.eye(3)

    # ------------------------------------------------------------------ state
    def reset(self, q_full: np.ndarray, velocity: np.ndarray | None = None) -> None:
        """Start at the full configuration (nq,) [rad], at rest or with chain velocity (n,)."""
        self._q_full = self.model.check_q(q_full).copy()
        self.q = np.clip(self._q_full[self._idx], self._lo, self._hi)
        self.joint_filter.reset(velocity)
        self.task_filter.reset()
        if velocity is not None:
            J = self._jacobian(self.q)
            self.task_filter.reset(J @ np.asarray(velocity, dtype=float))
        self.set_target(self.q)

    def state(self) -> GeneratorState:
        """Snapshot of the generator state (for re-targeting mid-motion)."""
        return GeneratorState(self.q.copy(), self.joint_filter.x.copy(), self.task_filter.x.copy())

    def restore(self, state: GeneratorState) -> None:
        """Continue from a snapshot taken by :meth:`state` (same chain)."""
        if state.q.shape != self.q.shape:
            raise InvalidInput(f"state: expected {self.q.size} joints, got {state.q.size}")
        self.q = state.q.copy()
        self.joint_filter.x = state.joint_filter.copy()
        self.task_filter.x = state.task_filter.copy()

    def set_target(self, q_target: np.ndarray) -> None:
        """New joint target q_d (n,) [rad]; the task target is its hand pose K(q_d)."""
        q_target = np.asarray(q_target, dtype=float).reshape(-1)
        if q_target.shape != self.q.shape or not np.all(np.isfinite(q_target)):
            raise InvalidInput(f"q_target: expected {self.q.size} finite values")
        self.q_target = np.clip(q_target, self._lo, self._hi)
        pose = self._pose(self.q_target)
        self._x_target = pose.translation.copy()
        self._R_target = pose.rotation.copy()

    def feed_back(self, q_measured: np.ndarray) -> None:
        """Replace the generator's joint state by the measured chain joints (n,) [rad] (the
        encoders, ``q_fb`` of the reaching paper's Fig 8): the next :meth:`step` plans from
        where the arm is, not from where the plan was (feedback generation, Sect. 4)."""
        q = np.asarray(q_measured, dtype=float).reshape(-1)
        if q.shape != self.q.shape or not np.all(np.isfinite(q)):
            raise InvalidInput(f"q_measured: expected {self.q.size} finite values")
        self.q = np.clip(q, self._lo, self._hi)

    # ------------------------------------------------------------------ kinematics
    def _full(self, q: np.ndarray) -> np.ndarray:
        qf = self._q_full.copy()
        qf[self._idx] = q
        return qf

    def _pose(self, q: np.ndarray) -> pin.SE3:
        return self.model.frame_pose(self._full(q), self._fid)

    def _jacobian(self, q: np.ndarray) -> np.ndarray:
        return self.model.frame_jacobian(self._full(q), self._fid)[:, self._idx]

    def _weights(self, q: np.ndarray) -> np.ndarray:
        d = np.maximum(0.0, np.minimum(q - self._lo, self._hi - q))
        return self.config.gamma * np.tanh(d / self._guard)

    # ------------------------------------------------------------------ stepping
    def step(self) -> np.ndarray:
        """Advance one period; returns the joint velocity applied (n,) [rad/s]."""
        Ts = self.config.period
        qd_joint = self.joint_filter.step(self.q_target - self.q)
        if self.config.task_space:
            qf = self._full(self.q)
            J = self.model.frame_jacobian(qf, self._fid)[:, self._idx]  # also runs the FK
            pose = self.model.data.oMf[self._fid]
            e_task = np.concatenate(
                [self._x_target - pose.translation, pin.log3(self._R_target @ pose.rotation.T)]
            )
            xd_task = self.task_filter.step(e_task)
            W = self._weights(self.q)
            JW = J * W  # J @ diag(W)
            lam = np.linalg.solve(np.eye(6) + JW @ J.T, xd_task - J @ qd_joint)
            qd = qd_joint + JW.T @ lam
        else:
            qd = qd_joint
        q_next = np.clip(self.q + Ts * qd, self._lo, self._hi)
        qd = (q_next - self.q) / Ts
        self.q = q_next
        return qd

    def rollout(self, max_duration: float | None = None) -> SampledTrajectory:
        """Run until every joint is within ``settle_tolerance`` of q_d and the motion has
        stopped (or ``max_duration_factor`` T, or ``max_duration`` [s]); the samples start at
        the current state (t = 0)."""
        Ts = self.config.period
        horizon = self.config.max_duration_factor * self.T
        if max_duration is not None:
            horizon = min(horizon, max_duration)
        n_max = max(1, int(round(horizon / Ts)))
        tol = self.config.settle_tolerance
        qs, qds, xs, states = [], [], [], []
        for k in range(n_max + 1):
            states.append(self.state())
            qs.append(self.q.copy())
            xs.append(self._pose(self.q).translation.copy())
            if k == n_max:
                qds.append(np.zeros_like(self.q))
                break
            settled = np.max(np.abs(self.q_target - self.q)) < tol
            if settled and k > 0 and np.max(np.abs(qds[-1])) < tol / Ts:
                qds.append(np.zeros_like(self.q))
                break
            qds.append(self.step())
        t = Ts * np.arange(len(qs))
        return SampledTrajectory(
            joint_names=self.chain.joints,
            t=t,
            q=np.array(qs),
            qd=np.array(qds),
            hand_position=np.array(xs),
            states=tuple(states),
        )
