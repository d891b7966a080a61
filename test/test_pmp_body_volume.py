"""The obstacle fields keep the arm's collision hulls clear, not only the hand frame
(icub_pmp/pmp/body_volume.py, PmpNetwork's volumes, PmpPlanner's ``obstacle_body_links``)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from icub_pmp.errors import InvalidInput
from icub_pmp.peripersonal import ArmBodyModel
from icub_pmp.pmp import PmpConfig, PmpPlanner, ReachGoal
from icub_pmp.pmp.body_volume import BodySphere, BodyVolume, hull_distances
from icub_pmp.pmp.box_obstacle_field import BoxObstacleField

LINKS = ("hand", "wrist_1", "forearm")
#: the demo's obstacle scene (icub_pmp/demo/scenario.py, phase 5): the cylinder's box on the
#: table between the right hand's start and target [m, root_link]
START_UP = np.array([-0.22, 0.34, 0.12])
START = np.array([-0.36, 0.34, 0.04])
TARGET = np.array([-0.36, 0.0, 0.06])
#: a lower start and target, 2 cm above the cylinder's top: the hand frame alone passes
START_LOW = np.array([-0.36, 0.34, 0.02])
TARGET_LOW = np.array([-0.36, 0.02, 0.02])
CYLINDER = np.array([-0.36, 0.17, -0.03])
CLEARANCE = 0.02


@pytest.fixture(scope="module")
def planners():
    with_body = PmpPlanner(PmpConfig())
    hand_only = PmpPlanner(dataclasses.replace(PmpConfig(), obstacle_body_links=()),
                           provider=with_body.provider)
    return with_body, hand_only


@pytest.fixture(scope="module")
def hulls(planners):
    body = ArmBodyModel.from_urdf(planners[0].provider, links=LINKS)
    return body.hulls["right"]


def test_spheres_cover_the_link_hulls(planners, hulls):
    """Every surface sample of the hand's, wrist's and forearm's hulls lies inside one of the
    volume's spheres (so a sphere clearance bounds the hull's)."""
    vol = BodyVolume.from_urdf(planners[0].provider, "right", LINKS)
    for h in hulls:
        mine = vol.owner == vol.frames.index(h.frame)
        d = np.linalg.norm(h.points[:, None, :] - vol.centers[mine][None], axis=2)
        assert np.all(np.min(d - vol.radii[mine][None], axis=1) <= 1e-9), h.frame


def test_sphere_torques_are_the_transposed_jacobian_of_the_sphere_centres(planners):
    """``torques`` = sum J_i^T f_i, checked against finite differences of the centres."""
    p = planners[0].provider
    vol = BodyVolume([BodySphere("r_hand", np.array([0.05, -0.02, 0.01]), 0.02),
                      BodySphere("r_forearm", np.array([-0.1, 0.0, 0.02]), 0.04)])
    rng = np.random.default_rng(0)
    q = np.clip(rng.normal(0, 0.3, p.nq), p.lower, p.upper)
    f = rng.normal(size=(2, 3))
    tau = vol.torques(p.kinematics(q, vol.frames), f)
    eps = 1e-6
    for j in range(p.nq):
        dq = np.zeros(p.nq)
        dq[j] = eps
        num = (vol.positions(p.kinematics(q + dq, vol.frames))
               - vol.positions(p.kinematics(q - dq, vol.frames))) / (2 * eps)
        assert abs(float(np.sum(num * f)) - tau[j]) < 1e-5
        assert np.allclose(vol.jacobians(p.kinematics(q, vol.frames))[:, :, j], num, atol=1e-6)


def test_sphere_field_stiffness_is_the_derivative_of_its_force():
    """``sphere_forces``: a sphere of radius r feels the field at clearance rho - r, and the
    stiffness it reports is -d|F|/d rho (finite differences), 0 beyond the influence."""
    ob = BoxObstacleField([0.0, 0.0, 0.0], np.eye(3), [0.05, 0.05, 0.05], influence=0.05,
                          inflation=0.02)
    x = np.array([[0.1, 0.0, 0.0], [0.0, 0.2, 0.0]])
    r = np.array([0.01, 0.01])
    f, rho, k = ob.sphere_forces(x, r)
    assert np.allclose(rho, [0.1 - 0.05 - 0.02 - 0.01, 0.2 - 0.05 - 0.02 - 0.01])
    assert np.allclose(f[0], ob.force(x[0] - [0.01, 0.0, 0.0]))
    assert np.allclose(f[1], 0.0) and k[1] == 0.0
    eps = 1e-7
    fp, _, _ = ob.sphere_forces(x[:1] + [eps, 0.0, 0.0], r[:1])
    fm, _, _ = ob.sphere_forces(x[:1] - [eps, 0.0, 0.0], r[:1])
    num = -(np.linalg.norm(fp) - np.linalg.norm(fm)) / (2 * eps)
    assert abs(num - k[0]) < 1e-4 * abs(k[0])


@pytest.mark.parametrize("bad, match", [
    (lambda: BodyVolume([]), "at least one sphere"),
    (lambda: BodyVolume([BodySphere("r_hand", np.array([0.0, np.nan, 0.0]), 0.1)]), "centre"),
    (lambda: BodyVolume([BodySphere("r_hand", np.zeros(3), 0.0)]), "radius"),
])
def test_bad_spheres_are_rejected_by_name(bad, match):
    """A sphere without a finite centre or with a radius <= 0 is rejected, naming it."""
    with pytest.raises(InvalidInput, match=match):
        bad()


def test_the_fingers_keep_the_clearance_the_hand_frame_alone_did_not(planners, hulls):
    """The demo's cylinder, the hand 2 cm above its top on either side: with only the hand
    frame kept 2 cm clear, the hand's hull (fingers, thumb) goes through the obstacle; with
    the body volume every hull sample of the hand, wrist and forearm stays at least the
    clearance away along the whole sampled plan, and the hand still arrives."""
    obstacle = BoxObstacleField(CYLINDER, np.eye(3), [0.03, 0.03, 0.06], influence=0.05,
                                inflation=CLEARANCE + 0.005)
    results = {}
    for name, planner in zip(("body", "hand"), planners):
        up = planner.plan(ReachGoal(targets={"right": START_UP}, tau=1.5))
        start = planner.plan(ReachGoal(targets={"right": START_LOW}, tau=1.5), up.q_final)
        plan = planner.plan(ReachGoal(targets={"right": TARGET_LOW}, tau=3.0,
                                      obstacles=(obstacle,)), start.q_final)
        results[name] = (plan, hull_distances(
            planner.provider, hulls, plan.configurations(planner.provider.joint_names),
            obstacle))
    hand_plan, hand_dist = results["hand"]
    assert hand_plan.success and hand_dist.min() < 0.0  # the hull enters the obstacle
    plan, dist = results["body"]
    assert plan.success, plan.message
    assert plan.residuals["right"] < 1e-3
    assert dist.min() >= CLEARANCE, dist.min()
    assert plan.obstacle_clearance <= dist.min() + 1e-9  # the spheres bound the hulls


def test_the_idle_left_arm_stays_within_its_velocity_limits(planners):
    """The demo's obstacle reach moves the trunk under the idle left arm, which holds its hand
    (decision 0056): no idle joint exceeds its velocity or acceleration limit at the asked tau
    (an idle wrist once jumped 1.6 rad in one sample, slowing the 3 s reach to 137 s)."""
    planner = PmpPlanner(dataclasses.replace(PmpConfig(), hold_idle_hands=True),
                         provider=planners[0].provider)
    obstacle = BoxObstacleField(CYLINDER, np.eye(3), [0.03, 0.03, 0.06], influence=0.05,
                                inflation=CLEARANCE + 0.005)
    up = planner.plan(ReachGoal(targets={"right": START_UP}, tau=1.5))
    start = planner.plan(ReachGoal(targets={"right": START}, tau=1.5), up.q_final)
    plan = planner.plan(ReachGoal(targets={"right": TARGET}, tau=3.0, obstacles=(obstacle,)),
                        start.q_final)
    assert plan.success, plan.message
    idle = [i for i, j in enumerate(plan.joint_names) if j.startswith("l_")]
    assert idle  # the left arm is in the trajectory
    speed = np.abs(np.diff(plan.positions[:, idle], axis=0)) / np.diff(plan.t)[:, None]
    vmax = np.array([planner.spec.velocity_limit(plan.joint_names[i]) for i in idle])
    assert np.all(speed <= vmax), speed.max(axis=0)
    acc = np.abs(np.diff(speed, axis=0)) / np.diff(plan.t)[1:, None]
    amax = np.array([planner.spec.acceleration_limit(plan.joint_names[i]) for i in idle])
    assert np.all(acc <= amax), acc.max(axis=0)


def test_no_room_for_the_arm_falls_back_to_the_hand_frames_and_says_so(planners, hulls):
    """A sphere where the hand passes half way up to its target, which is where the forearm
    ends (decision 0063): with the arm's volume kept clear the plan stalls against the sphere,
    so the planner keeps the hand frame clear only (as before the volumes): the hand arrives,
    its path keeps the clearance, and the answer says the volume was not kept and how close
    the arm comes (the hulls' true distance is no smaller)."""
    from icub_pmp.pmp.obstacle_field import ObstacleField

    planner = planners[0]
    target = np.array([-0.28, 0.10, 0.20])
    free = planner.plan(ReachGoal(targets={"right": target}, use_torso=False))
    path = free.hand_paths["right"]
    centre, radius = path[len(path) // 2], 0.03
    sphere = ObstacleField(centre, radius, influence=0.05, inflation=CLEARANCE + 0.005)
    plan = planner.plan(ReachGoal(targets={"right": target}, use_torso=False,
                                  obstacles=(sphere,)))
    assert plan.success and plan.residuals["right"] < 1e-3, plan.message
    hand = np.linalg.norm(plan.hand_paths["right"] - centre, axis=1) - radius
    assert hand.min() >= CLEARANCE - 1e-3
    assert plan.hand_frames_only and "hand frames only" in plan.message, plan.message
    said = float(plan.message.split("the arm's volume comes within ")[1].split(" mm")[0])
    assert said < CLEARANCE * 1e3
    dist = hull_distances(planner.provider, hulls,
                          plan.configurations(planner.provider.joint_names), sphere)
    assert dist.min() * 1e3 >= said - 0.1  # the spheres bound the hulls
