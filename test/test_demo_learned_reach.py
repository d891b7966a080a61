"""``python -m icub_pmp.demo.learned_reach`` as a user runs it: a body model learned from a short
babbling budget, one table target and the cylinder the eyes found reached by pmp_planner on the
learned Jacobian and on the URDF in the lockstep simulator, both judged in the physics (the
seen cylinder against its ground truth); bad input is a one-line error."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import pytest

from icub_pmp.config import repo_root

pytestmark = [pytest.mark.integration, pytest.mark.slow]


def _run(*args: str, timeout: float = 900.0) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "icub_pmp.demo.learned_reach", *args],
                          cwd=repo_root(), capture_output=True, text=True, timeout=timeout)


def _run_graph(*args: str, timeout: float = 2400.0) -> tuple[int | None, str]:
    """The demo with its graph, in a process group of its own (NodeProcess): past ``timeout``
    [s] (a loaded machine) it is interrupted with SIGINT, so it stops the nodes it started
    instead of leaving them behind. Returns the exit code (None: timed out) and its output."""
    from icub_pmp.graph import NodeProcess

    demo = NodeProcess(command=[sys.executable, "-m", "icub_pmp.demo.learned_reach", *args])
    try:
        rc = demo.proc.wait(timeout)
    except subprocess.TimeoutExpired:
        rc = None
    finally:
        demo.stop(timeout=120.0)
    return rc, demo.output()


def test_learned_and_analytic_reach_the_target_and_the_seen_object(tmp_path):
    """3,000 pinocchio babbles, 16 s of CPU of training. On the fixed target the learned
    planner's true hand ends within 1 cm in the physics, the analytic one within 5 mm. The
    cylinder moved across the table is seen still by the stereo segmenter, and both planners
    take the true hand within 2 cm of the point above the cylinder's true top (not the
    estimate's), the estimate within 1 cm of it; the summary holds both, and the learned model
    file it planned with."""
    out = tmp_path / "run"
    # 1,500 babbles and 8 s gave the learned hand 10.2 mm off in a check run (2026-12-04, load
    # 7-9): the bound is the model's, so the model gets the data and time to meet it.
    # the ideal robot: on the shipped icub one (friction, mass mismatch, 12-bit encoders) the
    # learned planner of this small model ended 16 mm off in a CI run (issue 17's note)
    rc, output = _run_graph("--babbles", "3000", "--budget", "16", "--targets", "1",
                            "--objects", "1", "--realism", "ideal", "--out", str(out))
    assert rc == 0, output[-6000:]
    s = json.loads((out / "summary.json").read_text())
    assert (out / "body_right.npz").is_file() and s["model"].endswith("body_right.npz")
    by = {r["planner"]: r for r in s["reaches"]}
    assert set(by) == {"learned", "analytic"}
    assert all(r["outcome"] in ("reached", "not_reached") for r in by.values()), by
    assert all(math.isfinite(r["true_error"]) for r in by.values())
    assert by["learned"]["true_error"] < 0.01, by
    assert by["analytic"]["true_error"] < 0.005, by
    seen = {r["planner"]: r for r in s["vision_reaches"]}
    assert set(seen) == {"learned", "analytic"}, seen
    # the same seen target for both: one estimate, the same goal
    assert seen["learned"]["goal"] == seen["analytic"]["goal"]
    assert seen["learned"]["target_error"] == seen["analytic"]["target_error"] <= 0.01, seen
    assert seen["learned"]["true_error"] <= 0.02, seen["learned"]
    assert seen["analytic"]["true_error"] <= 0.02, seen["analytic"]
    assert all(r["success"] for r in seen.values()), seen
    # the goal is above the cylinder that was seen, not a fixed point
    assert abs(seen["learned"]["goal"][1] - s["vision_reaches"][0]["object_position"][1]) < 0.03
    assert "object 0" in output and "learned" in output and "analytic" in output


def test_bad_input_is_a_one_line_error(tmp_path):
    """A missing model file, a model of the other arm, counts out of range and a NaN timeout:
    exit 2 naming the problem, no traceback, no graph started."""
    p = _run("--model", str(tmp_path / "none.npz"), "--out", str(tmp_path / "a"), timeout=120)
    assert p.returncode == 2 and "none.npz" in p.stderr and "Traceback" not in p.stderr, p.stderr
    from icub_pmp.body_schema import BodyNetwork, LmTrainer, LmTrainerConfig
    from icub_pmp.kinematics import IcubModel, RobotSpec
    from icub_pmp.peripersonal import analytic_babbling

    b = analytic_babbling("left", 200, seed=3)
    spec = RobotSpec.load()
    urdf = IcubModel(spec)
    idx = urdf.indices(b.joint_names)
    net, _ = BodyNetwork.train("left", b.joint_names, b.q, b.hand, urdf.lower[idx],
                               urdf.upper[idx], spec.hand_frame("left"), hidden=(8,),
                               trainer=LmTrainer(LmTrainerConfig(max_evaluations=3)))
    left = net.save(tmp_path / "left.npz")
    p = _run("--model", str(left), "--out", str(tmp_path / "b"), timeout=120)
    assert p.returncode == 2 and "left arm" in p.stderr and "Traceback" not in p.stderr, p.stderr
    for args, word in ((("--objects", "9"), "--objects"), (("--targets", "-1"), "--targets"),
                       (("--targets", "0", "--objects", "0"), "nothing to reach"),
                       (("--see-timeout", "nan"), "--see-timeout")):
        p = _run(*args, "--out", str(tmp_path / "c"), timeout=120)
        assert p.returncode == 2 and word in p.stderr and "Traceback" not in p.stderr, p.stderr
