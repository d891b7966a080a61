"""pmp_planner with ``jacobian_source: learned`` over DDS: the planner started as a user starts
it, on a body network learned from (pinocchio) babbles of the right arm."""

from __future__ import annotations

import time

import numpy as np
import pytest

from icub_pmp.body_schema import BodyNetwork, LmTrainer, LmTrainerConfig
from icub_pmp.kinematics import IcubModel, RobotSpec
from icub_pmp.peripersonal import analytic_babbling
from icub_pmp.testing import NodeProcess, repo_root


@pytest.fixture(scope="module")
def model_file(tmp_path_factory):
    """A right-arm body network (3000 babbles, 25 iterations of the default lm-normal with a
    float32 curvature: a few mm RMSE)."""
    b = analytic_babbling("right", 3000, seed=21)
    spec = RobotSpec.load()
    urdf = IcubModel(spec)
    idx = urdf.indices(b.joint_names)
    net, _ = BodyNetwork.train("right", b.joint_names, b.q, b.hand, urdf.lower[idx],
                               urdf.upper[idx], spec.hand_frame("right"),
                               trainer=LmTrainer(LmTrainerConfig(max_evaluations=25,
                                                                 curvature_dtype="float32")))
    return net.save(tmp_path_factory.mktemp("models") / "right.npz")


@pytest.fixture(scope="module")
def node(ros_domain_id, model_file):
    proc = NodeProcess(command=[str(repo_root() / "scripts/pmp_planner.sh"), "--ros-args",
                                "-p", "posture_memory_size:=3000",
                                "-p", "jacobian_source:=learned",
                                "-p", f"learned_model_right:={model_file}"])
    try:
        yield proc
    finally:
        proc.stop()


def test_learned_planner_reaches_with_the_true_hand(node, ros_probe):
    """/pmp/reach (simulate only, from rest) on the learned Jacobian: planned; the URDF hand at
    the planned final posture ends within 2 cm of each target; a left-hand goal (no left model)
    is refused with a message naming the frame."""
    from icub_interfaces.srv import Reach

    assert ros_probe.wait_for_service("/pmp/reach", Reach, 120), node.output()
    spec = RobotSpec.load()
    urdf = IcubModel(spec)
    rest = urdf.posture("rest")
    errors = []
    for target in ([-0.30, 0.15, 0.05], [-0.25, 0.20, 0.10], [-0.28, 0.10, 0.0]):
        req = Reach.Request(hands=["right"], simulate_only=True)
        p = req.right_target.pose.position
        p.x, p.y, p.z = target
        res = ros_probe.call("/pmp/reach", Reach, req, timeout=120)
        assert res.success, res.message
        q = urdf.q_from_dict(dict(zip(res.trajectory.joint_names,
                                      res.trajectory.points[-1].positions)), default=rest)
        errors.append(np.linalg.norm(urdf.frame_position(q, "r_hand_dh_frame") - target))
    assert max(errors) < 0.02, errors
    left = Reach.Request(hands=["left"], simulate_only=True)
    left.left_target.pose.position.x = -0.3
    res = ros_probe.call("/pmp/reach", Reach, left, timeout=60)
    assert not res.success and "l_hand_dh_frame" in res.message


def test_missing_model_file_stops_the_node_with_a_message(ros_domain_id, tmp_path):
    """A learned model path that does not exist: the node exits with a one-line error naming
    the file (no traceback)."""
    proc = NodeProcess(command=[str(repo_root() / "scripts/pmp_planner.sh"), "--ros-args",
                                "-p", "jacobian_source:=learned",
                                "-p", f"learned_model_right:={tmp_path / 'none.npz'}"])
    try:
        deadline = time.monotonic() + 120
        while proc.alive() and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not proc.alive()
        out = proc.output()
        assert "none.npz" in out and "Traceback" not in out, out
    finally:
        proc.stop()
