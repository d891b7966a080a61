"""The tabletop task over DDS as a user runs it (``python -m icub_pmp.demo.tabletop_dds``): the
node graph in lockstep plans a small task with the pair check through
``/peripersonal/plan_pair``, executes it through ``/pmp/reach_action`` and ``/sim/grasp`` and
judges it on the simulator's ground truth; bad input is a one-line error."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from icub_pmp.config import repo_root

pytestmark = [pytest.mark.integration, pytest.mark.slow]


def _run(*args: str, timeout: float = 1800.0) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "icub_pmp.demo.tabletop_dds", *args],
                          cwd=repo_root(), capture_output=True, text=True, timeout=timeout)


def test_two_cubes_delivered_without_arm_arm_contact(tmp_path):
    """A cube only the left arm reaches and one only the right arm reaches, each to its
    arm's target area: both rest in their areas at the end, the arms never touched each
    other nor a cube they were not working on; the report says so and the exit status is 0."""
    out = tmp_path / "run"
    p = _run("--cubes", "cube_left,cube_right", "--out", str(out))
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    report = json.loads((out / "report.json").read_text())
    run = report["scheduled"]
    assert sorted(run["delivered"]) == ["cube_left", "cube_right"], run
    assert run["arm_arm_contacts"] == 0 and run["arm_object_collisions"] == [], run
    assert report["task_success"] is True
    jobs = [r[a] for r in report["plan"] for a in ("left", "right") if r[a]]
    assert sorted(j.split()[0] for j in jobs) == ["cube_left", "cube_right"], report["plan"]
    assert "cubes delivered" in (out / "report.md").read_text()


def test_unknown_cube_is_a_one_line_error(tmp_path):
    """A cube that is not in the scene: exit 2 naming it and the valid ones, no traceback,
    no graph started."""
    p = _run("--cubes", "cube_left,cube_purple", "--out", str(tmp_path / "x"), timeout=120)
    assert p.returncode == 2, p.stderr
    assert "cube_purple" in p.stderr and "cube_right" in p.stderr
    assert "Traceback" not in p.stderr and not (tmp_path / "x").exists()


def test_missing_maps_are_a_one_line_error(tmp_path):
    """``--maps`` naming a folder without saved maps: exit 2 saying which file could not be
    loaded, no traceback, no graph started (it was a traceback)."""
    p = _run("--maps", str(tmp_path / "no_maps"), "--out", str(tmp_path / "x"), timeout=120)
    assert p.returncode == 2, p.stderr
    assert "--maps: cannot load the peripersonal map" in p.stderr and "no_maps" in p.stderr
    assert "Traceback" not in p.stderr and not (tmp_path / "x").exists()
