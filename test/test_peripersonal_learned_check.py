"""The imagined collision check on body models learned from babbling (Bhat and Mohan 2018: the
reaches are imagined with the learned internal models; issue 19's "mental simulation with the
learned body models"): in the core and through the peripersonal_space node's
``jacobian_source: learned``."""

from __future__ import annotations

import time

import numpy as np
import pytest

from icub_pmp.body_schema import BodyNetwork, LmTrainer, LmTrainerConfig
from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics import IcubModel, RobotSpec
from icub_pmp.peripersonal import ImaginedCollisionCheck, PeripersonalSpace, analytic_babbling
from icub_pmp.testing import NodeGraph, NodeProcess, repo_root

CROSSING = {"left": np.array([-0.28, 0.05, 0.05]), "right": np.array([-0.28, -0.05, 0.05])}
MIRRORED = {"left": np.array([-0.28, -0.2, 0.05]), "right": np.array([-0.28, 0.2, 0.05])}


@pytest.fixture(scope="module")
def model_files(tmp_path_factory):
    """A body network per arm (3000 pinocchio babbles, 25 iterations of lm-normal: a few mm)."""
    d = tmp_path_factory.mktemp("models")
    spec = RobotSpec.load()
    urdf = IcubModel(spec)
    files = {}
    for arm, seed in (("left", 31), ("right", 21)):
        b = analytic_babbling(arm, 3000, seed=seed)
        idx = urdf.indices(b.joint_names)
        net, _ = BodyNetwork.train(arm, b.joint_names, b.q, b.hand, urdf.lower[idx],
                                   urdf.upper[idx], spec.hand_frame(arm),
                                   trainer=LmTrainer(LmTrainerConfig(
                                       max_evaluations=25, curvature_dtype="float32")))
        files[arm] = str(net.save(d / f"{arm}.npz"))
    return files


def test_learned_check_flags_crossing_reaches_and_clears_mirrored_ones(model_files):
    """Imagined on the learned models: the crossing pair collides (serial), the mirrored pair
    does not (parallel); the imagined hands end near the targets on the true (URDF) body."""
    check = ImaginedCollisionCheck.learned(model_files)
    assert type(check.planner.provider).__name__ == "LearnedJacobianProvider"
    cross = check.plan_pair(CROSSING)
    assert cross.verdict.collides and cross.schedule.mode == "serial"
    apart = check.plan_pair(MIRRORED)
    assert not apart.verdict.collides and apart.schedule.mode == "parallel"
    urdf = IcubModel()
    rest = urdf.posture("rest")
    for arm, plan in apart.plans.items():
        q = urdf.q_from_dict(dict(zip(plan.joint_names, plan.positions[-1])), default=rest)
        hand = urdf.frame_position(q, urdf.spec.hand_frame(arm))
        assert np.linalg.norm(hand - MIRRORED[arm]) < 0.02, (arm, hand)


def test_learned_check_needs_a_model_per_arm(model_files):
    with pytest.raises(InvalidInput, match="left"):
        ImaginedCollisionCheck.learned({"right": model_files["right"]})


def test_node_imagines_on_the_learned_models(ros_domain_id, ros_probe, model_files, tmp_path):
    """peripersonal_space with ``jacobian_source: learned``: /peripersonal/plan_pair says
    serial for the crossing pair and parallel for the mirrored one."""
    from geometry_msgs.msg import Point

    from icub_interfaces.srv import PlanPair

    PeripersonalSpace.grow(2000, seed=1).save(tmp_path)
    params = {"peripersonal_space": {"use_sim_time": False, "maps_dir": str(tmp_path),
                                     "grow_if_missing": False, "jacobian_source": "learned",
                                     "learned_model_left": model_files["left"],
                                     "learned_model_right": model_files["right"]}}
    with NodeGraph(["peripersonal_space"], params) as graph:
        assert ros_probe.wait_for_service("/peripersonal/plan_pair", PlanPair, 120), \
            graph.outputs()
        answers = {}
        for name, targets in (("crossing", CROSSING), ("mirrored", MIRRORED)):
            req = PlanPair.Request(left_target=Point(**dict(zip("xyz", targets["left"]))),
                                   right_target=Point(**dict(zip("xyz", targets["right"]))))
            answers[name] = ros_probe.call("/peripersonal/plan_pair", PlanPair, req, 120.0)
        assert all(a.success for a in answers.values()), [a.message for a in answers.values()]
        assert answers["crossing"].mode == "serial" and answers["mirrored"].mode == "parallel"
        assert "learned body models" in graph.outputs()


def test_node_with_a_missing_model_exits_with_a_message(ros_domain_id, tmp_path):
    """A learned model path that does not exist: the node exits with a one-line error naming
    the file (no traceback)."""
    proc = NodeProcess(command=[str(repo_root() / "scripts/run_node.sh"), "peripersonal_space",
                                "--ros-args", "-p", f"maps_dir:={tmp_path}",
                                "-p", "grow_if_missing:=false",
                                "-p", "jacobian_source:=learned",
                                "-p", f"learned_model_left:={tmp_path / 'none.npz'}",
                                "-p", f"learned_model_right:={tmp_path / 'none.npz'}"])
    try:
        assert proc.wait_for_output("none.npz", 120.0), proc.output()
        for _ in range(300):  # it exits after saying so
            if not proc.alive():
                break
            time.sleep(0.1)
        out = proc.output()
        assert not proc.alive() and "Traceback" not in out, out
    finally:
        proc.stop()
