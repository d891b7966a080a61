"""Peripersonal space and two-arm cooperation (Bhat and Mohan 2018): growing neural gas maps
of each arm's reachable space, the shared workspace, neural activity and reward fields,
target allocation, empty areas and the imagined collision check of two reaches. No ROS
imports."""

from icub_pmp.geometry import Capsule, LinkHull, fit_capsule, fit_capsules
from icub_pmp.peripersonal.analytic_babbling import Babbling, analytic_babbling
from icub_pmp.peripersonal.arm_body_model import ArmBodyModel
from icub_pmp.peripersonal.collision_check_config import CollisionCheckConfig
from icub_pmp.peripersonal.collision_verdict import CollisionVerdict
from icub_pmp.peripersonal.empty_area_finder import EmptyArea, EmptyAreaFinder
from icub_pmp.peripersonal.exceptions import MapNotTrained, NoEmptyArea
from icub_pmp.peripersonal.gng_config import GrowingNeuralGasConfig
from icub_pmp.peripersonal.growing_neural_gas import GngTrainingReport, GrowingNeuralGas
from icub_pmp.peripersonal.imagined_collision_check import ImaginedCollisionCheck
from icub_pmp.peripersonal.neural_activity import neural_activity
from icub_pmp.peripersonal.pair_plan import PairPlan, PairSchedule, ScheduleStep
from icub_pmp.peripersonal.peripersonal_config import PeripersonalConfig
from icub_pmp.peripersonal.peripersonal_space import PeripersonalSpace, Reachability
from icub_pmp.peripersonal.reward_field import RewardField
from icub_pmp.peripersonal.segment_distance import segment_distance
from icub_pmp.peripersonal.shared_workspace import SharedWorkspace
from icub_pmp.peripersonal.target_allocator import Allocation, TargetAllocator

__all__ = [
    "Allocation",
    "ArmBodyModel",
    "Babbling",
    "Capsule",
    "CollisionCheckConfig",
    "CollisionVerdict",
    "EmptyArea",
    "EmptyAreaFinder",
    "GngTrainingReport",
    "GrowingNeuralGas",
    "GrowingNeuralGasConfig",
    "ImaginedCollisionCheck",
    "LinkHull",
    "MapNotTrained",
    "NoEmptyArea",
    "PairPlan",
    "PairSchedule",
    "PeripersonalConfig",
    "PeripersonalSpace",
    "Reachability",
    "RewardField",
    "ScheduleStep",
    "SharedWorkspace",
    "TargetAllocator",
    "analytic_babbling",
    "fit_capsule",
    "fit_capsules",
    "neural_activity",
    "segment_distance",
]
