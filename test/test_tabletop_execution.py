"""The tabletop task in the physics (issue 19): a cube only the left arm reaches, whose target
area only the right arm reaches, is handed over through an empty area of the shared
workspace and delivered, with the emulated grasp (palm contact) and no arm-arm or other
arm-object contact; a grasp where the cube is not is refused and the cube not delivered."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.demo.tabletop import WRISTS, sim_config_for
from icub_pmp.peripersonal import (
    GrowingNeuralGas,
    ImaginedCollisionCheck,
    PeripersonalConfig,
    PeripersonalSpace,
)
from icub_pmp.peripersonal.tabletop_task import (
    ImaginedPairCheck,
    TabletopPlanner,
    TabletopScene,
)
from icub_sim_bridge.harness.sim_loop import SimLoop
from icub_sim_bridge.harness.tabletop_execution import TabletopExecution

pytestmark = pytest.mark.slow

Z = -0.07
SCENE = TabletopScene({"cube_h": (-0.30, -0.10, Z)}, {"right_area": (-0.28, 0.24, Z)},
                      {"cube_h": "right_area"})


def grid_map(y_lo: float, y_hi: float, label: str) -> GrowingNeuralGas:
    """Neurons every 2 cm over x in [-0.32, -0.24], y in [y_lo, y_hi], at the grasp and
    release heights (a strip both real arms reach over the table)."""
    g = np.array([[x, y, Z + dz] for x in np.arange(-0.32, -0.24 + 1e-9, 0.02)
                  for y in np.arange(y_lo, y_hi + 1e-9, 0.02) for dz in (0.035, 0.06)])
    return GrowingNeuralGas.from_neurons(g, label=label)


@pytest.fixture(scope="module")
def setup():
    space = PeripersonalSpace({"left": grid_map(-0.30, 0.04, "left"),
                               "right": grid_map(-0.04, 0.30, "right")},
                              config=PeripersonalConfig(reach_radius=0.015))
    check = ImaginedCollisionCheck(frozen_joints=WRISTS)
    plan = TabletopPlanner(space, ImaginedPairCheck(check)).plan(SCENE)
    run = TabletopExecution(SimLoop(sim_config=sim_config_for(SCENE), estimator=False), check)
    return plan, run


def test_handover_delivered_in_the_physics(setup):
    plan, run = setup
    assert [r.mode for r in plan.rounds] == ["single", "single"] and plan.handovers == 1
    report = run.execute(SCENE, plan)
    assert report.grasp_refusals == ()
    assert report.delivered == ("cube_h",) and report.handovers == 1
    assert report.arm_arm_contacts == 0 and report.arm_object_collisions == ()
    assert report.success
    # the cube lay in the empty area between the two jobs (the trace after the release)
    spot = plan.rounds[0].jobs["left"].place
    released = [t for t in run.trace if t["phase"] == "retreat"][0]["objects"]["cube_h"]
    assert np.hypot(*(np.array(released[:2]) - spot[:2])) < 0.05


def test_grasp_without_the_cube_is_refused(setup):
    """The plan says the cube is 12 cm from where it is: the palm lands beside it, the grasp
    is refused, nothing is carried, the cube is not delivered."""
    plan, run = setup
    moved = TabletopScene({"cube_h": (-0.30, -0.22, Z)}, SCENE.areas, SCENE.destinations)
    first = plan._replace(rounds=plan.rounds[:1])
    report = run.execute(moved, first)
    assert len(report.grasp_refusals) == 1 and "does not touch" in report.grasp_refusals[0]
    assert report.delivered == () and not report.success
