"""FrictionCompensation: the joint friction the torque loop adds back (Sect. 3, eqs 4-5).

The iCub boards drive the motor with the torque PID output of eq 5 plus a model of the joint
friction, so that the joint torque follows ``tau_d`` although the gearbox (Harmonic Drive)
dissipates part of the motor torque. Per joint, with the desired velocity ``q_dot_d`` of the
set-point (a feed-forward: no noise of the measured velocity, no chattering at rest):

    tau_f = F_c tanh(q_dot_d / v_eps) + b q_dot_d

(Coulomb ``F_c`` [N m], viscous ``b`` [N m s/rad], smoothing speed ``v_eps`` [rad/s]). At
rest nothing is added: stiction then helps the joint hold, and the torque loop's integral
takes up what is left. The figures are per joint group (torso, arm, neck, eyes).
"""

from __future__ import annotations

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["FrictionCompensation"]


class FrictionCompensation:
    """Friction feed-forward on ``n`` joints (module doc).

    Args:
        coulomb: (n,) [N m]; viscous: (n,) [N m s/rad]; velocity_epsilon: [rad/s] > 0.
    """

    def __init__(self, coulomb: np.ndarray, viscous: np.ndarray, velocity_epsilon: float):
        self.coulomb = np.array(coulomb, dtype=float)
        self.viscous = np.array(viscous, dtype=float)
        if self.coulomb.shape != self.viscous.shape or not velocity_epsilon > 0:
            raise InvalidInput(f"FrictionCompensation: coulomb {self.coulomb.shape} and "
                               f"viscous {self.viscous.shape} must match and velocity_epsilon"
                               f" must be > 0, got {velocity_epsilon}")
        self.velocity_epsilon = float(velocity_epsilon)
        self.coulomb.setflags(write=False)
        self.viscous.setflags(write=False)

    def __call__(self, qd_desired: np.ndarray) -> np.ndarray:
        """Torque (n,) [N m] to add to the command for desired velocities (n,) [rad/s]."""
        return (self.coulomb * np.tanh(qd_desired / self.velocity_epsilon)
                + self.viscous * qd_desired)
