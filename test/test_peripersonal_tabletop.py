"""The tabletop task's planner (issue 19): allocation of a fixed scene by reward, parallel
rounds when the pair check says the jobs do not collide and serial ones when it says they
do, the hand-over through an empty area of the shared workspace, and bad scenes refused."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.peripersonal import (
    GrowingNeuralGas,
    ImaginedCollisionCheck,
    PeripersonalConfig,
    PeripersonalSpace,
)
from icub_pmp.peripersonal.tabletop_task import (
    ImaginedPairCheck,
    Job,
    TabletopPlanner,
    TabletopScene,
    TabletopTaskConfig,
)

Z = -0.07  # the cubes' centres [m]
STEP = 0.02


def grid_map(y_lo: float, y_hi: float, label: str) -> GrowingNeuralGas:
    """Neurons every 2 cm over x in [-0.40, -0.20], y in [y_lo, y_hi] at the hand heights
    of a job (grasp: Z + 0.035, release: Z + 0.06)."""
    xs = np.arange(-0.40, -0.20 + 1e-9, STEP)
    ys = np.arange(y_lo, y_hi + 1e-9, STEP)
    g = np.array([[x, y, Z + dz] for x in xs for y in ys for dz in (0.035, 0.06)])
    return GrowingNeuralGas.from_neurons(g, label=label)


@pytest.fixture(scope="module")
def space():
    """Left arm reaches y in [-0.40, 0.10], right arm y in [-0.10, 0.40]: shared |y| <= 0.1."""
    maps = {"left": grid_map(-0.40, 0.10, "left"), "right": grid_map(-0.10, 0.40, "right")}
    return PeripersonalSpace(maps, config=PeripersonalConfig(reach_radius=0.015))


AREAS = {"left_area": (-0.30, -0.34, Z), "right_area": (-0.30, 0.34, Z)}


def scene(**dest: tuple) -> TabletopScene:
    """A scene from name=(x, y, area)."""
    return TabletopScene({n: (x, y, Z) for n, (x, y, _) in dest.items()}, AREAS,
                         {n: a for n, (_, _, a) in dest.items()})


class Near:
    """A pair check that predicts a collision when the two jobs' hand targets come within
    ``d`` of each other at the same phase (the scheduler's input is a verdict; this one is
    known in advance). Records its calls."""

    def __init__(self, d: float):
        self.d, self.calls = d, []

    def __call__(self, left: Job, right: Job) -> bool:
        self.calls.append((left.object, right.object))
        cfg = TabletopTaskConfig()
        return any(np.linalg.norm(a - b) < self.d
                   for a, b in zip(left.waypoints(cfg), right.waypoints(cfg)))


def test_allocation_and_parallel_rounds_of_a_fixed_scene(space):
    """Each arm takes the cube only it reaches and delivers it to its own area; the shared
    cube goes to the arm with fewer loads; pairs the check finds clear run in parallel."""
    s = scene(a=(-0.30, -0.26, "left_area"), b=(-0.30, 0.26, "right_area"),
              c=(-0.30, 0.0, "left_area"), d=(-0.30, 0.20, "right_area"))
    check = Near(0.05)
    plan = TabletopPlanner(space, check).plan(s)
    assert plan.unreachable == () and dict(plan.undeliverable) == {}
    assert plan.handovers == 0
    objs = {a: [r.jobs[a].object for r in plan.rounds if r.jobs[a]] for a in ("left", "right")}
    # right: b and d only it reaches; left: a, and the shared c (2 rounds instead of 3)
    assert objs == {"left": ["a", "c"], "right": ["b", "d"]} or \
        objs == {"left": ["a", "c"], "right": ["d", "b"]}
    assert [r.mode for r in plan.rounds] == ["parallel", "parallel"]
    assert len(check.calls) == 2 and plan.checks == (2, 0)


def test_collision_verdict_makes_the_round_serial(space):
    """The same kind of scene with the check predicting a collision for the pair that
    works side by side in the middle: that round is serial, the other stays parallel."""
    s = scene(a=(-0.30, -0.26, "left_area"), b=(-0.30, 0.26, "right_area"),
              c=(-0.30, -0.04, "right_area"), d=(-0.30, 0.04, "left_area"))
    plan = TabletopPlanner(space, Near(0.10)).plan(s)
    modes = {frozenset(j.object for j in r.jobs.values() if j): r.mode for r in plan.rounds}
    assert modes[frozenset({"a", "b"})] == "parallel"
    serial = [r for r in plan.rounds if r.mode == "serial"]
    assert serial and plan.checks[1] == len(serial)
    for r in serial:  # a serial round names which arm goes first, and both have a job
        assert r.first in ("left", "right") and all(r.jobs.values())


def test_handover_through_an_empty_area(space):
    """A cube only the left arm reaches whose target area only the right arm reaches: the
    left arm puts it down in the shared workspace, clear of every object and area, and the
    right arm takes it from there to its area in a later round."""
    s = scene(h=(-0.30, -0.20, "right_area"), b=(-0.30, 0.26, "right_area"))
    plan = TabletopPlanner(space, Near(0.05)).plan(s)
    assert plan.handovers == 1
    jobs = [(k, r.jobs[a]) for k, r in enumerate(plan.rounds) for a in ("left", "right")
            if r.jobs[a] is not None and r.jobs[a].object == "h"]
    (k1, give), (k2, take) = jobs
    assert give.arm == "left" and give.kind == "handover" and take.arm == "right"
    assert take.kind == "deliver" and take.area == "right_area" and k2 > k1
    np.testing.assert_allclose(take.pick, give.place)
    assert space.shared.contains(give.place[None] + [0, 0, 0.06])[0]
    others = [np.array(p) for p in list(s.objects.values()) + list(AREAS.values())]
    assert min(np.linalg.norm(give.place - p) for p in others) >= \
        TabletopTaskConfig().place_clearance
    assert give.place[2] == pytest.approx(Z)


def test_unreachable_and_undeliverable_cubes_are_reported(space):
    """A cube neither arm reaches, and one whose area no arm reaches, are not planned."""
    areas = {**AREAS, "far": (-0.60, 0.0, Z)}
    s = TabletopScene({"x": (-0.60, 0.0, Z), "y": (-0.30, 0.0, Z), "a": (-0.30, -0.26, Z)},
                      areas, {"x": "left_area", "y": "far", "a": "left_area"})
    plan = TabletopPlanner(space, Near(0.05)).plan(s)
    assert plan.unreachable == ("x",)
    assert "y" in plan.undeliverable and "far" in plan.undeliverable["y"]
    assert [j.object for j in plan.jobs()] == ["a"]


def test_imagined_pair_check_mirrored_clear_crossing_collides():
    """The real check (PMP mental simulation of both arms, link hulls compared): mirrored
    jobs on each arm's own side are clear, jobs whose places cross in the middle collide."""
    check = ImaginedPairCheck(ImaginedCollisionCheck())
    left = Job("left", "a", "deliver", np.array([-0.25, -0.15, Z]),
               np.array([-0.25, -0.27, Z]), "left_area")
    right = Job("right", "b", "deliver", np.array([-0.25, 0.15, Z]),
                np.array([-0.25, 0.27, Z]), "right_area")
    assert check(left, right) is False
    assert len(check.verdicts) == 4
    cross_l = left._replace(place=np.array([-0.27, 0.02, Z]))
    cross_r = right._replace(place=np.array([-0.27, -0.02, Z]))
    assert check(cross_l, cross_r) is True


def test_bad_scenes_and_inputs_are_refused(space):
    """Empty scenes, a cube without a target area, an unknown area, NaN positions, a
    config with a bad band, a pair check that is not callable: clear errors."""
    with pytest.raises(InvalidInput, match="no objects"):
        TabletopScene({}, AREAS, {})
    with pytest.raises(InvalidInput, match="no target areas"):
        TabletopScene({"a": (-0.3, 0, Z)}, {}, {"a": "left_area"})
    with pytest.raises(InvalidInput, match="has no target area"):
        TabletopScene({"a": (-0.3, 0, Z)}, AREAS, {})
    with pytest.raises(UnknownName, match="target area"):
        TabletopScene({"a": (-0.3, 0, Z)}, AREAS, {"a": "nowhere"})
    with pytest.raises(InvalidInput, match="NaN"):
        TabletopScene({"a": (-0.3, float("nan"), Z)}, AREAS, {"a": "left_area"})
    with pytest.raises(InvalidInput, match="empty_area_band"):
        TabletopTaskConfig(empty_area_band=(0.1, 0.0))
    with pytest.raises(InvalidInput, match="pair_check"):
        TabletopPlanner(space, None)
