"""The demo's squeeze (phase 2) and its phase selection, without a graph: the force loop's
compliance moves the hands as the joint springs need, its force target pushes each palm
onto its side of the box, the palms' contact patches are measured on the hands' collision
hulls, and ``--phases`` picks phases (and the nodes they need) or refuses unknown names."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.demo import scenario
from icub_pmp.kinematics import IcubModel


@pytest.fixture(scope="module")
def model() -> IcubModel:
    return IcubModel()


def test_bimanual_compliance_predicts_how_far_the_springs_let_the_hands_go(model):
    """Forces on both hand frames deflect the joint springs by ``K^-1 J^T F``; the hands then
    move by ``C F`` (C = J K^-1 J^T, the torso shared): checked against forward kinematics of
    the deflected posture, for the left hand alone and for a squeeze of both."""
    spec = model.spec
    joints = list(spec.torso_joints) + list(spec.arm_joints("left")) + list(
        spec.arm_joints("right"))
    stiffness = scenario.joint_stiffness(joints)
    q = model.posture("rest")
    C = scenario.bimanual_compliance(model, q, stiffness)
    assert C.shape == (6, 6) and np.allclose(C, C.T)
    idx = model.indices(joints)
    k = np.array([stiffness[j] for j in joints])
    frames = [spec.hand_frame(h) for h in ("left", "right")]
    for F in (np.r_[0.0, 0.0, 2.0, 0.0, 0.0, 0.0], np.r_[0.0, -1.0, 0.0, 0.0, 1.0, 0.0]):
        J = np.vstack([model.frame_jacobian(q, f)[:3, idx] for f in frames])
        dq = np.zeros_like(q)
        dq[idx] = (J.T @ F) / k
        moved = np.concatenate([model.frame_position(q + dq, f) - model.frame_position(q, f)
                                for f in frames])
        assert np.linalg.norm(moved - C @ F) < 0.02 * np.linalg.norm(moved) + 1e-6
        assert np.linalg.norm(moved) > 1e-4  # the forces do move the hands


def test_squeeze_target_pushes_each_palm_onto_the_box_and_nothing_else():
    """The box pushing the left hand to -y and the right to +y with SQUEEZE_FORCE is no
    error; a hand hanging on the box (the box holding it up) is an error along z only."""
    f = scenario.SQUEEZE_FORCE
    err = scenario.squeeze_force_error({"left": [0.0, -f, 0.0], "right": [0.0, f, 0.0]})
    assert all(np.allclose(e, 0.0) for e in err.values())
    err = scenario.squeeze_force_error({"left": [0.0, -f, 7.0], "right": [0.0, f - 3.0, 0.0]})
    assert np.allclose(err["left"], [0.0, 0.0, 7.0])
    assert np.allclose(err["right"], [0.0, -3.0, 0.0])  # too weak: push further in (-y)


def test_palm_contact_offsets_measure_the_innermost_patch_of_each_hand(model):
    """The offsets are the hulls' innermost patches (along the hand-to-hand axis) against the
    point above the box centre: moving the box moves them by as much, the other way; the
    patch lies within the hull's points nearest to the box."""
    q = model.posture("rest")
    box = np.array([-0.33, 0.0, -0.05])
    off = scenario.palm_contact_offsets(model, q, box)
    moved = scenario.palm_contact_offsets(model, q, box + [0.02, 0.0, -0.01])
    for h, link, inward in (("left", "l_hand", 1.0), ("right", "r_hand", -1.0)):
        assert off[h][1] == 0.0
        assert np.allclose(moved[h], off[h] - [0.02, 0.0, -0.01])
        hull = scenario._hand_hulls()[link]
        pose = model.frame_pose(q, link)
        pts = hull.points @ np.asarray(pose.rotation).T + np.asarray(pose.translation)
        patch = box + [0.0, 0.0, scenario.SQUEEZE_CONTACT_HEIGHT] + off[h]
        # x and z of the patch lie among the hull's points nearest to the box (1 cm deep)
        near = pts[inward * pts[:, 1] >= (inward * pts[:, 1]).max() - 0.01]
        assert near[:, 0].min() <= patch[0] <= near[:, 0].max()
        assert near[:, 2].min() <= patch[2] <= near[:, 2].max()


def test_phases_are_selected_by_name_and_unknown_ones_refused(capsys):
    """``--phases`` keeps the demo's order, ``all`` is every phase, a typo is a one-line
    error naming it (exit status 2, no graph started); the bimanual phases alone run on a
    graph without cameras, gaze, segmenter or Cartesian solver."""
    assert scenario.parse_phases("press,bimanual") == ("bimanual", "press")
    assert scenario.parse_phases("all") == scenario.PHASES
    with pytest.raises(ValueError, match="unknown phase.*transprot"):
        scenario.parse_phases("bimanual,transprot")
    with pytest.raises(SystemExit) as exc:
        scenario.main(["--phases", "transprot"])
    assert exc.value.code == 2
    assert "unknown phase(s) transprot" in capsys.readouterr().err
    params = scenario.graph_parameters("icub")
    nodes, p = scenario.phase_graph(("bimanual",), params)
    assert nodes == ["sim_bridge", "wrench_estimator", "impedance_controller", "pmp_planner",
                     "robot_state_publisher"]
    assert p["sim_bridge"]["cameras_enabled"] is False
    assert "/gaze/look_at" not in scenario.ready_services(nodes)
    nodes, p = scenario.phase_graph(scenario.PHASES, params)
    assert nodes == scenario.GRAPH and "cameras_enabled" not in p["sim_bridge"]
    assert "/gaze/look_at" in scenario.ready_services(nodes)
