"""Bugs the interface fuzzer found (issue 22), pinned on the cores: each was a hang of the
node's service or action (the executor busy for hours), now a clear rejection at once."""

from __future__ import annotations

import time

import numpy as np
import pytest

from icub_pmp.cartesian import CartesianController, MinJerkConfig
from icub_pmp.errors import ConfigError, InvalidInput
from icub_pmp.gaze.gaze_controller import GazeController
from icub_pmp.gaze.gaze_controller_config import GazeControllerConfig
from icub_pmp.kinematics.robot_spec import RobotSpec


@pytest.mark.parametrize("asked", [1e9, 1e300, 60.5])
def test_cartesian_goal_longer_than_max_trajectory_time_is_rejected(vm_ik_solver, asked):
    """A go-to-pose asking trajectory_time 1e9 s used to roll out 4e11 samples in the
    service call (no answer, every other request of the node stuck behind it)."""
    ctrl = CartesianController(vm_ik_solver, MinJerkConfig())
    with pytest.raises(InvalidInput, match="max_trajectory_time"):
        ctrl.trajectory_time(asked)
    assert ctrl.trajectory_time(60.0) == 60.0
    assert ctrl.trajectory_time(0.0) == MinJerkConfig().trajectory_time


def test_gaze_neck_time_longer_than_max_is_rejected_at_once(model):
    """A look_at asking duration 1e9 s used to roll out 3e11 samples in the service call."""
    gaze = GazeController(model=model)
    rest = dict(RobotSpec.load().posture("rest"))
    t0 = time.perf_counter()
    with pytest.raises(InvalidInput, match="max_neck_traj_time"):
        gaze.plan(np.array([-0.4, 0.0, 0.0]), rest, neck_traj_time=1e9)
    assert time.perf_counter() - t0 < 5.0
    plan = gaze.plan(np.array([-0.4, 0.0, 0.0]), rest, neck_traj_time=1.0)
    assert plan.duration > 0


def test_max_durations_are_validated():
    """The new bounds cannot be set below the default times."""
    with pytest.raises(ConfigError, match="max_trajectory_time"):
        MinJerkConfig(trajectory_time=2.0, max_trajectory_time=1.0).validate()
    with pytest.raises(ConfigError, match="max_neck_traj_time"):
        GazeControllerConfig(max_neck_traj_time=0.5).validate()
