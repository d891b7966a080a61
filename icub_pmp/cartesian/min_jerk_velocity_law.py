"""MinJerkVelocityLaw: the multi-referential minimum-jerk generator closed on the measured
joints, as the iCub's cartesianController runs it (the reaching paper, Sect. 4 and Fig 8;
icub-main ServerCartesianController.cpp).

Every controller period the generator's joint state is replaced by the encoders (``q_fb``)
and one step gives the chain's joint velocities, which go to the joint velocity loop (eq 7 of
the impedance controller). Unlike the open-loop rollout of
:class:`~icub_pmp.cartesian.cartesian_controller.CartesianController` (a whole trajectory sent
once), tracking lag, friction and model errors are corrected as they happen: the plan always
starts from where the arm is.
"""

from __future__ import annotations

import numpy as np

from icub_pmp.cartesian.kinematic_chain import KinematicChain
from icub_pmp.cartesian.min_jerk_config import MinJerkConfig
from icub_pmp.cartesian.min_jerk_generator import MinJerkGenerator
from icub_pmp.kinematics.robot_model import IcubModel

__all__ = ["MinJerkVelocityLaw"]


class MinJerkVelocityLaw:
    """Joint velocities toward q_d from the measured joints, one period at a time.

    Args:
        model: the pinocchio model.
        chain: the moving chain.
        config: generator settings (``period`` is the control period [s]).
        trajectory_time: T [s] (default ``config.trajectory_time``).
    """

    def __init__(self, model: IcubModel, chain: KinematicChain,
                 config: MinJerkConfig | None = None, trajectory_time: float | None = None):
        self.gen = MinJerkGenerator(model, chain, config, trajectory_time)
        self.joint_names = tuple(chain.joints)
        self.idx = model.indices(chain.joints)
        self.period = self.gen.config.period

    def start(self, q_full: np.ndarray, q_d: np.ndarray) -> None:
        """Begin a reach from the full measured configuration (nq,) toward the chain's
        target q_d (n,) [rad] (raises InvalidInput on a wrong shape or NaN)."""
        self.gen.reset(q_full)
        self.gen.set_target(q_d)

    def command(self, q_full: np.ndarray) -> np.ndarray:
        """The chain's joint velocities (n,) [rad/s] for the measured configuration (nq,)."""
        self.gen.feed_back(np.asarray(q_full, dtype=float)[self.idx])
        return self.gen.step()

    def remaining(self, q_full: np.ndarray) -> float:
        """Largest joint distance to q_d [rad] of the measured configuration."""
        return float(np.max(np.abs(self.gen.q_target - np.asarray(q_full)[self.idx])))
