"""The body_schema node over DDS in the lockstep graph (sim_bridge with cameras +
impedance_controller + gaze_controller + body_schema, started through their scripts): a short
babbling run produces a dataset a learner can use, with the ground truth kept apart."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.body_schema import LEARNER_FIELDS, load_dataset
from icub_pmp.kinematics import IcubModel, RobotSpec
from icub_pmp.testing import NodeGraph

pytestmark = pytest.mark.slow

GRAPH = ["sim_bridge", "impedance_controller", "gaze_controller", "body_schema"]
#: samples of the babbling run: each costs about 2 s of wall time in the lockstep graph with
#: cameras (one or more attempts); 12 are enough for every claim below (shapes, limits, the
#: median triangulation error); longer runs are `icub babble`'s, measured by
#: bench/body_schema.py --dataset (decision 0027)
SAMPLES = 12


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("babbling")


@pytest.fixture(scope="module")
def graph(ros_domain_id, data_dir):
    params = {
        "sim_bridge": {"mode": "lockstep"},
        "impedance_controller": {"use_sim_time": True, "mode": "position"},
        "gaze_controller": {"use_sim_time": True, "wait_timeout": 120.0},
        "body_schema": {"use_sim_time": True, "data_dir": str(data_dir), "move_time": 0.8,
                        "settle_time": 0.3},
    }
    with NodeGraph(GRAPH, params) as g:
        yield g


def test_babbling_run_produces_a_dataset(graph, ros_probe, data_dir):
    """start_babbling for SAMPLES samples: progress reaches the budget and ends; the dataset
    holds them: the 7 right-arm joints within the URDF limits, head joints, pixels inside the
    images and triangulated hands within 3 cm (median) of the simulator's marker; the ground
    truth is stored apart from the learner's fields and is not a copy of what the robot saw;
    a second start while running is refused; bad requests are refused with a message."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    from icub_interfaces.msg import BabblingProgress
    from icub_interfaces.srv import StartBabbling

    assert ros_probe.wait_for_service("/body_schema/start_babbling", StartBabbling, 180), \
        graph.outputs()
    progress: list = []
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
    ros_probe.node.create_subscription(BabblingProgress, "/body_schema/progress",
                                       progress.append, qos)
    assert ros_probe.wait_for(
        lambda: ros_probe.node.count_subscribers("/joint_trajectory") >= 1
        and ros_probe.node.count_publishers("/joint_trajectory") >= 2, 120), \
        graph.outputs()

    bad = ros_probe.call("/body_schema/start_babbling", StartBabbling,
                         StartBabbling.Request(arm="middle", samples=3))
    assert not bad.success and "arm" in bad.message

    res = ros_probe.call("/body_schema/start_babbling", StartBabbling,
                         StartBabbling.Request(arm="right", samples=SAMPLES,
                                               dataset_name="dds_test"), timeout=60)
    assert res.success, res.message
    again = ros_probe.call("/body_schema/start_babbling", StartBabbling,
                           StartBabbling.Request(arm="right", samples=3))
    assert not again.success and "already running" in again.message

    done = ros_probe.wait_for(
        lambda: any((not m.active) and m.samples >= SAMPLES for m in progress), 1500)
    last = progress[-1] if progress else None
    assert done, (last, graph.outputs())
    assert last.visible_fraction > 0.3 and last.attempts >= SAMPLES, last
    assert last.rate_sim > 0 and last.rate_wall > 0

    data = load_dataset(res.dataset_path)
    spec = RobotSpec.load()
    model = IcubModel(spec)
    idx = model.indices(spec.right_arm_joints)
    assert set(data.learner) == set(LEARNER_FIELDS) and "ground_truth" not in data.learner
    q = data.learner["q"]
    assert q.shape == (SAMPLES, 7) and data.learner["head"].shape == (SAMPLES, 6)
    assert np.all(q >= model.lower[idx] - 0.05) and np.all(q <= model.upper[idx] + 0.05)
    px = data.learner["pixels"]
    assert px.shape == (SAMPLES, 4) and np.all(px >= 0) and np.all(px[:, [0, 2]] < 320)
    seen, truth = data.learner["hand_seen"], data.ground_truth
    err = np.linalg.norm(seen - truth, axis=1)
    assert np.median(err) < 0.03, err
    assert np.all(err > 0), "the learner's hand positions are the ground truth itself"
    assert data.meta["arm"] == "right" and data.meta["joint_names"] == list(spec.right_arm_joints)
    assert data.meta["evaluation_only"] == ["ground_truth"]
    assert data.meta["dropped"] == last.dropped and data.meta["samples"] == SAMPLES


def test_icub_babble_command(graph, ros_probe, data_dir):
    """``icub babble --arm right --samples 4 --name cli_run`` shows a progress bar, prints the
    dataset path, exits 0, and the dataset holds the 4 samples."""
    from icub_interfaces.srv import StartBabbling
    from icub_pmp.testing import run_icub

    assert ros_probe.wait_for_service("/body_schema/start_babbling", StartBabbling, 180)
    out = run_icub("babble", "--arm", "right", "--samples", "4", "--name", "cli_run",
                   timeout=900)
    assert out.returncode == 0, (out.stdout, out.stderr)
    assert "%" in out.stderr and "samples" in out.stderr
    path = data_dir / "cli_run.npz"
    assert f"dataset: {path}" in out.stdout, out.stdout
    assert load_dataset(path).learner["q"].shape == (4, 7)
