"""The Passive Motion Paradigm (Mohan, Morasso, Metta, Sandini 2009): fields, branching
networks, terminal-attractor timing and the planner facade. No ROS imports."""

from icub_pmp.pmp.branch_network import BranchNetwork
from icub_pmp.pmp.force_field import ForceField
from icub_pmp.pmp.held_object import HeldObject
from icub_pmp.pmp.jacobian_provider import FrameKinematics, JacobianProvider
from icub_pmp.pmp.joint_limit_field import JointLimitField
from icub_pmp.pmp.obstacle_field import ObstacleField
from icub_pmp.pmp.orientation_field import OrientationField
from icub_pmp.pmp.pinocchio_provider import PinocchioJacobianProvider
from icub_pmp.pmp.pmp_config import PmpConfig
from icub_pmp.pmp.pmp_network import NetworkState, PmpNetwork, PostureField
from icub_pmp.pmp.pmp_planner import PmpPlanner
from icub_pmp.pmp.posture_memory import PostureMemory, Recall
from icub_pmp.pmp.reach_goal import ReachGoal
from icub_pmp.pmp.reach_plan import ReachPlan
from icub_pmp.pmp.relaxation import Relaxation, RelaxationSettings, RelaxationTrace
from icub_pmp.pmp.tbg_timing import TbgTiming
from icub_pmp.pmp.time_base_generator import TimeBaseGenerator
from icub_pmp.pmp.torque_limit_field import TorqueLimitField

__all__ = [
    "BranchNetwork",
    "ForceField",
    "FrameKinematics",
    "HeldObject",
    "JacobianProvider",
    "JointLimitField",
    "NetworkState",
    "ObstacleField",
    "OrientationField",
    "PinocchioJacobianProvider",
    "PmpConfig",
    "PmpNetwork",
    "PmpPlanner",
    "PostureField",
    "PostureMemory",
    "ReachGoal",
    "ReachPlan",
    "Recall",
    "Relaxation",
    "RelaxationSettings",
    "RelaxationTrace",
    "TbgTiming",
    "TimeBaseGenerator",
    "TorqueLimitField",
]
