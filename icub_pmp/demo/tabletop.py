"""The tabletop task of issue 19: two arms cooperating on small cubes, judged in the physics.

    scripts/env.sh python -m icub_pmp.demo.tabletop            # = make demo-tabletop
    scripts/env.sh python -m icub_pmp.demo.tabletop --out bags/tabletop --maps DIR

Four 4 cm cubes lie on the table (:data:`SCENE`): one only the left arm reaches, one only the
right arm reaches, one in the shared workspace and one only the left arm reaches that must go
to the right arm's target area. The peripersonal maps allocate the cubes to the arms by
reward; each round pairs the two arms' jobs, run in parallel when the imagined collision
check says they do not collide and in series when it says they do; the cube the left arm
cannot bring to its target area is put down in an empty area of the shared workspace and the
right arm takes it from there (the hand-over of Bhat and Mohan 2018). The iCub model has no
fingers: the grasp is emulated by a weld switched on only when the palm touches the cube in
the simulator's contacts (:meth:`Simulator.grasp`), switched off at the target.

The task runs twice on the same scene in the in-process simulator harness (MuJoCo + the
impedance controller core at 1 kHz in lockstep, :class:`TabletopExecution`): as scheduled,
and all-serial (every round one arm after the other: the baseline). The report (JSON and
markdown in ``--out``) gives the cubes delivered, the simulated time of both runs and the
speed-up, arm-arm contacts and arm-object collisions in the physics (goal 0) and the
hand-overs done. Exit status 1 when the scheduled run is not a success.

:func:`run_tabletop` is the phase the demo can call (it takes the maps and returns the
report).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

from icub_pmp.config import repo_root
from icub_pmp.peripersonal.tabletop_task import (
    ImaginedPairCheck,
    TabletopPlanner,
    TabletopScene,
    TabletopTaskConfig,
    TaskPlan,
)

#: the joints the task's reaches keep still
WRISTS = tuple(f"{s}_wrist_{j}" for s in "lr" for j in ("prosup", "pitch", "yaw"))

__all__ = ["SCENE", "WRISTS", "run_tabletop", "plan_summary", "sim_config_for", "main"]

_Z = -0.07  # a 4 cm cube's centre on the table top (z = -0.09) [m]
#: the demo's scene (root_link [m]): cube -> (centre, target area); areas' centres
SCENE = TabletopScene(
    objects={"cube_left": (-0.28, -0.14, _Z), "cube_right": (-0.28, 0.14, _Z),
             "cube_shared": (-0.27, 0.03, _Z), "cube_handover": (-0.31, -0.08, _Z)},
    areas={"left_area": (-0.28, -0.26, _Z), "right_area": (-0.28, 0.26, _Z)},
    destinations={"cube_left": "left_area", "cube_right": "right_area",
                  "cube_shared": "right_area", "cube_handover": "right_area"},
)


def sim_config_for(scene: TabletopScene):  # -> SimConfig
    """The simulator's configuration with the scene's cubes (no cameras)."""
    from icub_sim_bridge.sim_config import SimConfig

    spec = " ".join(f"{n}:{p[0]},{p[1]},{p[2]}" for n, p in scene.objects.items())
    return SimConfig(cameras_enabled=False, tabletop_objects=spec)


def plan_summary(plan: TaskPlan) -> list[dict]:
    """The rounds as plain dicts: mode, and each arm's job (object, kind, area)."""
    out = []
    for r in plan.rounds:
        out.append({"mode": r.mode, **{a: (None if j is None else
                                            f"{j.object} {j.kind} -> {j.area or 'empty area'}")
                                       for a, j in r.jobs.items()}})
    return out


def run_tabletop(space: object, scene: TabletopScene = SCENE,
                 config: TabletopTaskConfig | None = None, serial_baseline: bool = True
                 ) -> dict:
    """Plan ``scene`` with the peripersonal maps ``space`` and execute it in the physics
    (module doc); returns the report dict (``task_success``, ``task_speedup_vs_serial``, the
    plan, both runs)."""
    from icub_pmp.peripersonal import ImaginedCollisionCheck
    from icub_sim_bridge.harness.sim_loop import SimLoop
    from icub_sim_bridge.harness.tabletop_execution import TabletopExecution

    config = config or TabletopTaskConfig()
    # the wrists stay still: a pick-and-place needs the hand's position only, and PMP's
    # relaxation spins the light wrist joints faster than their rate limits on the long
    # carries (the executed reaches would be slowed down many times)
    check = ImaginedCollisionCheck(frozen_joints=WRISTS)
    t0 = time.perf_counter()
    plan = TabletopPlanner(space, ImaginedPairCheck(check, config), config).plan(scene)
    planning_s = time.perf_counter() - t0
    loop = SimLoop(sim_config=sim_config_for(scene), estimator=False)
    run = TabletopExecution(loop, check, config)
    scheduled = run.execute(scene, plan)
    report = {"plan": plan_summary(plan), "unreachable": list(plan.unreachable),
              "undeliverable": dict(plan.undeliverable), "planning_s": planning_s,
              "pair_checks": plan.checks[0], "pair_checks_collision": plan.checks[1],
              "scheduled": scheduled.as_dict(), "task_success": scheduled.success}
    if serial_baseline:
        serial = run.execute(scene, plan, all_serial=True)
        report["serial"] = serial.as_dict()
        report["task_speedup_vs_serial"] = serial.duration / scheduled.duration
    return report


def _cell(v: object) -> str:
    """A table cell: a list as its length (and its items when short), floats to 0.01."""
    if isinstance(v, list):
        return f"{len(v)}" + (f" ({', '.join(map(str, v))})" if 0 < len(v) <= 4 else "")
    return f"{v:.2f}" if isinstance(v, float) else str(v)


def _markdown(report: dict) -> str:
    s = report["scheduled"]
    lines = ["# Tabletop task (issue 19)", "",
             "Grasp emulated: a weld switched on only when the palm touches the cube.", "",
             "| round | mode | left | right |", "|---|---|---|---|"]
    for k, r in enumerate(report["plan"]):
        lines.append(f"| {k + 1} | {r['mode']} | {r['left'] or '-'} | {r['right'] or '-'} |")
    lines += ["", "| figure | scheduled | all-serial |", "|---|---|---|"]
    b = report.get("serial", {})
    for key, name in (("delivered", "cubes delivered"), ("duration", "simulated time [s]"),
                      ("arm_arm_contacts", "arm-arm contacts"),
                      ("arm_object_collisions", "arm-object collisions"),
                      ("handovers", "hand-overs done")):
        lines.append(f"| {name} | {_cell(s[key])} | {_cell(b.get(key, '-'))} |")
    if "task_speedup_vs_serial" in report:
        lines += ["", f"Speed-up vs all-serial: {report['task_speedup_vs_serial']:.2f}; "
                      f"task success: {report['task_success']}"]
    return "\n".join(lines) + "\n"


def _space(maps: Path | None) -> object:
    """The peripersonal maps: ``maps`` (a folder of saved maps), else grown as the node
    does (``config/peripersonal_space.yaml``: babble_samples, babble_seed)."""
    from icub_pmp.peripersonal import GrowingNeuralGas, PeripersonalSpace
    from icub_pmp.peripersonal.peripersonal_space import map_file

    if maps is not None:
        if (maps / "peripersonal_arms.json").exists():
            return PeripersonalSpace.load(maps)
        return PeripersonalSpace({a: GrowingNeuralGas.load(map_file(maps, a))
                                  for a in ("left", "right")})
    d = repo_root() / "data" / "peripersonal"
    if (d / "peripersonal_arms.json").exists():
        return PeripersonalSpace.load(d)
    from icub_pmp.peripersonal.peripersonal_node_config import PeripersonalNodeConfig

    cfg = PeripersonalNodeConfig.from_yaml(repo_root() / "config" / "peripersonal_space.yaml",
                                           "peripersonal_space")
    print(f"growing the peripersonal maps ({cfg.babble_samples} babbles per arm) ...",
          flush=True)
    space = PeripersonalSpace.grow(cfg.babble_samples, cfg.babble_seed)
    space.save(d)
    return space


def space_or_exit(ap: argparse.ArgumentParser, maps: Path | None) -> object:
    """:func:`_space`, or a one-line usage error (exit 2) when the maps cannot be loaded (a
    wrong ``--maps`` folder, a damaged file) instead of a traceback."""
    from icub_pmp.errors import IcubPmpError

    try:
        return _space(maps)
    except IcubPmpError as exc:
        ap.error(f"--maps: {exc}")


def main(argv: list[str] | None = None) -> int:
    """Command line (module doc)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=None,
                    help="report folder (default bags/tabletop-<time>)")
    ap.add_argument("--maps", type=Path, default=None,
                    help="saved peripersonal maps (default data/peripersonal, grown if missing)")
    ap.add_argument("--no-serial", action="store_true", help="skip the all-serial baseline")
    args = ap.parse_args(argv)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    out = args.out or repo_root() / "bags" / time.strftime("tabletop-%Y%m%d-%H%M%S")
    report = run_tabletop(space_or_exit(ap, args.maps), serial_baseline=not args.no_serial)
    out.mkdir(parents=True, exist_ok=True)
    (out / "report.json").write_text(json.dumps(report, indent=2))
    (out / "report.md").write_text(_markdown(report))
    print(_markdown(report))
    print(f"report: {out}/report.md")
    return 0 if report["task_success"] else 1


if __name__ == "__main__":
    sys.exit(main())
