"""The paper report (issue 21): each experiment at a tiny size returns the report's fields,
the report has the paper's columns, and the command line writes it."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import pytest

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.paper import (
    EXPERIMENTS,
    REPORT_COLUMNS,
    STATUSES,
    ExperimentResult,
    Measurement,
    find,
    report_table,
    run_experiment,
    write_report,
)

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def results():
    """Every registered experiment run once at its tiny size."""
    return {e.name: run_experiment(e, e.tiny_size) for e in EXPERIMENTS}


def test_registry_holds_every_paper_in_report_order():
    """Names are unique, the PMP paper's rows come first, the body-schema paper's last, and
    every experiment has a tiny <= quick <= full size."""
    names = [e.name for e in EXPERIMENTS]
    assert len(names) == len(set(names))
    for must in ("pmp_fig2_joint_limits", "pmp_fig3_torque_limits", "pmp_fig4_9_tbg",
                 "pmp_fig7_trunk", "pmp_fig8_transport", "pmp_sect4_unreachable",
                 "pmp_eq4a_basic_vs_default", "force_table1_ft_prediction",
                 "force_fig6_7_rfrr_vs_krr", "force_fig11_motioncut_heldout",
                 "body_schema_model_rmse", "body_schema_gng_map", "body_schema_reward_field",
                 "body_schema_imagined_collisions", "force_table2_jerk"):
        assert must in names
    assert names[0].startswith("pmp_") and names[-1].startswith("body_schema_")
    for e in EXPERIMENTS:
        assert 1 <= e.tiny_size <= e.quick_size <= e.full_size, e


def test_each_experiment_at_a_tiny_size_returns_the_report_fields(results):
    """Every result names its paper and figure, quotes the paper, carries a status among the
    three and a verdict; a run experiment measured something finite with n >= 1."""
    for name, r in results.items():
        assert isinstance(r, ExperimentResult) and r.name == name
        assert r.paper and r.reference and r.paper_reports and r.claim and r.verdict
        assert r.status in STATUSES
        assert r.seconds > 0
        if r.status != "not yet implemented":
            assert any(m.n >= 1 for m in r.measured), name
            for m in r.measured:  # n = 0: a quantity the run did not reach ("not measured")
                assert (m.n >= 1 and math.isfinite(m.mean) and math.isfinite(m.spread)) or (
                    m.n == 0 and math.isnan(m.mean) and m.text() == "not measured"), (name, m)


def test_pmp_claims_hold_at_a_tiny_size(results):
    """The PMP paper's qualitative claims are reproduced even on one trial each (the claims
    the project's planner tests also assert)."""
    for name in ("pmp_fig2_joint_limits", "pmp_fig3_torque_limits", "pmp_fig4_9_tbg",
                 "pmp_fig7_trunk", "pmp_fig8_transport", "pmp_sect4_unreachable"):
        assert results[name].status == "reproduced", (name, results[name].verdict)


def test_heldout_motion_sequences_are_never_tuning_sequences():
    """Fig 11 runs on held-out sequences: no seed is one the segmenter was tuned on
    (bench/motion.py's 7 and 11), seeds are distinct, both cameras and both head axes occur."""
    from icub_pmp.paper.motion_experiments import TUNING_SEEDS, heldout_specs

    bench = (ROOT / "bench" / "motion.py").read_text()
    assert "seed=7" in bench and "seed=11" in bench and TUNING_SEEDS == {7, 11}
    seqs = heldout_specs(16)
    seeds = [s.spec.seed for s in seqs]
    assert len(set(seeds)) == len(seeds) and not set(seeds) & TUNING_SEEDS
    assert {s.camera for s in seqs} == {"left", "right"}
    assert {s.spec.head_axis for s in seqs} == {"yaw", "pitch"}
    assert all(s.noise_std > 0 and s.spec.head_rate > 0 for s in seqs)


def test_force_rows_say_which_simulator_they_ran_on(results):
    """The force paper's simulator rows name the preset they ran on (or say the simulator was
    the ideal one, until SimConfig has a 'realism' field)."""
    from icub_pmp.paper.force_experiments import realism_note

    for name in ("force_table1_ft_prediction", "force_fig6_7_rfrr_vs_krr",
                 "force_table2_jerk"):
        assert realism_note() in results[name].verdict


def test_table2_reaches_are_executed_and_min_jerk_is_the_smoothest(results):
    """Table 2 at a tiny size: every controller's reaches end within 1 cm of the asked pose
    on the imperfect robot, and the min-jerk controller's hand path has the lowest jerk (the
    paper's claim), with both paper figures."""
    r = results["force_table2_jerk"]
    by = {m.quantity: m for m in r.measured}
    for c in ("min-jerk", "VITE", "DLS"):
        assert by[f"{c} position error [mm]"].mean < 10.0, by
        assert by[f"{c} position error [mm]"].n == 2
    assert by["min-jerk's jerk lower than VITE's by [-]"].mean > 0
    assert by["min-jerk's jerk lower than DLS's by [-]"].mean > 0
    assert len(r.figures) == 2


def test_body_model_row_waits_for_the_body_schema_package(results):
    """Without icub_pmp.body_schema the body-model row says 'not yet implemented' and why."""
    from icub_pmp.paper.body_schema_experiments import body_model_available

    r = results["body_schema_model_rmse"]
    if not body_model_available():
        assert r.status == "not yet implemented" and "body_schema" in r.verdict


def test_report_has_the_papers_columns_and_one_row_per_experiment(results, tmp_path):
    """The report's table has the columns Experiment | Paper | Figure/table | Paper reports |
    We measure | Verdict, one row per experiment; figures are written as PNG with their CSV."""
    assert REPORT_COLUMNS == ("Experiment", "Paper", "Figure/table", "Paper reports",
                              "We measure", "Verdict")
    rows = list(results.values())
    table = report_table(rows).splitlines()
    assert table[0] == "| " + " | ".join(REPORT_COLUMNS) + " |"
    assert len(table) == 2 + len(rows)
    for r, line in zip(rows, table[2:]):
        assert line.startswith(f"| {r.name} | {r.paper} |") and r.status in line
        assert line.count(" | ") >= len(REPORT_COLUMNS) - 1
    path = write_report(rows, tmp_path / "run")
    text = path.read_text()
    assert text.count("\n| ") >= len(rows) + 1
    pngs = sorted(tmp_path.glob("run/*.png"))
    assert len(pngs) == sum(len(r.figures) for r in rows) > 0
    for png in pngs:
        assert png.read_bytes()[:4] == b"\x89PNG" and png.with_suffix(".csv").exists()
        assert f"]({png.name})" in text


def test_measurement_statistics_and_bad_inputs():
    """Measurement.of gives the mean and the sample std; empty = not measured; bad status,
    unknown experiment names and sizes < 1 raise clear errors."""
    m = Measurement.of("x [m]", [1.0, 2.0, 3.0])
    assert (m.mean, m.spread, m.n) == (2.0, 1.0, 3)
    assert Measurement.of("x", []).text() == "not measured"
    with pytest.raises(InvalidInput, match="status"):
        ExperimentResult("a", "PMP", "Fig 1", "c", "p", (), "maybe", "v")
    with pytest.raises(UnknownName, match="pmp_fig2_joint_limits"):
        find("no_such_experiment")
    with pytest.raises(InvalidInput, match="size"):
        run_experiment(find("pmp_fig8_transport"), 0)


def test_command_line_writes_a_timestamped_report(tmp_path):
    """`python -m icub_pmp.paper --only NAME --size 1 --out DIR` writes DIR/<timestamp>/
    report.md with that one row; an unknown --only name exits 2 naming the valid ones."""
    cmd = [sys.executable, "-m", "icub_pmp.paper", "--out", str(tmp_path)]
    out = subprocess.run(cmd + ["--only", "pmp_fig8_transport", "--size", "1"], cwd=ROOT,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    reports = list(tmp_path.glob("*/report.md"))
    assert len(reports) == 1
    text = reports[0].read_text()
    assert "| pmp_fig8_transport | PMP | Fig 8" in text and "pmp_fig7_trunk |" not in text
    bad = subprocess.run(cmd + ["--only", "fig99"], cwd=ROOT, capture_output=True, text=True,
                         timeout=120)
    assert bad.returncode == 2 and "pmp_fig2_joint_limits" in bad.stderr


def test_reward_fields_send_each_arm_to_its_own_side_first(results):
    """Fig 4 at a tiny size: each arm's reward peaks outside the shared workspace and the
    allocation is as parallel as every scene allows."""
    r = results["body_schema_reward_field"]
    assert r.status == "reproduced", r.verdict
    by = {m.quantity: m for m in r.measured}
    assert by["fewest possible rounds / rounds [-]"].mean >= 0.99
    assert by["sequences with the own side first [fraction]"].mean >= 0.9


def test_rfrr_is_compared_with_a_library_gp(results):
    """Figs 6-7 carry a library baseline beside KRR: scikit-learn's GP with marginal-likelihood
    hyperparameters, whose test nMSE is finite and better than predicting the mean (< 1)."""
    r = results["force_fig6_7_rfrr_vs_krr"]
    gp = [m for m in r.measured if m.quantity.startswith("scikit-learn GP nMSE")]
    assert len(gp) == 1 and 0.0 <= gp[0].mean < 1.0, gp
    assert "scikit-learn GP" in r.verdict
