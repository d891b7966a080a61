"""Cartesian solver (eq 11 of the reaching paper, CasADi + IPOPT) and min-jerk trajectories.

The core of the ``cartesian_solver`` node (iKinCartesianSolver + cartesianController on the
iCub); no ROS imports.
"""

from icub_pmp.cartesian.arm_linear_constraints import ArmLinearConstraints, LinearConstraints
from icub_pmp.cartesian.cartesian_controller import CartesianController, CartesianMotion
from icub_pmp.cartesian.casadi_kinematics import CasadiKinematics
from icub_pmp.cartesian.ik_config import IkConfig
from icub_pmp.cartesian.ik_problem import IkProblem, NlpConstraint
from icub_pmp.cartesian.ik_seed import IkSeed
from icub_pmp.cartesian.ik_solution import IkSolution
from icub_pmp.cartesian.ik_solver import IkSolver
from icub_pmp.cartesian.kinematic_chain import CHAIN_NAMES, KinematicChain
from icub_pmp.cartesian.min_jerk_config import MinJerkConfig
from icub_pmp.cartesian.min_jerk_filter import MinJerkFilter
from icub_pmp.cartesian.min_jerk_generator import MinJerkGenerator
from icub_pmp.cartesian.sampled_trajectory import GeneratorState, SampledTrajectory

__all__ = [
    "CartesianController",
    "CartesianMotion",
    "ArmLinearConstraints",
    "LinearConstraints",
    "CasadiKinematics",
    "IkConfig",
    "IkProblem",
    "NlpConstraint",
    "IkSeed",
    "IkSolution",
    "IkSolver",
    "CHAIN_NAMES",
    "KinematicChain",
    "MinJerkConfig",
    "MinJerkFilter",
    "MinJerkGenerator",
    "GeneratorState",
    "SampledTrajectory",
]
