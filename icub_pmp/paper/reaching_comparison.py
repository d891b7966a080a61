"""Table 2 of the reaching paper executed in the physics: the minimum-jerk Cartesian controller
against VITE and DLS on point-to-point reaches (Metta et al. 2011, Sect. 4.1, Fig 9, Table 2).

Each controller is a velocity law closed at 100 Hz (the cartesianController's period) on the
robot: every 10 ms it reads the measured joints (``q_fb`` of Fig 8: the simulator's encoders,
with the realism preset's quantisation and the controller's view), computes the 7 arm joints'
velocities and sends them to the 1 kHz impedance controller's velocity mode (eq 7), which
integrates them into position set-points on the simulated robot (friction, mismatch, noise):

- ``minjerk``: the multi-referential minimum-jerk generator (:class:`MinJerkGenerator`, T = 2 s)
  toward the IK solution q_d (eq 11), fed back with the measured joints at every period (the
  paper's feedback formulation);
- ``vite``: the same multi-referential scheme with VITE dynamics in both spaces (alpha 0.008,
  beta 0.002 per ms: :class:`ViteFilter`), run open loop on its own state as Hersch and Billard
  did, the plan tracked by a proportional joint velocity law of gain K_P = 3 1/s (our reading of
  the paper's K_P: its meaning is in ref [14], which we do not have);
- ``dls``: damped least squares (mu = 1e-5) on the measured 6-D pose error with a gain that
  removes 90 % of it in T, plus the gradient projection of a joint-limit cost in the null space
  (the Orocos controller of the paper).

A trial starts at the rest posture (each joint offset by up to +-0.5 deg, seeded: a robot never
starts twice from the same encoders), holds 0.3 s, then runs the law for 2 T. The hand path is
the simulator's true hand (forward kinematics of the true joints at 1 kHz). Figures per
controller: final position and orientation errors against the asked pose, the mean radius of
the 95 % band of the paths (per time sample, the 95th percentile of the trials' distances from
the mean path, averaged over the motion), and the mean hand jerk ||d^3x/dt^3|| of the 1 kHz
path low-passed (zero phase, the same for every controller) at :data:`JERK_CUTOFF_HZ`: the
reach's own band. Above it the jerk of the executed path is that of the joint servo (friction,
quantised encoders, 100 Hz velocity steps), the same whichever controller plans, so the
comparison is also given against the cut-off (docs/decisions/0051-table2-executed-reaches.md).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Protocol

import numpy as np
import pinocchio as pin

from icub_pmp.cartesian.kinematic_chain import KinematicChain
from icub_pmp.cartesian.min_jerk_config import MinJerkConfig
from icub_pmp.cartesian.min_jerk_generator import MinJerkGenerator
from icub_pmp.cartesian.min_jerk_velocity_law import MinJerkVelocityLaw
from icub_pmp.cartesian.vite_filter import ViteFilter
from icub_pmp.control.impedance_controller_config import ImpedanceControllerConfig
from icub_pmp.kinematics.robot_model import IcubModel

__all__ = ["VelocityLaw", "MinJerkLaw", "ViteLaw", "DlsLaw", "ReachTrial", "ControllerStats",
           "run_trials", "controller_stats", "band_radius", "mean_jerk", "PALM_DOWN",
           "TABLE2_TARGET", "CONTROLLERS", "JERK_CUTOFF_HZ"]

#: the right hand's palm directed downward (root_link: x backward, y right, z up); iCub's
#: "palm inward, pointing forward" orientation of its grasping demos turned 90 deg about x
PALM_DOWN = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]])
#: "a location in front of the iCub" [m, root_link]: 15 cm from the rest posture's hand, the
#: farthest point of a 4 x 4 x 5 grid in front of the chest where the 7-DoF arm reaches the
#: palm-down orientation within 0.01 rad (IK, eq 11)
TABLE2_TARGET = np.array([-0.34, 0.12, 0.14])
CONTROLLERS = ("minjerk", "vite", "dls")
#: low-pass of the hand path before the jerk [Hz] (module doc)
JERK_CUTOFF_HZ = 5.0


class VelocityLaw(Protocol):
    """A reaching controller closed on the measured joints at period ``Ts``."""

    def start(self, q_full: np.ndarray, q_d: np.ndarray) -> None:
        """Begin a reach from the full measured configuration toward the chain's q_d."""

    def command(self, q_full: np.ndarray) -> np.ndarray:
        """The chain's joint velocities (n,) [rad/s] for the measured configuration."""


class MinJerkLaw(MinJerkVelocityLaw):
    """The feedback multi-referential minimum-jerk generator (module doc)."""

    def __init__(self, model: IcubModel, chain: KinematicChain, T: float = 2.0,
                 Ts: float = 0.01):
        super().__init__(model, chain, MinJerkConfig(trajectory_time=T, period=Ts))


class ViteLaw:
    """Multi-referential VITE run open loop, its plan tracked with gain ``kp`` (module doc)."""

    def __init__(self, model: IcubModel, chain: KinematicChain, Ts: float = 0.01,
                 kp: float = 3.0, T: float = 2.0):
        self.gen = MinJerkGenerator(model, chain, MinJerkConfig(trajectory_time=T, period=Ts))
        self.gen.joint_filter = ViteFilter(len(chain.joints), Ts)
        self.gen.task_filter = ViteFilter(6, Ts)
        self.idx = model.indices(chain.joints)
        self.kp = float(kp)

    def start(self, q_full: np.ndarray, q_d: np.ndarray) -> None:
        self.gen.reset(q_full)
        self.gen.set_target(q_d)

    def command(self, q_full: np.ndarray) -> np.ndarray:
        qd_plan = self.gen.step()
        return qd_plan + self.kp * (self.gen.q - q_full[self.idx])


class DlsLaw:
    """Damped least squares on the measured pose error with joint-limit gradient projection
    (module doc). ``gain`` [1/s] defaults to ln(10) / T; ``k_limits`` scales the null-space
    term."""

    def __init__(self, model: IcubModel, chain: KinematicChain, mu: float = 1e-5,
                 T: float = 2.0, k_limits: float = 0.5, gain: float | None = None):
        self.model = model
        self.idx = model.indices(chain.joints)
        self.fid = model.frame_id(chain.frame)
        self.mu = float(mu)
        self.gain = math.log(10.0) / T if gain is None else float(gain)
        self.k_limits = float(k_limits)
        lo, hi = model.lower[self.idx], model.upper[self.idx]
        self.mid, self.range = 0.5 * (lo + hi), hi - lo
        self.x_d = np.zeros(3)
        self.R_d = np.eye(3)

    def start(self, q_full: np.ndarray, q_d: np.ndarray) -> None:
        qf = np.array(q_full, dtype=float)
        qf[self.idx] = q_d
        pose = self.model.frame_pose(qf, self.fid)
        self.x_d, self.R_d = pose.translation.copy(), pose.rotation.copy()

    def command(self, q_full: np.ndarray) -> np.ndarray:
        J = self.model.frame_jacobian(q_full, self.fid)[:, self.idx]  # also runs the FK
        M = self.model.data.oMf[self.fid]
        e = np.concatenate([self.x_d - M.translation, pin.log3(self.R_d @ M.rotation.T)])
        J_dls = J.T @ np.linalg.inv(J @ J.T + self.mu**2 * np.eye(6))
        q = q_full[self.idx]
        grad = -(q - self.mid) / self.range**2  # descent of sum ((q - mid) / range)^2
        null = np.eye(len(self.idx)) - J_dls @ J
        return J_dls @ (self.gain * e) + null @ (self.k_limits * grad)


@dataclasses.dataclass(frozen=True)
class ReachTrial:
    """One executed reach: times (k,) [s from the start], true hand positions (k, 3) [m], the
    final position error [m] and orientation error [rad] against the asked pose."""

    t: np.ndarray
    x: np.ndarray
    position_error: float
    orientation_error: float


@dataclasses.dataclass(frozen=True)
class ControllerStats:
    """Table 2's row for one controller (errors as mean and 95 % half-width over trials)."""

    name: str
    trials: int
    position_error_mm: tuple[float, float]
    orientation_error_rad: tuple[float, float]
    band_radius_mm: tuple[float, float]
    jerk: float  # mean hand jerk [m/s^3], mean over the trials
    mean_path: np.ndarray  # (k, 3) [m]


def _law(name: str, model: IcubModel, chain: KinematicChain, T: float, Ts: float
         ) -> VelocityLaw:
    if name == "minjerk":
        return MinJerkLaw(model, chain, T, Ts)
    if name == "vite":
        return ViteLaw(model, chain, Ts, T=T)
    if name == "dls":
        return DlsLaw(model, chain, T=T)
    raise ValueError(f"controller {name!r}: expected one of {CONTROLLERS}")


def run_trials(sim, controller: str, trials: int, seed: int = 0,  # noqa: ANN001
               target: np.ndarray = TABLE2_TARGET, rotation: np.ndarray = PALM_DOWN,
               T: float = 2.0, Ts: float = 0.01) -> list[ReachTrial]:
    """``trials`` reaches of the right arm (7 DoF) on ``sim`` (an icub_sim_bridge Simulator,
    kept across trials: the same robot) with ``controller`` (module doc)."""
    from icub_pmp.cartesian.ik_solver import IkSolver
    from icub_sim_bridge.harness.sim_loop import SimLoop

    model = IcubModel(sim.spec)
    chain = KinematicChain.from_name("right_arm", sim.spec)
    fid = model.frame_id(chain.frame)
    rest = model.posture("rest")
    sol = IkSolver(model).solve("right_arm", np.asarray(target, float), rotation, rest)
    if not sol.success:
        raise ValueError(f"Table 2 target {target} is not reachable: {sol.position_error} m")
    rng = np.random.default_rng(seed)
    names = list(sim.joint_names)
    rest_dict = sim.spec.posture("rest")
    out = []
    for _ in range(trials):
        start = {n: v + math.radians(rng.uniform(-0.5, 0.5)) if n in chain.joints else v
                 for n, v in rest_dict.items()}
        sim.reset(q=start)
        loop = SimLoop(ImpedanceControllerConfig(mode="position",
                                                 feedforward="inverse_dynamics"), sim=sim)
        loop.run(0.3)
        law = _law(controller, model, chain, T, Ts)
        ctrl = loop.controller

        def q_model(values: np.ndarray, base: np.ndarray = rest) -> np.ndarray:
            return model.q_from_dict(dict(zip(names, values)), base)

        law.start(q_model(ctrl.measured_position), sol.q)
        t0 = loop.t
        ts, xs = [], []

        def record(_step, t0=t0, ts=ts, xs=xs, loop=loop) -> None:  # noqa: ANN001
            ts.append(loop.t - t0)
            xs.append(model.frame_position(q_model(sim.true_joint_state().position), fid))

        for _ in range(int(round(2 * T / Ts))):
            qd = law.command(q_model(ctrl.measured_position))
            ctrl.set_velocity_command(chain.joints, qd, loop.t)
            loop.run(Ts, record)
        final = model.frame_pose(q_model(sim.true_joint_state().position), fid)
        out.append(ReachTrial(
            np.array(ts), np.array(xs), float(np.linalg.norm(final.translation - target)),
            float(np.linalg.norm(pin.log3(rotation @ final.rotation.T)))))
    return out


def band_radius(paths: np.ndarray, level: float = 95.0) -> np.ndarray:
    """Per time sample, the ``level`` percentile of the paths' distances from the mean path
    (paths (trials, k, 3) [m]) -> (k,) [m]."""
    mean = paths.mean(axis=0)
    d = np.linalg.norm(paths - mean, axis=2)
    return np.percentile(d, level, axis=0)


def mean_jerk(t: np.ndarray, x: np.ndarray, cutoff_hz: float = JERK_CUTOFF_HZ) -> float:
    """Mean ||d^3x/dt^3|| [m/s^3] of a path sampled uniformly at times t (k,), after a
    zero-phase 4th-order Butterworth low-pass at ``cutoff_hz``."""
    from scipy.signal import butter, filtfilt

    dt = float(np.median(np.diff(t)))
    b, a = butter(4, cutoff_hz * 2.0 * dt)
    xf = filtfilt(b, a, x, axis=0)
    jerk = np.diff(xf, n=3, axis=0) / dt**3
    return float(np.mean(np.linalg.norm(jerk, axis=1)))


def _half95(values: np.ndarray) -> tuple[float, float]:
    a = np.asarray(values, dtype=float)
    return float(a.mean()), float(1.96 * a.std(ddof=1)) if a.size > 1 else 0.0


def controller_stats(name: str, trials: list[ReachTrial]) -> ControllerStats:
    """Table 2's figures of ``trials`` (same length paths) for controller ``name``."""
    k = min(len(tr.t) for tr in trials)
    paths = np.stack([tr.x[:k] for tr in trials])
    radius = band_radius(paths) if len(trials) > 1 else np.zeros(k)
    return ControllerStats(
        name, len(trials),
        _half95(np.array([tr.position_error for tr in trials]) * 1e3),
        _half95(np.array([tr.orientation_error for tr in trials])),
        (float(radius.mean() * 1e3), float(1.96 * radius.std() * 1e3)),
        float(np.mean([mean_jerk(tr.t[:k], tr.x[:k]) for tr in trials])),
        paths.mean(axis=0))
