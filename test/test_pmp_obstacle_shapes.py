"""Obstacle primitives of the PMP planner (sphere, capsule, box): surface distances, the
repulsive force as the potential's negative gradient, the clearance inflation and the
influence shrunk off the targets (icub_pmp/pmp/obstacle_field.py and its subclasses)."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.rotations import quat_wxyz_to_matrix
from icub_pmp.pmp import ObstacleField
from icub_pmp.pmp.box_obstacle_field import BoxObstacleField
from icub_pmp.pmp.capsule_obstacle_field import CapsuleObstacleField

ROT = quat_wxyz_to_matrix(np.array([0.9, 0.1, -0.3, 0.2]) / np.linalg.norm([0.9, 0.1, -0.3, 0.2]))


def shapes(inflation=0.0):
    return [
        ObstacleField([0.1, 0.0, 0.2], 0.05, inflation=inflation),
        CapsuleObstacleField([0.0, 0.0, 0.0], [0.0, 0.0, 0.2], 0.03, inflation=inflation),
        BoxObstacleField([0.0, 0.1, 0.0], ROT, [0.05, 0.02, 0.1], inflation=inflation),
    ]


def test_known_surface_distances():
    """Capsule: distance to the axis segment minus the radius (beside it and beyond a cap);
    box: to the nearest face from inside (negative), to an edge from outside."""
    cap = CapsuleObstacleField([0, 0, 0], [0, 0, 0.2], 0.03)
    assert cap.surface_distance([0.1, 0.0, 0.1]) == pytest.approx(0.07)
    assert cap.surface_distance([0.0, 0.0, 0.3]) == pytest.approx(0.07)
    assert cap.surface_distance([0.0, 0.01, 0.1]) == pytest.approx(-0.02)
    box = BoxObstacleField([0, 0, 0], np.eye(3), [0.05, 0.02, 0.1])
    assert box.surface_distance([0.0, 0.0, 0.0]) == pytest.approx(-0.02)
    assert box.surface_distance([0.08, 0.06, 0.0]) == pytest.approx(0.05)
    assert box.surface_distance([0.0, 0.0, 0.15]) == pytest.approx(0.05)


@pytest.mark.parametrize("k", range(3))
def test_force_is_the_negative_gradient_of_the_potential(k):
    """Finite differences of the FIRAS potential match the force within the influence shell,
    for every primitive, inflated or not."""
    rng = np.random.default_rng(k)
    for ob in shapes() + shapes(0.01):
        checked = 0
        while checked < 5:
            x = rng.uniform(-0.15, 0.3, 3)
            rho = float(ob.clearance(x))
            if not 0.005 < rho < ob.influence - 0.005:
                continue
            eps = 1e-6
            grad = np.array([(ob.potential(x + eps * e) - ob.potential(x - eps * e)) / (2 * eps)
                             for e in np.eye(3)])
            np.testing.assert_allclose(ob.force(x), -grad, rtol=1e-4, atol=1e-6)
            checked += 1


def test_inflation_and_zero_force_outside_the_shell():
    """The clearance counts from the surface grown by the inflation; no force beyond the
    influence distance."""
    for plain, grown in zip(shapes(), shapes(0.02)):
        x = np.array([0.5, 0.5, 0.5])
        assert grown.clearance(x) == pytest.approx(plain.clearance(x) - 0.02)
        assert np.all(grown.force(x) == 0.0)


def test_clear_of_keeps_the_targets_outside_the_field():
    """clear_of(targets) shrinks the influence so the field is zero at every target (the
    equilibrium stays on it), keeps it when already clear, and rejects a target inside."""
    ob = ObstacleField([0, 0, 0], 0.05, influence=0.05, inflation=0.02)
    target = np.array([0.09, 0.0, 0.0])  # 20 mm outside the grown surface
    assert np.any(ob.force(target) != 0)
    shrunk = ob.clear_of([target])
    assert shrunk.influence == pytest.approx(0.018)
    assert np.all(shrunk.force(target) == 0) and np.any(shrunk.force([0.08, 0, 0]) != 0)
    assert ob.clear_of([[1.0, 0.0, 0.0]]) is ob
    with pytest.raises(InvalidInput, match="inside"):
        ob.clear_of([[0.06, 0.0, 0.0]])


@pytest.mark.parametrize("make, match", [
    (lambda: CapsuleObstacleField([0, 0, 0], [0, 0, 0], 0.1), "coincide"),
    (lambda: CapsuleObstacleField([0, 0, 0], [0, 0, 1], -0.1), "radius"),
    (lambda: BoxObstacleField([0, 0, 0], np.eye(3) * 2, [0.1, 0.1, 0.1]), "rotation"),
    (lambda: BoxObstacleField([0, 0, 0], np.eye(3), [0.1, 0.0, 0.1]), "box size"),
    (lambda: ObstacleField([0, 0, np.nan], 0.1), "center"),
    (lambda: ObstacleField([0, 0, 0], 0.1, inflation=-0.01), "inflation"),
])
def test_bad_shapes_are_rejected(make, match):
    """Each malformed primitive: InvalidInput naming what is wrong."""
    with pytest.raises(InvalidInput, match=match):
        make()
