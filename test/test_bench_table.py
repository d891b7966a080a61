"""bench/run_all.py: the BENCHMARKS.md table is built from the stored results, goals are
judged on the figures, missing figures and benchmarks say so."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys

import pytest

from icub_pmp.testing import repo_root


def _run_all():
    spec = importlib.util.spec_from_file_location("run_all", repo_root() / "bench/run_all.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_goals_are_judged_and_the_table_lists_every_metric(tmp_path):
    ra = _run_all()
    registry = {"a": {"what": "A", "metrics": {"x": ">= 1", "n.y": "<= 2", "z": ""}},
                "b": {"what": "B", "metrics": {"w": "== 0"}}}
    (tmp_path / "a.json").write_text(json.dumps({
        "benchmark": "a", "command": "cmd a", "commit": "abc", "date": "d", "load": [1, 2],
        "wall_s": 1.0, "figures": {"x": 0.5, "n": {"y": 1.5}}}))
    table = tmp_path / "T.md"
    summary = ra.write_table(registry, tmp_path, table)
    text = table.read_text()
    assert summary == {"a": "1/2"}
    assert "| a | x | >= 1 | 0.5 | **no** |" in text
    assert "| a | n.y | <= 2 | 1.5 | yes |" in text
    assert "| a | z |  | (missing) |  |" in text
    assert "| b | (not run) |" in text


def test_the_registry_names_existing_benchmarks():
    """Every entry runs an existing script: its own name, or the ``script`` it names (a second
    row of one script with other ``args``, e.g. eye_hand_rendered = body_schema.py
    --eye-hand-only --rendered), and those args are options that script parses."""
    ra = _run_all()
    for name, entry in ra.load_registry().items():
        script = repo_root() / "bench" / f"{entry.get('script', name)}.py"
        assert script.exists(), name
        for arg in entry.get("args", []):
            assert arg.startswith("--") and arg in script.read_text(), (name, arg)


@pytest.mark.parametrize("name", sorted(p.stem for p in (repo_root() / "bench").glob("*.py")))
def test_every_benchmark_starts(name):
    """Each bench/<name>.py imports what it uses and parses its options (``--help``): a moved
    module breaks the benchmark here, not in the next ``make bench``."""
    proc = subprocess.run([sys.executable, str(repo_root() / "bench" / f"{name}.py"), "--help"],
                          cwd=repo_root(), capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "--quick" in proc.stdout or name == "run_all", proc.stdout[-500:]
