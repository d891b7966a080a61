"""Peripersonal-space queries (Bhat and Mohan 2018): shared workspace, neural activity, reward
fields, target allocation and empty areas, on maps whose answers are known."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.errors import InvalidInput, ModelError, UnknownName
from icub_pmp.peripersonal import (
    GrowingNeuralGas,
    MapNotTrained,
    NoEmptyArea,
    PeripersonalConfig,
    PeripersonalSpace,
    neural_activity,
)

STEP = 0.02  # grid spacing of the test maps [m]
Z = 0.0  # table-top height of the test scenes [m]
ARM_Y = {"left": -0.12, "right": 0.12}


def grid_map(y_lo: float, y_hi: float, label: str) -> GrowingNeuralGas:
    """A flat map: neurons every 2 cm over x in [-0.40, -0.20], y in [y_lo, y_hi], z = 0."""
    xs = np.arange(-0.40, -0.20 + 1e-9, STEP)
    ys = np.arange(y_lo, y_hi + 1e-9, STEP)
    g = np.array([[x, y, Z] for x in xs for y in ys])
    return GrowingNeuralGas.from_neurons(g, label=label)


@pytest.fixture(scope="module")
def space():
    """Left arm reaches y in [-0.40, 0.10], right arm y in [-0.10, 0.40]: shared |y| <= 0.1."""
    maps = {"left": grid_map(-0.40, 0.10, "left"), "right": grid_map(-0.10, 0.40, "right")}
    return PeripersonalSpace(maps, config=PeripersonalConfig(reach_radius=0.015))


def test_shared_workspace_is_the_overlap(space):
    """Neurons of each map that the other arm reaches: exactly those with |y| <= 0.1."""
    for arm in ("left", "right"):
        pts = space.shared.points(arm)
        assert len(pts) == space.shared.size(arm) > 0
        assert np.all(np.abs(pts[:, 1]) <= 0.1 + 1e-9)
        n_all = np.sum(np.abs(space.maps[arm].neurons[:, 1]) <= 0.1 + 1e-9)
        assert space.shared.size(arm) == n_all
    inside = space.shared.contains([[-0.3, 0.0, Z], [-0.3, -0.3, Z], [-0.3, 0.3, Z]])
    assert inside.tolist() == [True, False, False]


def test_reward_field_peaks_on_the_acting_arms_side(space):
    """Each arm's Y is the middle of the space only it reaches (y = -/+ 0.26 m here);
    R_i = (exp(-(y_i - Y)^2 / 2 sigma_R^2) + R_c) / Z sums to 1 and is largest at Y: the left
    arm prefers objects on its left (y < 0), the right arm on its right, the shared space
    least; the constant R_c keeps every reward above its floor."""
    assert space.arm_y["left"] == pytest.approx(-0.26) and space.arm_y["right"] == \
        pytest.approx(0.26)
    for arm, sign in (("left", -1), ("right", 1)):
        field = space.reward_fields[arm]
        n = space.maps[arm].neurons
        assert field.rewards.sum() == pytest.approx(1.0)
        assert abs(n[field.peak, 1] - space.arm_y[arm]) <= STEP / 2 + 1e-9
        shared = space.shared.neurons(arm)
        assert field.rewards[shared].max() < np.delete(field.rewards, shared).min()
        assert np.all(field.rewards >= space.config.r_c / field.z - 1e-12)
        own = field.rewards[sign * n[:, 1] > 0.05].mean()
        far = field.rewards[sign * n[:, 1] < -0.05].mean()
        assert own > far
    near_left = space.reachability("left", [[-0.3, -0.12, Z], [-0.3, 0.08, Z]])
    assert near_left.inside.all() and near_left.reward[0] > near_left.reward[1]


def test_reachability_per_arm(space):
    """A point inside a map has its best-matching neuron within reach_radius; outside, the
    reward is 0."""
    r = space.reachability("right", [[-0.3, 0.3, Z], [-0.3, -0.3, Z], [-0.3, 0.3, 0.2]])
    assert r.inside.tolist() == [True, False, False]
    assert r.distance[0] < 1e-9 and r.reward[1] == 0.0 and r.reward[2] == 0.0


def test_activity_is_highest_at_the_objects(space):
    """x_i peaks at the neurons that best match the objects; far neurons stay silent."""
    objects = np.array([[-0.30, -0.30, Z], [-0.24, 0.02, Z]])
    x = space.activity("left", objects)
    n = space.maps["left"].neurons
    for o in objects:
        i = int(np.argmin(np.linalg.norm(n - o, axis=1)))
        nearby = np.linalg.norm(n - o, axis=1) < 0.05
        assert x[i] == pytest.approx(x[nearby].max())
    assert x[np.linalg.norm(n - [-0.4, 0.1, Z], axis=1) < 0.01].max() < 1e-3 * x.max()
    assert neural_activity(n, np.zeros((0, 3)), 0.03).max() == 0.0


def test_allocation_of_a_fixed_scene(space):
    """Objects only one arm reaches go to it; shared objects balance the loads and go to the
    arm they reward most; each arm starts with its highest-reward object (nearest its Y) and
    ends in the shared space; unreachable ones are reported."""
    objects = np.array([
        [-0.30, -0.30, Z],  # 0: left only, far out
        [-0.30, 0.30, Z],  # 1: right only, far out
        [-0.30, -0.06, Z],  # 2: shared, left side
        [-0.30, 0.06, Z],  # 3: shared, right side
        [-0.30, 0.80, Z],  # 4: nobody
        [-0.30, -0.14, Z],  # 5: left only, near the shared space
    ])
    a = space.allocate(objects)
    assert a.assignments["left"] == (0, 5, 2)
    assert a.assignments["right"] == (1, 3)
    assert a.next == {"left": 0, "right": 1}
    assert a.unreachable == (4,)
    assert a.rounds == 3 and a.pairs() == [(0, 1), (5, 3), (2, None)]
    assert a.reachable.tolist()[4] == [False, False] and a.rewards[4].tolist() == [0.0, 0.0]


def test_allocation_moves_shared_work_to_the_idle_arm(space):
    """Three left-only objects and one shared object on the left side: the shared one goes
    to the right arm, which would be idle otherwise (2 rounds instead of 4)."""
    objects = np.array([[-0.3, -0.35, Z], [-0.3, -0.25, Z], [-0.3, -0.15, Z], [-0.3, -0.04, Z]])
    a = space.allocate(objects)
    assert a.assignments["right"] == (3,)
    assert set(a.assignments["left"]) == {0, 1, 2} and a.rounds == 3


def test_empty_area_is_clear_of_every_object(space):
    """The least active shared neuron is farther than the gripper width from every object,
    and farther than a required radius when one is asked for."""
    rng = np.random.default_rng(0)
    objects = np.column_stack([rng.uniform(-0.4, -0.2, 6), rng.uniform(-0.1, 0.1, 6),
                               np.full(6, Z)])
    t = space.config.gripper_width
    for arm in ("left", "right"):
        e = space.empty_area(objects, arm)
        d = np.linalg.norm(objects - e.point, axis=1)
        assert d.min() > t and e.clearance == pytest.approx(d.min())
        assert e.activity == 0.0 and abs(e.point[1]) <= 0.1 + 1e-9
        assert np.allclose(space.maps[arm].neurons[e.neuron], e.point)
    e = space.empty_area(objects[:2], "left", radius=0.1)
    assert np.linalg.norm(objects[:2] - e.point, axis=1).min() >= 0.1
    free = space.empty_area([], "left")  # an empty scene: the middle of the shared space
    assert np.linalg.norm(free.point[:2] - [-0.3, 0.0]) < 0.03


def test_no_empty_area_when_the_shared_space_is_full(space):
    """Objects everywhere in the shared workspace: a clear error with the best clearance."""
    xs, ys = np.meshgrid(np.arange(-0.40, -0.19, 0.05), np.arange(-0.10, 0.11, 0.05))
    objects = np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, Z)])
    with pytest.raises(NoEmptyArea, match="no empty area") as err:
        space.empty_area(objects, "left")
    assert 0 < err.value.best_clearance < space.config.gripper_width
    with pytest.raises(NoEmptyArea, match="z_range"):
        space.empty_area(objects[:1], "left", z_range=(0.5, 0.6))


def test_bad_inputs_give_clear_errors(space, tmp_path):
    """NaN points, an empty object list, an unknown arm and a missing model are refused with
    a message naming what is wrong."""
    with pytest.raises(InvalidInput, match=r"objects: row\(s\) \[1\]"):
        space.allocate([[-0.3, 0.0, 0.0], [np.nan, 0.0, 0.0]])
    with pytest.raises(InvalidInput, match="no objects"):
        space.allocate(np.zeros((0, 3)))
    with pytest.raises(UnknownName, match="unknown arm 'middle'; valid: left, right"):
        space.reachability("middle", [0.0, 0.0, 0.0])
    with pytest.raises(UnknownName, match="middle"):
        space.empty_area([[-0.3, 0.0, 0.0]], "middle")
    with pytest.raises(InvalidInput, match="radius"):
        space.empty_area([[-0.3, 0.0, 0.0]], "left", radius=-1.0)
    with pytest.raises(MapNotTrained, match="right"):
        PeripersonalSpace({"left": space.maps["left"], "right": GrowingNeuralGas(label="right")},
                          ARM_Y)
    with pytest.raises(ModelError, match="no peripersonal maps"):
        PeripersonalSpace.load(tmp_path / "nothing")


def test_save_and_load_both_maps(space, tmp_path):
    """Both maps and the arms' Y are saved in one folder and load back to the same answers."""
    space.save(tmp_path)
    back = PeripersonalSpace.load(tmp_path, space.config)
    objects = [[-0.3, -0.3, Z], [-0.3, 0.05, Z]]
    assert back.allocate(objects).assignments == space.allocate(objects).assignments
    assert back.arm_y == space.arm_y
