"""``python -m icub_pmp.demo.learned_reach`` as a user runs it: a body model learned from a short
babbling budget, one table target reached by pmp_planner on the learned Jacobian and on the
URDF in the lockstep simulator, both judged on the true hand; bad input is a one-line error."""

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


def test_learned_and_analytic_reach_the_target_in_the_physics(tmp_path):
    """1,500 pinocchio babbles, 8 s of CPU of training: the learned planner's true hand ends
    within 1 cm of the target in the physics, the analytic one within 5 mm; the summary holds
    both, and the learned model file it planned with."""
    out = tmp_path / "run"
    p = _run("--babbles", "1500", "--budget", "8", "--targets", "1", "--out", str(out))
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    s = json.loads((out / "summary.json").read_text())
    assert (out / "body_right.npz").is_file() and s["model"].endswith("body_right.npz")
    by = {r["planner"]: r for r in s["reaches"]}
    assert set(by) == {"learned", "analytic"}
    assert all(r["outcome"] in ("reached", "not_reached") for r in by.values()), by
    assert all(math.isfinite(r["true_error"]) for r in by.values())
    assert by["learned"]["true_error"] < 0.01, by
    assert by["analytic"]["true_error"] < 0.005, by
    assert "learned" in p.stdout and "analytic" in p.stdout


def test_bad_input_is_a_one_line_error(tmp_path):
    """A missing model file and a model of the other arm: exit 2 naming the problem, no
    traceback, no graph started."""
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
