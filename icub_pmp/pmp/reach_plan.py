"""ReachPlan: the result of a PMP plan (mental simulation, Sect. 4): trajectory + residuals."""

from __future__ import annotations

import dataclasses
import functools
from typing import Callable, Mapping, Sequence

import numpy as np

from icub_pmp.pmp.relaxation import RelaxationTrace

__all__ = ["ReachPlan"]


@dataclasses.dataclass(frozen=True)
class ReachPlan:
    """A planned reach. Arrays are read-only.

    Attributes:
        hands: the hands that took part, in :attr:`residuals` order.
        joint_names: the trajectory's joints: the network's, then the arm joints of idle
            hands held in place while the trunk moves (``PmpConfig.hold_idle_hands``,
            decision 0056); others do not move.
        t: (N,) sample times [s], 0 .. tau.
        positions: (N, n) joint angles [rad]; ``positions[-1]`` is the equilibrium.
        velocities: (N, n) [rad/s] (zero at both ends).
        hand_paths: hand -> (N, 3) predicted hand positions [m]: forward kinematics of every
            sample, computed on first access (about 1 ms; not needed to plan).
        residuals: hand -> distance to its target at t = tau [m] (the "tool length" that would
            be needed when the target is out of reach).
        rotation_residuals: hand -> orientation error at tau [rad] (0 if position-only).
        success: every residual within the success tolerances (and torques within limits
            after settling, when target forces were given).
        message: one line for a user.
        tau: TBG duration [s].
        q_start: (nq,) full start configuration [rad]; q_final: (nq,) at tau.
        trace: the relaxation nodes (relaxation time s, states, hand positions).
        object_path: (N, 3) held-object path [m], or None.
        torque_ratio: max |tau_i| / tau_max_i at tau after settling (None without forces).
        obstacle_clearance: smallest distance [m] from a hand to an obstacle surface along
            the sampled plan (None without obstacles).
        final_torques: (n,) joint torques [N m] needed at the final posture (target forces
            + gravity) over the network's joints (the first n of ``joint_names``; None
            without target forces or torque limits).
        torque_limits: (n,) the limits [N m] they were held to (None likewise).
        hand_frames_only: with obstacles, no plan keeping the arms' volumes clear reached, and
            this one keeps the hand frames clear only (decision 0063).
        attempts: relaxations run (1 + those guided by remembered postures).
        used_memory: whether the posture-memory relaxation gave the returned plan.
    """

    hands: tuple[str, ...]
    joint_names: tuple[str, ...]
    t: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    residuals: Mapping[str, float]
    rotation_residuals: Mapping[str, float]
    success: bool
    message: str
    tau: float
    q_start: np.ndarray
    q_final: np.ndarray
    trace: RelaxationTrace
    object_path: np.ndarray | None = None
    torque_ratio: float | None = None
    attempts: int = 1
    used_memory: bool = False
    obstacle_clearance: float | None = None
    final_torques: np.ndarray | None = None
    torque_limits: np.ndarray | None = None
    hand_frames_only: bool = False
    path_function: Callable[[], Mapping[str, np.ndarray]] | None = dataclasses.field(
        default=None, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        for name in ("t", "positions", "velocities", "q_start", "q_final", "object_path",
                     "final_torques", "torque_limits"):
            a = getattr(self, name)
            if isinstance(a, np.ndarray):
                a.setflags(write=False)

    @functools.cached_property
    def hand_paths(self) -> Mapping[str, np.ndarray]:
        """hand -> (N, 3) predicted hand path [m] (forward kinematics of the samples)."""
        paths = self.path_function() if self.path_function is not None else {}
        for a in paths.values():
            a.setflags(write=False)  # (the plan's cached paths: never written)
        return paths

    @property
    def max_residual(self) -> float:
        """Largest hand residual at tau [m]."""
        return max(self.residuals.values(), default=0.0)

    def configurations(self, joint_names: Sequence[str]) -> np.ndarray:
        """Full configurations (N, nq) [rad] at the samples, in the order of ``joint_names``
        (the body model's, that of :attr:`q_start`); joints the plan does not move stay at
        ``q_start``."""
        names = list(joint_names)
        q = np.repeat(np.asarray(self.q_start, dtype=float)[None], len(self.t), axis=0)
        q[:, [names.index(j) for j in self.joint_names]] = self.positions
        return q

    def hand_speed(self, hand: str) -> np.ndarray:
        """(N,) hand speed [m/s] along the predicted path (finite differences)."""
        return np.linalg.norm(np.gradient(self.hand_paths[hand], self.t, axis=0), axis=1)
