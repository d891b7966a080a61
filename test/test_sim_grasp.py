"""The simulator's tabletop cubes and emulated grasp (issue 19): a weld switched on only when
the palm touches the cube in the simulator's contacts, released on request; the robot's
contacts with objects reported as ground truth; bad requests refused with a clear message."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.errors import ConfigError, UnknownName
from icub_sim_bridge.model_builder import ModelBuilder
from icub_sim_bridge.sim_config import SimConfig
from icub_sim_bridge.simulator import GraspRefused, Simulator

CUBES = "cube_a:-0.30,-0.15,-0.07 cube_b:-0.30,0.15,-0.07"


@pytest.fixture(scope="module")
def sim():
    return Simulator(SimConfig(cameras_enabled=False, tabletop_objects=CUBES))


def _touch(sim: Simulator, cube: str, hand: str) -> np.ndarray:
    """Teleport ``cube`` onto the palm (its centre at the hand frame): they overlap."""
    p = sim.frame_pose(sim.built.hand_frames[hand]).position
    sim.set_object_pose(cube, p)
    return p


def test_default_scene_has_no_cubes():
    """The shipped configuration adds nothing to the demo's scene: no cube, no weld."""
    m = ModelBuilder(SimConfig(cameras_enabled=False)).build().model
    assert m.neq == 0
    s = Simulator(SimConfig(cameras_enabled=False), built=ModelBuilder(
        SimConfig(cameras_enabled=False)).build())
    assert s.object_names == ("box", "cylinder") and s.graspable == ()


def test_cubes_rest_on_the_table(sim):
    """The cubes are movable objects at their configured centres and stay on the table."""
    sim.reset("rest")
    assert set(sim.graspable) == {"cube_a", "cube_b"}
    sim.step(300)
    for name, y in (("cube_a", -0.15), ("cube_b", 0.15)):
        p = sim.object_pose(name).position
        np.testing.assert_allclose(p, [-0.30, y, -0.07], atol=3e-3)
    assert sim.object_contacts() == []  # the arms at rest touch no cube


def test_grasp_refused_without_palm_contact(sim):
    """At rest the palm is far from the cube: the grasp is refused, naming the reason, and
    nothing is attached."""
    sim.reset("rest")
    with pytest.raises(GraspRefused, match="does not touch"):
        sim.grasp("cube_a", "left")
    assert sim.grasped == {}


def test_grasp_with_palm_contact_attaches_and_release_drops(sim):
    """With the cube on the palm the contact is reported (arm, link) and the grasp is
    accepted; the held cube then follows the hand instead of falling; released, it falls."""
    sim.reset("rest")
    p = _touch(sim, "cube_a", "left")
    contacts = [c for c in sim.object_contacts() if c.object == "cube_a"]
    assert contacts and {c.arm for c in contacts} == {"left"}
    assert "l_hand" in {c.body for c in contacts}
    sim.grasp("cube_a", "left")
    assert sim.grasped == {"left": "cube_a"}
    assert all(c.grasped for c in sim.object_contacts() if c.object == "cube_a")
    sim.step(500)
    held = sim.object_pose("cube_a").position
    assert np.linalg.norm(held - p) < 0.02  # still in the hand after 0.5 s
    assert sim.release("left") == "cube_a" and sim.grasped == {}
    sim.step(500)
    assert sim.object_pose("cube_a").position[2] < held[2] - 0.05  # fell towards the table


def test_grasp_bad_requests(sim):
    """Unknown hand, an object that is not a cube, a second object in a held hand, a cube
    held by the other hand: clear errors, nothing changes."""
    sim.reset("rest")
    with pytest.raises(UnknownName, match="hand"):
        sim.grasp("cube_a", "middle")
    with pytest.raises(UnknownName, match="graspable object"):
        sim.grasp("box", "left")
    with pytest.raises(UnknownName, match="hand"):
        sim.release("middle")
    _touch(sim, "cube_a", "left")
    sim.grasp("cube_a", "left")
    with pytest.raises(GraspRefused, match="already holds"):
        sim.grasp("cube_b", "left")
    with pytest.raises(GraspRefused, match="left hand holds it"):
        sim.grasp("cube_a", "right")
    assert sim.grasped == {"left": "cube_a"}
    sim.reset("rest")
    assert sim.grasped == {}  # a reset releases every grasp


@pytest.mark.parametrize("spec", ["cube", "cube:1,2", "box:-0.3,0,0", "a:0,0,0 a:0,0,1",
                                  "a:0,nan,0", ":0,0,0"])
def test_bad_tabletop_objects_are_refused(spec):
    """A malformed cube list names the bad entry."""
    with pytest.raises(ConfigError, match="tabletop_objects"):
        SimConfig(tabletop_objects=spec)


def test_bad_cube_size_is_refused():
    with pytest.raises(ConfigError, match="tabletop_cube_size"):
        SimConfig(tabletop_cube_size=0.0)
