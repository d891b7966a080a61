"""Simulator API: effort commands (validation, saturation, hold hand-over), reset, objects,
scripted wrenches, and the 1 ms step staying stable with torques at the limits."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics import RobotSpec


def test_reset_puts_posture_and_holds_it(sim):
    """After reset('rest') the joints are at the robot.yaml rest posture and, with no command,
    stay there (internal hold) for a simulated second."""
    spec = RobotSpec.load()
    sim.reset("rest")
    rest = np.array([spec.posture("rest")[n] for n in sim.joint_names])
    np.testing.assert_allclose(sim.joint_state().position, rest, atol=1e-12)
    t0 = sim.time
    sim.step(1000)
    assert sim.time == pytest.approx(t0 + 1.0)
    np.testing.assert_allclose(sim.joint_state().position, rest, atol=1e-4)
    assert not sim.commanded.any()


def test_command_is_applied_and_saturated(sim):
    """A commanded torque is what the actuator applies; beyond the robot.yaml limit it is
    saturated (l_elbow: 20 N m); the joint leaves the hold."""
    sim.reset("rest")
    sat = sim.command(["torso_yaw", "l_elbow"], [1.5, -100.0])
    np.testing.assert_allclose(sat, [1.5, -20.0])
    sim.step(1)
    eff = sim.joint_state().effort[sim.indices(["torso_yaw", "l_elbow"])]
    np.testing.assert_allclose(eff, [1.5, -20.0])
    assert sim.commanded[sim.indices(["torso_yaw", "l_elbow"])].all()
    assert sim.commanded.sum() == 2


@pytest.mark.parametrize("names,efforts,match", [
    (["l_elbow", "nose"], [1.0, 2.0], "nose"),
    (["l_elbow"], [float("nan")], "NaN"),
    (["l_elbow"], [float("inf")], "NaN or infinite"),
    (["l_elbow", "r_elbow"], [1.0], "2 names but 1"),
    (["l_elbow", "l_elbow"], [1.0, 1.0], "duplicate"),
])
def test_bad_command_rejected_and_nothing_changes(sim, names, efforts, match):
    """Unknown names, NaN/inf or mismatched lengths raise a clear error and leave the previous
    command in force."""
    sim.reset("rest")
    sim.command(["l_elbow"], [2.0])
    with pytest.raises(InvalidInput, match=match):
        sim.command(names, efforts)
    sim.step(1)
    assert sim.joint_state().effort[sim.indices(["l_elbow"])[0]] == pytest.approx(2.0)


def test_command_all_fast_path(sim):
    """command_all takes a full (n,) vector in joint_names order, saturated; wrong shapes
    and NaN are rejected."""
    sim.reset("rest")
    tau = np.full(sim.n, 100.0)
    out = sim.command_all(tau)
    np.testing.assert_allclose(out, sim.torque_limits)
    with pytest.raises(InvalidInput):
        sim.command_all(np.zeros(3))
    with pytest.raises(InvalidInput):
        sim.command_all(np.full(sim.n, np.nan))


def test_limit_torques_stay_stable(sim):
    """One second at saturated torques on every joint (into the joint limits) keeps the state
    finite and the joints within their limits plus a small penetration."""
    sim.reset("rest")
    sim.command_all(np.where(np.arange(sim.n) % 2 == 0, 1e3, -1e3))
    sim.step(1000)
    st = sim.joint_state()
    assert np.all(np.isfinite(st.position)) and np.all(np.isfinite(st.velocity))
    assert np.all(st.position > sim.lower - 0.05) and np.all(st.position < sim.upper + 0.05)


def test_gravity_without_hold_falls(sim):
    """With zero commanded torque the arms fall under gravity (the hold is really released)."""
    sim.reset("rest")
    i = sim.indices(["l_shoulder_pitch"])[0]
    q0 = sim.joint_state().position[i]
    sim.command_all(np.zeros(sim.n))
    sim.step(300)
    assert sim.joint_state().position[i] > q0 + 0.05  # the forearm swings down (pitch +)


def test_object_pose_and_errors(sim):
    """set_object_pose teleports an object (at rest); unknown objects, NaN and zero
    quaternions are rejected."""
    sim.reset("rest")
    sim.set_object_pose("cylinder", [-0.55, -0.3, -0.03], [1.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(sim.object_pose("cylinder").position, [-0.55, -0.3, -0.03])
    sim.step(200)
    np.testing.assert_allclose(sim.object_pose("cylinder").position, [-0.55, -0.3, -0.03],
                               atol=2e-3)  # standing on the table top (z = -0.09)
    with pytest.raises(UnknownName, match="box"):
        sim.set_object_pose("ball", [0, 0, 0])
    with pytest.raises(InvalidInput):
        sim.set_object_pose("box", [np.nan, 0, 0])
    with pytest.raises(InvalidInput):
        sim.set_object_pose("box", [0, 0, 0], [0, 0, 0, 0])
    sim.reset("rest")
    np.testing.assert_allclose(sim.object_pose("cylinder").position,
                               sim.config.cylinder_position, atol=1e-9)


def test_move_object_follows_simulated_time_and_stops_at_rest(sim):
    """move_object slides the cylinder on the table at its velocity in simulated time: at every
    step it is where start + v t says (within 1 mm), it stops at start + v duration and stays
    there at rest; a teleport ends a motion at once; a bad velocity, duration or end pose is
    refused and nothing moves."""
    sim.reset("rest")
    sim.set_object_pose("box", [-0.52, -0.40, -0.05])  # off the cylinder's way
    start, v = np.array([-0.44, -0.10, -0.03]), np.array([0.05, 0.20, 0.0])
    t0, t1 = sim.move_object("cylinder", start, v, 0.5)
    assert t0 == pytest.approx(sim.time) and t1 == pytest.approx(t0 + 0.5)
    for _ in range(10):
        sim.step(37)
        s = min(sim.time - t0, 0.5)
        np.testing.assert_allclose(sim.object_pose("cylinder").position, start + v * s,
                                   atol=1e-3)
    sim.step(500)
    end = sim.object_pose("cylinder").position
    np.testing.assert_allclose(end, start + v * 0.5, atol=2e-3)
    sim.step(300)
    np.testing.assert_allclose(sim.object_pose("cylinder").position, end, atol=1e-4)
    # a teleport ends the motion
    sim.move_object("cylinder", start, v, 0.5)
    sim.set_object_pose("cylinder", start)
    sim.step(200)
    np.testing.assert_allclose(sim.object_pose("cylinder").position, start, atol=2e-3)
    p0 = sim.object_pose("cylinder").position
    for velocity, duration, match in (([0.0, np.nan, 0.0], 1.0, "velocity"),
                                      ([0.0, 0.1], 1.0, "velocity"),
                                      ([0.0, 0.1, 0.0], 0.0, "duration"),
                                      ([0.0, 0.1, 0.0], 1e3, "duration"),
                                      ([0.0, 0.0, -1.0], 1.0, "below the floor")):
        with pytest.raises(InvalidInput, match=match):
            sim.move_object("cylinder", start, velocity, duration)
    with pytest.raises(UnknownName):
        sim.move_object("ball", start, v, 0.5)
    sim.step(100)
    np.testing.assert_allclose(sim.object_pose("cylinder").position, p0, atol=1e-3)


def test_apply_wrench_moves_object_and_validates(sim):
    """A scripted upward force larger than the box's weight lifts it; bad targets, NaN and
    non-positive durations are rejected."""
    sim.reset("rest")
    z0 = sim.object_pose("box").position[2]
    sim.apply_wrench("box", [0.0, 0.0, 2 * sim.config.box_mass * 9.81], [0, 0, 0], 0.2)
    sim.step(200)
    assert sim.object_pose("box").position[2] > z0 + 0.05
    with pytest.raises(UnknownName):
        sim.apply_wrench("no_such_frame", [0, 0, 1], [0, 0, 0], 1.0)
    with pytest.raises(InvalidInput):
        sim.apply_wrench("box", [0, np.nan, 1], [0, 0, 0], 1.0)
    with pytest.raises(InvalidInput):
        sim.apply_wrench("box", [0, 0, 1], [0, 0, 0], 0.0)


def test_reset_keeps_time_monotonic(sim):
    """A reset does not rewind simulated time (/clock never goes back)."""
    sim.step(10)
    t = sim.time
    sim.reset("zero")
    assert sim.time == t
    with pytest.raises(UnknownName):
        sim.reset("dance")


def test_forearm_stops_on_the_chest(sim):
    """Arms collide with the torso: swinging the left forearm inwards (shoulder yaw torque)
    stops it on the chest, well before the joint limit, with a chest/forearm contact."""
    sim.reset(q={"l_shoulder_pitch": -0.3, "l_shoulder_roll": 0.15, "l_shoulder_yaw": 0.6,
                 "l_elbow": 1.85})
    i = sim.indices(["l_shoulder_yaw"])[0]
    sim.command(["l_shoulder_yaw"], [6.0])
    sim.step(800)
    m, d = sim.model, sim.data
    pairs = {frozenset((m.geom(c.geom1).name, m.geom(c.geom2).name)) for c in d.contact[:d.ncon]}
    assert frozenset(("chest_collision", "l_forearm_collision")) in pairs or \
        frozenset(("chest_collision", "l_hand_collision")) in pairs
    assert sim.joint_state().position[i] < sim.upper[i] - 0.15


def test_the_two_arms_collide_with_each_other(sim):
    """The left and right arms collide: hands brought together in front of the chest and
    pushed inwards (shoulder yaw torques) stop on each other, and self_contacts reports the
    arm-arm contact (left link first, the force the right hand exerts on the left one points
    to the left, -y); apart at rest, there is no self contact."""
    sim.reset("rest")
    sim.step(50)
    assert sim.self_contacts() == []
    q = {}
    for s in "lr":
        q.update({f"{s}_shoulder_pitch": -0.8, f"{s}_shoulder_roll": 0.45,
                  f"{s}_shoulder_yaw": 0.5, f"{s}_elbow": 1.4})
    sim.reset(q=q)
    assert sim.self_contacts() == []
    sim.command(["l_shoulder_yaw", "r_shoulder_yaw"], [4.0, 4.0])
    sim.step(300)
    contacts = sim.self_contacts()
    arm_arm = [c for c in contacts if c.kind == "arm-arm"]
    assert arm_arm
    for c in arm_arm:
        assert c.body1.startswith("l_") and c.body2.startswith("r_")
        assert c.normal_force > 0.0 and c.depth >= 0.0
    total = np.sum([c.force for c in arm_arm], axis=0)
    assert total[1] < -1.0  # the right hand pushes the left one towards the left
    # the hands did not pass through each other: the left hand stays left of the right one
    left = sim.frame_pose("l_hand_dh_frame").position[1]
    right = sim.frame_pose("r_hand_dh_frame").position[1]
    assert left < right


def test_object_contacts_report_the_hand_on_the_cylinder(sim):
    """object_contacts is empty while nothing touches an object; with the cylinder teleported
    onto the right hand, it reports the right arm's links touching the cylinder (not grasped,
    a positive normal force), and none of them is a self contact."""
    sim.reset("rest")
    sim.step(50)
    assert sim.object_contacts() == []
    hand = sim.frame_pose("r_hand_dh_frame").position
    sim.set_object_pose("cylinder", hand + [0.0, 0.0, 0.09])
    seen = []
    for _ in range(100):
        sim.step(5)
        seen += sim.object_contacts()
    assert seen and all(c.object == "cylinder" and not c.grasped for c in seen)
    assert all(c.body.startswith("r_") and c.arm == "right" for c in seen)
    assert max(c.normal_force for c in seen) > 0.0
    assert all("cylinder" not in (c.body1, c.body2) for c in sim.self_contacts())


@pytest.mark.parametrize("target, force, torque, duration, match", [
    ("box", [1e6, 0, 0], [0, 0, 0], 0.2, r"\|force\| = 1e\+06 N is beyond max_wrench_force"),
    ("r_hand", [0, 0, 5], [0, 20, 0], 1.0, r"\|torque\| = 20 N m is beyond max_wrench_torque"),
    ("box", [1, 0, 0], [0, 0, 0], 1e9, r"duration must be in \(0, 60\] s"),
])
def test_unphysical_wrench_rejected_and_nothing_applied(sim, target, force, torque, duration,
                                                        match):
    """The issue's requests (1e6 N on the box, a 1e9 s duration) and a 20 N m torque are
    refused with a message naming the bound; nothing is applied (the box stays put)."""
    sim.reset("rest")
    p0 = sim.object_pose("box").position
    with pytest.raises(InvalidInput, match=match):
        sim.apply_wrench(target, force, torque, duration)
    sim.step(200)
    np.testing.assert_allclose(sim.object_pose("box").position, p0, atol=1e-3)


def test_object_pose_out_of_the_workspace_rejected(sim):
    """An object 1e6 m away or below the floor is refused with a message; it stays put."""
    sim.reset("rest")
    p0 = sim.object_pose("cylinder").position
    with pytest.raises(InvalidInput, match="object_workspace_radius 1.5 m"):
        sim.set_object_pose("cylinder", [1e6, 0.0, 0.0])
    with pytest.raises(InvalidInput, match="below the floor"):
        sim.set_object_pose("cylinder", [-0.3, 0.0, -1.0])
    np.testing.assert_allclose(sim.object_pose("cylinder").position, p0, atol=1e-9)


@pytest.fixture(scope="module")
def unbounded_sim():
    """A simulator that accepts the issue's 1e6 N push (bounds raised on purpose)."""
    from icub_sim_bridge import SimConfig, Simulator

    return Simulator(SimConfig(cameras_enabled=False, max_wrench_force=1e7))


@pytest.mark.parametrize("target", ["r_hand_dh_frame", "box"])
def test_divergence_recovered_once_time_monotonic(unbounded_sim, target):
    """A 1e6 N push makes the physics diverge: it is detected and recovered from once (not a
    reset loop), simulated time never goes back, the robot is back at the last good state
    within its joint limits and on hold, the push is cleared (the box is back on the table)."""
    sim = unbounded_sim
    sim.reset("rest")
    sim.step(250)
    rest = sim.joint_state().position
    box = sim.object_pose("box").position
    before = sim.divergences
    sim.apply_wrench(target, [1e6, 0.0, 0.0], [0.0, 0.0, 0.0], 0.2)
    times = []
    for _ in range(1000):
        sim.step()
        times.append(sim.time)
    assert sim.divergences == before + 1
    d = sim.last_divergence
    assert "divergence_speed" in d.reason and d.restored_time <= d.time
    assert np.all(np.diff(times) > 0)  # never back (MuJoCo's auto-reset rewinds to 0)
    st = sim.joint_state()
    assert np.all(st.position >= sim.lower - 0.01) and np.all(st.position <= sim.upper + 0.01)
    np.testing.assert_allclose(st.position, rest, atol=0.02)
    assert sim.holding
    np.testing.assert_allclose(sim.object_pose("box").position, box, atol=1e-3)


def test_hold_keeps_the_posture_and_a_command_releases_it(sim):
    """hold() (the fallback when commands stop) keeps the commanded joints where they are
    against gravity; the next command hands the joints it names back to the torque."""
    sim.reset("rest")
    sim.command_all(np.zeros(sim.n))  # limp: the arms start to fall
    sim.step(50)
    sim.hold()
    assert sim.holding
    q = sim.joint_state().position
    sim.step(1000)
    np.testing.assert_allclose(sim.joint_state().position, q, atol=0.02)
    i = sim.indices(["l_shoulder_pitch"])[0]
    sim.command(["l_shoulder_pitch"], [0.0])
    assert not sim.holding and sim.commanded.sum() == 1
    sim.step(300)
    assert sim.joint_state().position[i] > q[i] + 0.05  # falls again: released
