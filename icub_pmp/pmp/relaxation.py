"""Relaxation: integration of a PMP network to equilibrium in the TBG's relaxation time s.

The PMP dynamics with the terminal attractor (Appendix A, eq A1; eqs 1-5 and 4a)::

    F = K_ext (x_T - x),  T = J^T F (+ T_int),  q_dot = Gamma(t) A_int T,  x_dot = J q_dot

become, in the relaxation time ``s = -ln(1 - xi(t))`` (``ds = Gamma dt``, see
:mod:`time_base_generator`), the autonomous basic PMP ``dz/ds = A (G^T F(z) + T_int(z))``: a
gradient flow of the network's potential in the metric ``A^-1``. ``t -> tau`` is ``s -> inf``,
so instead of evaluating the diverging Gamma we integrate in s until the equilibrium.

Integrator: linearly implicit Euler (a minimizing-movement step of the gradient flow)::

    (I + h A (G^T K G + D)) dz = h A (G^T F + T_int)

with ``K`` the stiffness of the attractive fields and ``D`` the (diagonal) stiffness of the
internal fields. By the push-through identity it needs one (m x m) solve, m = task rows (6 for
two hands), not an (nz x nz) one; with ``B = h A / (1 + h A D)``::

    dz = B g - B G^T K (I + G B G^T K)^-1 G B g,     g = G^T F + T_int

It is unconditionally stable (any h), which an explicit Euler step of the same flow is not
(stable only for h < 2 / lambda_max(K G A G^T), orders of magnitude below the steps used here
near the end); for small h it follows the PMP flow lines, for large h it converges like
Gauss-Newton, so the tail ``s -> inf`` (``t -> tau``) is reached in a few steps. The step grows
geometrically (``step_growth``) from ``initial_step``: with the defaults 10 steps reach s = 11
(t = 0.985 tau) and 25 steps s = 1000 (t = tau to machine precision). Optional step control
(``max_displacement`` > 0): h is rescaled after each step so the next one moves the hands by
about that much (or what remains), growing by at most ``step_growth``, halving at most: nodes
evenly spread along the hand paths, at the cost of more steps on long paths.

Joint limits are never crossed: every joint may cover at most ``boundary_fraction`` of its
remaining distance to a limit (kept 1e-9 of its range away) per step. A step that would put a
hand inside an obstacle (or, with obstacles and step control, moves a hand more than twice
``max_displacement``) is halved and retried. Obstacles (explicit) and the ``F`` of the
fields are evaluated at the start of the step.

Before the first step the hands' fields may be balanced (:meth:`PmpNetwork.balance_hands`) and
the admittance scaled so the initial relaxation rate is 1 per unit s (Appendix A's gamma = 1);
before every step the hands' fields may be re-weighted by their relative progress
(:meth:`PmpNetwork.synchronise_hands`, an extension: ``synchronise`` > 0).

Stopping: converged when every hand is within ``tolerance`` of its target (and orientation
within ``rotation_tolerance``, and no torque beyond its limit when a torque-limit field is in
the network); stalled (the equilibrium of an unreachable target, Sect. 4) when the worst
residual has not improved by 1% in ``stall_steps`` steps; or ``max_steps``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.linalg import lapack

from icub_pmp.errors import InvalidInput, SolverError
from icub_pmp.pmp.pmp_network import NetworkState, PmpNetwork

__all__ = ["Relaxation", "RelaxationSettings", "RelaxationTrace"]


def _solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve a x = b (LAPACK dgesv directly: numpy's wrapper costs 5x more on 6x6)."""
    _, _, x, info = lapack.dgesv(a, b)
    if info != 0:
        raise SolverError(f"relaxation step: singular linear system (dgesv info {info})")
    return x


@dataclass(frozen=True)
class RelaxationSettings:
    """Step schedule and stopping rules of :class:`Relaxation` (steps in relaxation time s)."""

    initial_step: float = 0.2
    step_growth: float = 1.35
    max_step: float = 1.0e4
    max_displacement: float = 0.0  # [m]; 0 = geometric step growth
    max_steps: int = 200
    stall_steps: int = 15
    tolerance: float = 2.0e-5  # [m]
    rotation_tolerance: float = 1.0e-4  # [rad]
    boundary_fraction: float = 0.99
    normalise_rate: bool = True
    balance_hands: bool = True
    synchronise: float = 0.0  # exponent of PmpNetwork.synchronise_hands (0 = off)

    def __post_init__(self) -> None:
        checks = {
            "initial_step": self.initial_step > 0,
            "step_growth": self.step_growth >= 1.0,
            "max_step": self.max_step >= self.initial_step,
            "max_displacement": self.max_displacement >= 0,
            "max_steps": self.max_steps >= 1,
            "stall_steps": self.stall_steps >= 1,
            "tolerance": self.tolerance > 0,
            "rotation_tolerance": self.rotation_tolerance > 0,
            "boundary_fraction": 0.0 < self.boundary_fraction < 1.0,
            "synchronise": self.synchronise >= 0.0,
        }
        for name, ok in checks.items():
            value = getattr(self, name)
            if not ok or (isinstance(value, float) and not math.isfinite(value)):
                raise InvalidInput(f"relaxation setting {name}: invalid value {value!r}")


class RelaxationTrace(NamedTuple):
    """The relaxation's nodes (N of them, the start included)."""

    s: np.ndarray  # (N,) relaxation time of each node
    z: np.ndarray  # (N, nz) network state (joints [rad], then object position [m])
    hand_positions: np.ndarray  # (N, k, 3) [m]
    hand_rotations: np.ndarray  # (N, k, 3, 3)
    position_errors: np.ndarray  # (N, k) [m]
    rotation_errors: np.ndarray  # (N, k) [rad]
    converged: bool
    stop_reason: str  # "converged" | "stalled" | "max_steps"
    rate_scale: float  # factor applied to A so the initial relaxation rate is 1 per unit s

    @property
    def steps(self) -> int:
        """Number of integration steps taken."""
        return len(self.s) - 1

    def worst_error(self) -> float:
        """Largest final hand position error [m]."""
        return float(self.position_errors[-1].max()) if self.position_errors.size else 0.0


def _jump(a: NetworkState, b: NetworkState) -> float:
    """Largest hand displacement [m] from state a to state b."""
    dx = b.hand_positions - a.hand_positions
    return float(np.sqrt((dx * dx).sum(axis=1)).max())


class Relaxation:
    """Integrates a :class:`PmpNetwork` from a state to its equilibrium."""

    def __init__(self, settings: RelaxationSettings | None = None):
        self.settings = settings or RelaxationSettings()

    @staticmethod
    def rate(network: PmpNetwork, state: NetworkState, admittance: np.ndarray) -> float:
        """Initial relaxation rate gamma along the current force (Appendix A, eq A2):
        ``F^T G A G^T F / F^T K^-1 F``, the rate at which the field's energy decays."""
        f = state.force
        gf = state.jacobian.T @ f
        num = float(gf @ (admittance * gf))
        try:
            den = float(f @ np.linalg.lstsq(network.field_stiffness, f, rcond=None)[0])
        except np.linalg.LinAlgError:
            return 0.0
        return num / den if den > 0 and num > 0 else 0.0

    def run(self, network: PmpNetwork, z0: np.ndarray | None = None) -> RelaxationTrace:
        """Relax from ``z0`` (default: the network's initial state) to equilibrium."""
        cfg = self.settings
        z = network.initial_state() if z0 is None else np.array(z0, dtype=float)
        n = network.n
        # joints stay at least 1e-9 of their range inside the limits (eq 6 is infinite on
        # them): the start is clamped there and every step keeps that margin
        margin = 1e-9 * (network.upper - network.lower)
        lo, hi = network.lower + margin, network.upper - margin
        z[:n] = np.minimum(np.maximum(z[:n], lo), hi)
        state = network.evaluate(z, 0.0)
        if cfg.balance_hands and network.held_object is None and len(network.hands) > 1:
            network.balance_hands(state)
            state = network.evaluate(z, 0.0)
        a = network.admittance
        scale = 1.0
        if cfg.normalise_rate:
            gamma = self.rate(network, state, a)
            if gamma > 0:
                scale = 1.0 / gamma
        a = a * scale
        kmat = network.field_stiffness
        eye = np.eye(network.m)

        s_nodes = [0.0]
        z_nodes = [z.copy()]
        pos_nodes = [state.hand_positions]
        rot_nodes = [state.hand_rotations]
        perr = [state.position_errors]
        rerr = [state.rotation_errors]

        s = 0.0
        h = cfg.initial_step
        best = math.inf
        best_step = 0
        reason = "max_steps"
        converged = self._converged(state)
        if converged:
            reason = "converged"
        sync = cfg.synchronise > 0 and network.can_synchronise
        e0 = state.position_errors + 0.1 * state.rotation_errors
        frac = cfg.boundary_fraction
        flo, fhi = frac * lo, frac * hi
        tol, rot_tol = cfg.tolerance, cfg.rotation_tolerance
        adaptive = cfg.max_displacement > 0
        step = 0
        while not converged and step < cfg.max_steps:
            step += 1
            if sync:
                state = network.synchronise_hands(state, e0, cfg.synchronise)
                kmat = network.field_stiffness
            jac = state.jacobian
            g = jac.T @ state.force + state.torque
            for _ in range(12):  # step halving when a hand would enter an obstacle (or, among
                # obstacles with step control, jump more than twice the step's hand motion)
                ha = h * a
                bmat = ha / (1.0 + ha * state.stiffness)
                gb = jac * bmat
                y = _solve(eye + (gb @ jac.T) @ kmat, gb @ g)
                dz = bmat * g - gb.T @ (kmat @ y)
                # per-joint fraction to the boundary: limits are never reached
                fz = frac * z[:n]
                dz[:n] = np.minimum(np.maximum(dz[:n], flo - fz), fhi - fz)
                z_new = z + dz
                new_state = network.evaluate(z_new, s + h)
                if not network.obstacles:
                    break
                # a body that starts within the clearance may move out of it
                clear = new_state.clearance > 0.0 or new_state.clearance >= state.clearance
                if clear and not (adaptive and _jump(
                        state, new_state) > 2.0 * cfg.max_displacement):
                    break
                h *= 0.5
            if adaptive:
                dx = new_state.hand_positions - state.hand_positions
                moved = float(np.sqrt((dx * dx).sum(axis=1)).max()) + 0.1 * float(
                    np.abs(new_state.rotation_errors - state.rotation_errors).max(initial=0.0))
            z, state, s = z_new, new_state, s + h
            s_nodes.append(s)
            z_nodes.append(z)
            pos_nodes.append(state.hand_positions)
            rot_nodes.append(state.hand_rotations)
            perr.append(state.position_errors)
            rerr.append(state.rotation_errors)
            pmax = state.position_errors.max()
            rmax = state.rotation_errors.max()
            if pmax <= tol and rmax <= rot_tol and state.torque_excess == 0.0:
                converged, reason = True, "converged"
                break
            worst = pmax + 0.1 * rmax + state.torque_excess
            if worst < 0.99 * best:
                best, best_step = worst, step
            elif step - best_step >= cfg.stall_steps:
                reason = "stalled"
                break
            if adaptive:  # step control on the hands' motion
                want = min(cfg.max_displacement, worst)
                ratio = want / moved if moved > 0 else cfg.step_growth
                h = min(h * min(max(ratio, 0.5), cfg.step_growth), cfg.max_step)
            else:
                h = min(h * cfg.step_growth, cfg.max_step)
        return RelaxationTrace(
            s=np.array(s_nodes),
            z=np.array(z_nodes),
            hand_positions=np.array(pos_nodes),
            hand_rotations=np.array(rot_nodes),
            position_errors=np.array(perr),
            rotation_errors=np.array(rerr),
            converged=converged,
            stop_reason=reason,
            rate_scale=scale,
        )

    def _converged(self, state: NetworkState) -> bool:
        cfg = self.settings
        return bool(
            np.all(state.position_errors <= cfg.tolerance)
            and np.all(state.rotation_errors <= cfg.rotation_tolerance)
            and state.torque_excess == 0.0
        )
