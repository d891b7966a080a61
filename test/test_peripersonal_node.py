"""The peripersonal_space node over DDS (started through its script with a small pair of
maps): reach check, allocation, empty area, imagined pair plans, the map cloud, the CLI verbs,
and bad inputs answered with a clear message while the node stays up."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

from icub_pmp.peripersonal import PeripersonalSpace
from icub_pmp.testing import NodeGraph, repo_root

ENV_SH = str(repo_root() / "scripts" / "env.sh")


@pytest.fixture(scope="module")
def maps_dir(tmp_path_factory):
    """Small maps (2,000 babbles per arm), saved as the node loads them."""
    d = tmp_path_factory.mktemp("peri_maps")
    PeripersonalSpace.grow(2000, seed=1).save(d)
    return d


@pytest.fixture(scope="module")
def node(maps_dir, ros_domain_id):
    params = {"peripersonal_space": {"use_sim_time": False, "maps_dir": str(maps_dir),
                                     "grow_if_missing": False}}
    with NodeGraph(["peripersonal_space"], params) as graph:
        yield graph


def _call(probe, name, srv, **fields):
    return probe.call(name, srv, srv.Request(**fields), timeout=120.0)


def _pt(x, y, z):
    from geometry_msgs.msg import Point

    return Point(x=float(x), y=float(y), z=float(z))


def _wait_loaded(probe):
    from icub_interfaces.srv import CheckReach

    for _ in range(60):
        r = _call(probe, "/peripersonal/check_reach", CheckReach, points=[_pt(-0.3, 0.0, 0.0)])
        if r.success:
            return
        assert "not loaded yet" in r.message, r.message
        probe.wait_for(lambda: False, 1.0)
    raise AssertionError("maps not loaded after 60 s")


def test_no_maps_answers_not_loaded_and_reload_loads_them(ros_domain_id, tmp_path, maps_dir,
                                                          ros_probe):
    """(First in the file: a second node with the same services must not run beside it.)"""
    import shutil

    from std_srvs.srv import Trigger

    from icub_interfaces.srv import AllocateObjects

    empty = tmp_path / "maps"
    params = {"peripersonal_space": {"use_sim_time": False, "maps_dir": str(empty),
                                     "grow_if_missing": False}}
    with NodeGraph(["peripersonal_space"], params):
        for _ in range(30):  # "not loaded yet" until the loader has looked in maps_dir
            r = _call(ros_probe, "/peripersonal/allocate", AllocateObjects,
                      objects=[_pt(-0.3, 0.0, 0.0)])
            assert not r.success
            if "no maps loaded" in r.message:
                break
            ros_probe.wait_for(lambda: False, 1.0)
        assert "no maps loaded" in r.message and "reload" in r.message, r.message
        shutil.copytree(maps_dir, empty)
        t = ros_probe.call("/peripersonal/reload", Trigger, Trigger.Request(), timeout=60.0)
        assert t.success, t.message
        r = _call(ros_probe, "/peripersonal/allocate", AllocateObjects,
                  objects=[_pt(-0.3, 0.0, 0.0)])
        assert r.success, r.message


def test_queries_answer_what_the_maps_say(node, ros_probe, maps_dir):
    from icub_interfaces.srv import AllocateObjects, CheckReach, FindEmptyArea

    _wait_loaded(ros_probe)
    space = PeripersonalSpace.load(maps_dir)
    left_only = space.maps["left"].neurons[np.argmin(space.maps["left"].neurons[:, 1])]
    right_only = space.maps["right"].neurons[np.argmax(space.maps["right"].neurons[:, 1])]
    r = _call(ros_probe, "/peripersonal/check_reach", CheckReach,
              points=[_pt(*left_only), _pt(*right_only), _pt(1.0, 1.0, 1.0)])
    assert r.success, r.message
    assert list(r.arms) == ["left"] * 3 + ["right"] * 3
    assert list(r.inside) == [True, False, False, False, True, False]
    assert r.reward[0] > 0 and r.reward[4] > 0 and r.reward[2] == 0.0
    a = _call(ros_probe, "/peripersonal/allocate", AllocateObjects,
              objects=[_pt(*left_only), _pt(*right_only), _pt(1.0, 1.0, 1.0)])
    assert a.success, a.message
    assert list(a.arm) == ["left", "right", "none"] and list(a.round) == [0, 0, -1]
    obj = space.shared.neurons("left")
    assert len(obj) > 0
    o = space.maps["left"].neurons[obj[len(obj) // 2]]
    e = _call(ros_probe, "/peripersonal/empty_area", FindEmptyArea, objects=[_pt(*o)],
              arm="left")
    assert e.success, e.message
    p = np.array([e.point.x, e.point.y, e.point.z])
    assert np.linalg.norm(p - o) > 0.07 and e.clearance > 0.07


def test_plan_pair_predicts_crossing_reaches_and_clears_mirrored_ones(node, ros_probe):
    from icub_interfaces.srv import PlanPair

    _wait_loaded(ros_probe)
    cross = _call(ros_probe, "/peripersonal/plan_pair", PlanPair,
                  left_target=_pt(-0.28, 0.05, 0.05), right_target=_pt(-0.28, -0.05, 0.05))
    assert cross.success, cross.message
    assert cross.collides and cross.mode == "serial"
    assert len(cross.step_arm) >= 2 and cross.step_start[-1] > 0.0
    apart = _call(ros_probe, "/peripersonal/plan_pair", PlanPair,
                  left_target=_pt(-0.28, -0.2, 0.05), right_target=_pt(-0.28, 0.2, 0.05))
    assert apart.success, apart.message
    assert not apart.collides and apart.mode == "parallel"
    end = apart.left_path[-1]
    assert np.linalg.norm([end.x + 0.28, end.y + 0.2, end.z - 0.05]) < 0.01


def test_plan_pair_from_a_given_posture_chains_pairs(node, ros_probe):
    """A pair imagined from the ``final`` posture of a previous answer starts where that one
    ended (each arm's imagined path starts at its previous end), which the rest posture does
    not; ``final`` names every joint of the body model."""
    from icub_interfaces.srv import PlanPair

    _wait_loaded(ros_probe)
    first = _call(ros_probe, "/peripersonal/plan_pair", PlanPair,
                  left_target=_pt(-0.28, -0.2, 0.05), right_target=_pt(-0.28, 0.2, 0.05))
    assert first.success, first.message
    assert len(first.final.name) == len(first.final.position) > 14
    assert "l_elbow" in first.final.name and "r_elbow" in first.final.name
    second = _call(ros_probe, "/peripersonal/plan_pair", PlanPair,
                   left_target=_pt(-0.28, -0.2, 0.12), right_target=_pt(-0.28, 0.2, 0.12),
                   start=first.final)
    assert second.success, second.message
    for arm in ("left", "right"):
        end = getattr(first, f"{arm}_path")[-1]
        start = getattr(second, f"{arm}_path")[0]
        assert np.linalg.norm([start.x - end.x, start.y - end.y, start.z - end.z]) < 1e-3
    rest = _call(ros_probe, "/peripersonal/plan_pair", PlanPair,
                 left_target=_pt(-0.28, -0.2, 0.12), right_target=_pt(-0.28, 0.2, 0.12))
    s0, e = rest.left_path[0], first.left_path[-1]
    assert np.linalg.norm([s0.x - e.x, s0.y - e.y, s0.z - e.z]) > 0.02


@pytest.mark.parametrize("names, positions, words", [
    (["l_elbow", "no_such_joint"], [0.5, 0.1], "no_such_joint"),
    (["l_elbow", "r_elbow"], [0.5], "2 names but 1 positions"),
    (["l_elbow"], [float("nan")], "not finite"),
])
def test_bad_start_posture_gets_a_clear_message(node, ros_probe, names, positions, words):
    from sensor_msgs.msg import JointState

    from icub_interfaces.srv import PlanPair

    _wait_loaded(ros_probe)
    r = _call(ros_probe, "/peripersonal/plan_pair", PlanPair,
              left_target=_pt(-0.28, -0.2, 0.05), right_target=_pt(-0.28, 0.2, 0.05),
              start=JointState(name=names, position=positions))
    assert not r.success and words in r.message, r.message
    assert all(node.alive().values())


def test_map_cloud_is_latched_with_both_arms(node, ros_probe, maps_dir):
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import PointCloud2

    _wait_loaded(ros_probe)
    got = []
    qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
    ros_probe.node.create_subscription(PointCloud2, "/peripersonal/maps", got.append, qos)
    assert ros_probe.wait_for(lambda: bool(got), 30.0)
    cloud = np.frombuffer(bytes(got[0].data), dtype=np.float32).reshape(-1, 5)
    space = PeripersonalSpace.load(maps_dir)
    assert len(cloud) == space.maps["left"].size + space.maps["right"].size
    assert set(np.unique(cloud[:, 3])) == {0.0, 1.0} and cloud[:, 4].max() == 1.0


@pytest.mark.parametrize("srv, fields, words", [
    ("check", {"points": []}, "empty list"),
    ("check", {"points": [("nan", 0, 0)]}, "not finite"),
    ("check", {"points": [(-0.3, 0, 0)], "arm": "middle"}, "middle"),
    ("allocate", {"objects": []}, "empty list"),
    ("empty", {"objects": [], "arm": "left", "radius": -1.0}, "radius"),
    ("empty", {"objects": [], "arm": ""}, "arm"),
    ("pair", {"left_target": ("inf", 0, 0), "right_target": (-0.3, 0.1, 0)}, "left_target"),
    ("pair", {"left_target": (-0.3, -0.1, 0), "right_target": (-0.3, 0.1, 0),
              "first": "both"}, "both"),
])
def test_bad_requests_get_a_clear_message_and_the_node_stays_up(node, ros_probe, srv, fields,
                                                                words):
    from icub_interfaces.srv import AllocateObjects, CheckReach, FindEmptyArea, PlanPair

    _wait_loaded(ros_probe)
    name, cls = {"check": ("/peripersonal/check_reach", CheckReach),
                 "allocate": ("/peripersonal/allocate", AllocateObjects),
                 "empty": ("/peripersonal/empty_area", FindEmptyArea),
                 "pair": ("/peripersonal/plan_pair", PlanPair)}[srv]
    conv = {k: ([_pt(*map(float, p)) for p in v] if isinstance(v, list)
                else _pt(*map(float, v)) if isinstance(v, tuple) else v)
            for k, v in fields.items()}
    r = _call(ros_probe, name, cls, **conv)
    assert not r.success and words in r.message
    assert all(node.alive().values())


def test_cli_verbs(node, ros_probe):
    _wait_loaded(ros_probe)
    run = subprocess.run([ENV_SH, "icub", "peri", "plan-pair", "left=-0.28,0.05,0.05",
                          "right=-0.28,-0.05,0.05"], capture_output=True, text=True, timeout=180)
    assert run.returncode == 0, run.stderr
    assert "collides: true" in run.stdout and "mode: serial" in run.stdout
    run = subprocess.run([ENV_SH, "icub", "peri", "allocate", "-0.3,-0.25,0.0",
                          "-0.3,0.25,0.0"], capture_output=True, text=True, timeout=180)
    assert run.returncode == 0, run.stderr
    assert "rounds: 1" in run.stdout
    bad = subprocess.run([ENV_SH, "icub", "peri", "check", "-0.3,nan,0"], capture_output=True,
                         text=True, timeout=180)
    assert bad.returncode == 1 and "icub: error:" in bad.stderr and "Traceback" not in bad.stderr
