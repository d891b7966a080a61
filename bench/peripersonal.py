"""Benchmark of the peripersonal-space models: maps, shared space, imagined collisions.

    scripts/env.sh python bench/peripersonal.py --quick     # 30 reach pairs, < 2 min
    scripts/env.sh python bench/peripersonal.py             # 120 reach pairs
    scripts/env.sh python bench/peripersonal.py --tune      # the tuning pairs (seed 1)
    scripts/env.sh python bench/peripersonal.py --quick --dds --dds-runs 2  # + over DDS

Maps: per arm, analytic motor babbling (``--babbles`` postures uniform within the arm's joint
limits, trunk and other arm at rest, hand = forward kinematics of the URDF through pinocchio)
grows a :class:`GrowingNeuralGas` with the paper's constants (config defaults). Trained maps
are kept in ``--maps`` (default bench/out/peripersonal_maps, git-ignored) and reused when
their babbling and config match; ``--retrain`` forces training. Coverage: the fraction of
HELD-OUT babbled hand positions (another seed, never trained on) within 2 cm of a neuron
(goal >= 0.98; the worse arm is reported), quantisation error = their mean distance to the
best-matching neuron [mm]. Shared neurons: neurons of each map within ``reach_radius`` of the
other map.

Collision check against the physics: random pairs of reach targets, each drawn from the
shared workspace of its arm's map (above the table: z >= ``Z_MIN``). Each pair is imagined
(:meth:`ImaginedCollisionCheck.plan_pair`, timed: plan_pair_ms) and then executed in
parallel in the in-process simulator harness (:class:`SimLoop`: MuJoCo with the arms
colliding, the impedance controller core following both PMP joint trajectories at 1 kHz;
objects moved off the table), from the rest posture, for tau + 0.5 s; the physics verdict is
whether any arm-arm contact appeared (``Simulator.self_contacts``). Recall = predicted
collisions among the pairs that collided in the physics (goal 1.0), precision = pairs that
collided among the predicted ones (goal >= 0.8). Pairs whose imagined reach misses its
target by more than 1 cm are skipped (counted). The check's ``margin`` was chosen with
``--tune`` on seed 1; the benchmark's pairs use seed 2 (held out). ``margin_for_recall_1``
reports the smallest margin that would have caught every physics collision of this run.

The tabletop task (issue 19, :mod:`icub_pmp.demo.tabletop`): the demo's four cubes planned
with these maps (allocation by reward, hand-overs through an empty area, pairs parallel or
serial by the imagined check) and executed twice in the same harness, as scheduled and
all-serial: ``task_success`` (every cube delivered, 0 arm-arm contacts, 0 arm-object
collisions other than the grasped cube, in the physics), ``task_speedup_vs_serial`` (the
all-serial run's simulated time over the scheduled run's), ``task_arm_arm_contacts``,
``task_arm_object_collisions``, ``task_handovers``. ``--no-task`` skips it.

``--dds`` also runs the task over DDS (:mod:`icub_pmp.demo.tabletop_dds`: the node graph in
lockstep, the pair check through ``/peripersonal/plan_pair``, ``/pmp/reach_action``,
``/sim/grasp``, judged on the ground-truth topics), as scheduled and all-serial in the same
graph, the same cubes and retries, on the same maps: the same figures prefixed ``task_dds_``
(``task_dds_speedup_vs_serial``: the all-serial run's simulated time over the scheduled
run's, both over DDS). ``--dds-runs N``: N scheduled runs in that graph
(``task_dds_runs_delivered``; ``task_dds_success`` needs every one). The graph's realism preset
is pinned (``--realism``, default ``ideal``). 15-60 min on a loaded 2-core machine: not part of
``--quick``, not in ``bench/registry.yaml``.

Ends with one JSON line. Timings depend on the machine's load (the load average is printed).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from icub_pmp.demo.tabletop import run_tabletop  # noqa: E402
from icub_pmp.errors import ModelError  # noqa: E402
from icub_pmp.kinematics.robot_spec import HANDS  # noqa: E402
from icub_pmp.peripersonal import (  # noqa: E402
    GrowingNeuralGas,
    GrowingNeuralGasConfig,
    ImaginedCollisionCheck,
    PeripersonalSpace,
    analytic_babbling,
)
from icub_pmp.peripersonal.peripersonal_space import map_file  # noqa: E402
from icub_sim_bridge import SimConfig  # noqa: E402
from icub_sim_bridge.harness.arm_pair_execution import (  # noqa: E402
    PAIR_Z_MIN,
    execute_pair,
    recall_precision,
    shared_target_pairs,
)
from icub_sim_bridge.harness.sim_loop import SimLoop  # noqa: E402

OUT = Path(__file__).resolve().parent / "out"
PAPER_NEURONS = {"left": 478, "right": 476}  # TX and RX robots' maps (Bhat and Mohan 2018)
PAPER_BABBLES = 10_000
BABBLE_SEED = {"left": 11, "right": 12}
HELD_OUT_SEED = {"left": 21, "right": 22}
Z_MIN = PAIR_Z_MIN  # lowest target [m]: 6 cm above the table top (z = -0.09)
SETTLE = 0.5  # [s] run after tau before judging the physics
REACH_TOLERANCE = 0.01  # [m] imagined residual above which a pair is skipped


def load_or_train(directory: Path, n_babbles: int, retrain: bool) -> tuple[dict, dict]:
    """Both arms' maps (from ``directory`` when they match, else trained) and timings."""
    cfg = GrowingNeuralGasConfig()
    maps, info = {}, {"trained": [], "train_s": {}}
    for arm in HANDS:
        path = map_file(directory, arm)
        if not retrain and path.exists():
            try:
                gng = GrowingNeuralGas.load(path)
                if gng.config == cfg and gng.report and gng.report.inputs % n_babbles == 0 \
                        and gng.label == f"{arm}:{n_babbles}:{BABBLE_SEED[arm]}":
                    maps[arm] = gng
                    continue
            except ModelError:
                pass
        data = analytic_babbling(arm, n_babbles, BABBLE_SEED[arm]).hand
        gng = GrowingNeuralGas(cfg, f"{arm}:{n_babbles}:{BABBLE_SEED[arm]}")
        t0 = time.perf_counter()
        gng.fit(data)
        info["train_s"][arm] = time.perf_counter() - t0
        info["trained"].append(arm)
        gng.save(path)
        maps[arm] = gng
    return maps, info


def _task_figures(rep: dict, prefix: str, wall0: float) -> dict:
    """A tabletop report's figures (module doc; ``rep`` has ``scheduled``, ``serial``,
    ``task_success`` and ``task_speedup_vs_serial``), keys prefixed ``prefix``, with the
    run's rounds and its wall time since ``wall0``."""
    s, b = rep["scheduled"], rep["serial"]
    rounds = s.get("rounds") or [r["mode"] for r in rep["plan"]]
    return {f"{prefix}{k}": v for k, v in {
        "success": bool(rep["task_success"]),
        "speedup_vs_serial": round(rep["task_speedup_vs_serial"], 3),
        "delivered": len(s["delivered"]),
        "objects": s["objects"],
        "time_s": round(s["duration"], 2),
        "serial_time_s": round(b["duration"], 2),
        "arm_arm_contacts": s["arm_arm_contacts"],
        "arm_object_collisions": len(s["arm_object_collisions"]),
        "serial_success": bool(b["success"]),
        "serial_arm_arm_contacts": b["arm_arm_contacts"],
        "handovers": s["handovers"],
        "rounds": rounds,
        "wall_s": round(time.perf_counter() - wall0, 1),
    }.items()}


def tabletop_figures(space: PeripersonalSpace) -> dict:
    """The tabletop task's figures (module doc), from one scheduled and one all-serial run."""
    t0 = time.perf_counter()
    rep = run_tabletop(space)
    s, b = rep["scheduled"], rep["serial"]
    (OUT / "tabletop_report.json").write_text(json.dumps(rep, indent=1))
    print(f"tabletop: plan {[r['mode'] for r in rep['plan']]}; delivered {s['delivered']} of "
          f"{s['objects']}; {s['duration']:.2f} s scheduled vs {b['duration']:.2f} s all-serial "
          f"(simulated); arm-arm contacts {s['arm_arm_contacts']} / {b['arm_arm_contacts']}, "
          f"arm-object {s['arm_object_collisions']} / {b['arm_object_collisions']}; hand-overs "
          f"{s['handovers']}; grasp refusals {s['grasp_refusals']}", file=sys.stderr)
    return _task_figures(rep, "task_", t0)


def tabletop_dds_figures(maps: Path, runs: int = 1, realism: str = "ideal") -> dict:
    """The tabletop task over DDS (module doc): ``python -m icub_pmp.demo.tabletop_dds
    --serial --runs runs`` on ``maps`` in one graph (the scheduled run, the all-serial
    baseline, then the further scheduled runs), its report's figures prefixed ``task_dds_``;
    ``task_dds_runs_delivered``: the cubes each scheduled run delivered."""
    import subprocess

    t0 = time.perf_counter()
    out = OUT / "tabletop_dds"
    (out / "report.json").unlink(missing_ok=True)  # never a previous run's figures
    p = subprocess.run([sys.executable, "-m", "icub_pmp.demo.tabletop_dds", "--serial",
                        "--runs", str(runs), "--realism", realism, "--maps", str(maps),
                        "--out", str(out)], capture_output=True, text=True)
    print(p.stdout[-4000:], file=sys.stderr)
    if not (out / "report.json").exists() or p.returncode not in (0, 1):
        print(p.stderr[-3000:], file=sys.stderr)
        return {"task_dds_success": False, "task_dds_error": f"exit {p.returncode}"}
    rep = json.loads((out / "report.json").read_text())
    s, b = rep["scheduled"], rep["serial"]
    print(f"tabletop over DDS: delivered {s['delivered']} of {s['objects']}; "
          f"{s['duration']:.2f} s scheduled vs {b['duration']:.2f} s all-serial (simulated); "
          f"rounds {s['rounds']}, replans {s['replans']}, grasp retries {s['grasp_retries']}",
          file=sys.stderr)
    return {**_task_figures(rep, "task_dds_", t0),
            "task_dds_runs_delivered": [len(r["delivered"]) for r in rep["runs"]],
            "task_dds_runs_time_s": [round(r["duration"], 2) for r in rep["runs"]],
            "task_dds_realism": realism}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="30 reach pairs (< 2 min)")
    ap.add_argument("--pairs", type=int, default=None, help="number of reach pairs")
    ap.add_argument("--seed", type=int, default=2, help="pair seed (1 = the tuning set)")
    ap.add_argument("--tune", action="store_true", help="the tuning pairs: seed 1, 120 pairs")
    ap.add_argument("--babbles", type=int, default=40_000, help="babbled postures per arm")
    ap.add_argument("--maps", type=Path, default=OUT / "peripersonal_maps")
    ap.add_argument("--retrain", action="store_true", help="train the maps even if saved")
    ap.add_argument("--no-task", action="store_true", help="skip the tabletop task")
    ap.add_argument("--dds", action="store_true",
                    help="also the tabletop task over DDS (task_dds_* keys; 10-30 min)")
    ap.add_argument("--dds-runs", type=int, default=1,
                    help="scheduled runs of the task over DDS in its graph (with --dds)")
    ap.add_argument("--realism", choices=("ideal", "icub"), default="ideal",
                    help="the simulator's realism preset of the task over DDS (with --dds)")
    ap.add_argument("--estimator", action="store_true",
                    help="close the controller's torque loop on the wrench estimator too")
    args = ap.parse_args()
    if args.dds_runs < 1:
        ap.error(f"--dds-runs: expected >= 1, got {args.dds_runs}")
    if args.tune:
        args.seed = 1
    n_pairs = args.pairs or (30 if args.quick else 120)
    load0 = os.getloadavg()[0]
    wall0 = time.perf_counter()

    # ------------------------------------------------------------------ maps
    maps, info = load_or_train(args.maps, args.babbles, args.retrain)
    space = PeripersonalSpace(maps)
    cover, quant = {}, {}
    for arm in HANDS:
        held = analytic_babbling(arm, 5000, HELD_OUT_SEED[arm]).hand
        cover[arm] = maps[arm].coverage(held, 0.02)
        quant[arm] = maps[arm].quantisation_error(held) * 1e3
    print(f"maps: {maps['left'].size} / {maps['right'].size} neurons (paper 478 / 476 from "
          f"about {PAPER_BABBLES} babbles; here {args.babbles} per arm), trained "
          f"{info['trained'] or 'none (loaded)'} {info['train_s']}", file=sys.stderr)
    print(f"held-out coverage at 2 cm {cover}, quantisation error [mm] {quant}; shared "
          f"neurons left {space.shared.size('left')}, right {space.shared.size('right')}; "
          f"arm Y {space.arm_y}", file=sys.stderr)

    # ------------------------------------------------------------------ pairs
    check = ImaginedCollisionCheck()
    loop = SimLoop(sim_config=SimConfig(cameras_enabled=False), estimator=args.estimator)
    targets = shared_target_pairs(space, 4 * n_pairs, args.seed)
    rows, skipped, plan_ms = [], 0, []
    exec_s = 0.0
    for tg in targets:
        if len(rows) == n_pairs:
            break
        t0 = time.perf_counter()
        pair = check.plan_pair({"left": tg[0], "right": tg[1]})
        plan_ms.append((time.perf_counter() - t0) * 1e3)
        if max(p.max_residual for p in pair.plans.values()) > REACH_TOLERANCE:
            skipped += 1
            continue
        t0 = time.perf_counter()
        phys = execute_pair(loop, pair.plans, SETTLE)
        exec_s += time.perf_counter() - t0
        v = pair.verdict
        rows.append({"left": tg[0].round(4).tolist(), "right": tg[1].round(4).tolist(),
                     "predicted": v.collides, "distal_hit": v.distal_hit,
                     "min_clearance": v.min_clearance, "min_distal": v.min_distal_distance,
                     "closest": v.closest_links, **phys})
        print(f"pair {len(rows):3d}: predicted {v.collides!s:5} (clearance "
              f"{v.min_clearance * 1e3:6.1f} mm, distal {v.min_distal_distance * 1e3:5.1f} mm)"
              f"  physics {phys['collided']!s:5} {phys['bodies'][:2]}", file=sys.stderr)
    pred = np.array([r["predicted"] for r in rows])
    truth = np.array([r["collided"] for r in rows])
    distal = np.array([r["distal_hit"] for r in rows])
    clear = np.array([r["min_clearance"] for r in rows])
    recall, precision = recall_precision(pred, truth)
    d_recall, d_precision = recall_precision(distal, truth)
    need = float(clear[truth].max()) + 1e-4 if truth.any() else None
    p_need = recall_precision(clear < need, truth)[1] if need is not None else None
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / f"peripersonal_pairs_seed{args.seed}.json").write_text(json.dumps(rows, indent=1))
    result = {
        "quick": bool(args.quick),
        "seed": args.seed,
        "babbles_per_arm": args.babbles,
        "gng_neurons_left": maps["left"].size,
        "gng_neurons_right": maps["right"].size,
        "paper_gng_neurons_left": PAPER_NEURONS["left"],
        "paper_gng_neurons_right": PAPER_NEURONS["right"],
        "paper_babbles": PAPER_BABBLES,
        "coverage_2cm": round(min(cover.values()), 4),
        "coverage_2cm_left": round(cover["left"], 4),
        "coverage_2cm_right": round(cover["right"], 4),
        "quant_err_mm": round(float(np.mean(list(quant.values()))), 2),
        "shared_neurons": space.shared.size("left") + space.shared.size("right"),
        "shared_neurons_left": space.shared.size("left"),
        "shared_neurons_right": space.shared.size("right"),
        "pairs": len(rows),
        "pairs_skipped_unreachable": skipped,
        "pairs_colliding_physics": int(truth.sum()),
        "pairs_predicted": int(pred.sum()),
        "collision_check_recall": None if recall is None else round(recall, 3),
        "collision_check_precision": None if precision is None else round(precision, 3),
        "distal_only_recall": None if d_recall is None else round(d_recall, 3),
        "distal_only_precision": None if d_precision is None else round(d_precision, 3),
        "margin_m": check.config.margin,
        "distal_threshold_m": check.config.distal_threshold,
        "margin_for_recall_1_m": None if need is None else round(need, 4),
        "precision_at_margin_for_recall_1": None if p_need is None else round(p_need, 3),
        "plan_pair_ms_median": round(float(np.median(plan_ms)), 1),
        "plan_pair_ms_p95": round(float(np.percentile(plan_ms, 95)), 1),
        "map_train_s": {a: round(s, 1) for a, s in info["train_s"].items()},
        "pair_exec_s_mean": round(exec_s / max(len(rows), 1), 2),
        "estimator": bool(args.estimator),
        "check_config": dataclasses.asdict(check.config),
        "wall_s": round(time.perf_counter() - wall0, 1),
        "load_avg": [round(load0, 2), round(os.getloadavg()[0], 2)],
    }
    if not args.no_task:
        result.update(tabletop_figures(space))
        result["wall_s"] = round(time.perf_counter() - wall0, 1)
        result["load_avg"][1] = round(os.getloadavg()[0], 2)
    if args.dds:
        result.update(tabletop_dds_figures(args.maps, args.dds_runs, args.realism))
        result["wall_s"] = round(time.perf_counter() - wall0, 1)
        result["load_avg"][1] = round(os.getloadavg()[0], 2)
    print(f"paper: 478 / 476 neurons (TX / RX) from about {PAPER_BABBLES} babbles; ours "
          f"{result['gng_neurons_left']} / {result['gng_neurons_right']} from "
          f"{args.babbles}", file=sys.stderr)
    print(json.dumps(result))


if __name__ == "__main__":
    main()
