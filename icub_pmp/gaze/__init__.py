"""Gaze control of the iCub head (iKinGazeCtrl): neck and eyes fixate a 3-D point.

The core of the ``gaze_controller`` node; no ROS imports.
"""

from icub_pmp.gaze.eye_fixation import EYE_JOINTS, EyeFixation
from icub_pmp.gaze.gaze_controller import GazeController
from icub_pmp.gaze.gaze_controller_config import GazeControllerConfig
from icub_pmp.gaze.gaze_node_config import GazeNodeConfig
from icub_pmp.gaze.gaze_plan import GazePlan, GazeState
from icub_pmp.gaze.gaze_solution import GAZE_JOINTS, GazeSolution
from icub_pmp.gaze.min_jerk_loop import MinJerkLoop
from icub_pmp.gaze.neck_solver import NECK_JOINTS, NeckSolution, NeckSolver

__all__ = [
    "EYE_JOINTS",
    "EyeFixation",
    "GazeController",
    "GazeControllerConfig",
    "GazeNodeConfig",
    "GazePlan",
    "GazeState",
    "GAZE_JOINTS",
    "GazeSolution",
    "MinJerkLoop",
    "NECK_JOINTS",
    "NeckSolution",
    "NeckSolver",
]
