"""Run every benchmark of bench/registry.yaml (``--quick``) and rewrite BENCHMARKS.md.

    scripts/env.sh python bench/run_all.py              # = make bench: run all, rewrite
    scripts/env.sh python bench/run_all.py --only pmp,gaze
    scripts/env.sh python bench/run_all.py --table-only # rebuild the table from bench/results

Each benchmark runs as its own process, one after the other (the machine has two cores:
benchmarks never overlap), as ``scripts/env.sh python bench/<name>.py --quick``; its last
stdout line is its JSON figures. The run's figures, commit, date, load average and command are
stored in ``bench/results/<name>.json`` (committed: the table can be rebuilt and a partial
re-run keeps the other rows), its log in ``bench/out/<name>.log``. BENCHMARKS.md is then
written from every stored result: benchmark, metric, goal, value, met, commit, date, load,
command. Ends with one JSON line: {benchmark: goals met / goals}.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "bench" / "results"
LOGS = ROOT / "bench" / "out"
TABLE = ROOT / "BENCHMARKS.md"


def load_registry() -> dict:
    """bench/registry.yaml as {name: {what, metrics: {key: goal}}}."""
    return yaml.safe_load((ROOT / "bench" / "registry.yaml").read_text())


def _commit() -> str:
    out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                         capture_output=True, text=True)
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                           cwd=ROOT, capture_output=True, text=True).stdout.strip()
    return out.stdout.strip() + ("+dirty" if dirty else "")


def run_one(name: str, timeout: float, entry: dict | None = None) -> dict:
    """Run bench/<name>.py --quick (or the registry ``entry``'s ``script`` with its ``args``:
    a second row of one benchmark script); returns the stored record (raises on failure)."""
    entry = entry or {}
    script = [f"bench/{entry.get('script', name)}.py", *entry.get("args", []), "--quick"]
    cmd = [str(ROOT / "scripts" / "env.sh"), "python", *script]
    LOGS.mkdir(parents=True, exist_ok=True)
    load0 = os.getloadavg()[0]
    t0 = time.monotonic()
    with open(LOGS / f"{name}.log", "w") as log:
        proc = subprocess.run(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=log, text=True,
                              timeout=timeout)
    lines = [ln for ln in proc.stdout.splitlines() if ln.strip().startswith("{")]
    if proc.returncode != 0 or not lines:
        raise RuntimeError(f"{' '.join(script)} failed (exit {proc.returncode}); see "
                           f"{LOGS / (name + '.log')}")
    return {
        "benchmark": name,
        "command": "scripts/env.sh python " + " ".join(script),
        "commit": _commit(),
        "date": dt.datetime.now().strftime("%Y-%m-%d %H:%M"),
        "load": [round(load0, 2), round(os.getloadavg()[0], 2)],
        "wall_s": round(time.monotonic() - t0, 1),
        "figures": json.loads(lines[-1]),
    }


def lookup(figures: dict, key: str):
    """A figure by dotted key (None when absent)."""
    v = figures
    for part in key.split("."):
        if not isinstance(v, dict) or part not in v:
            return None
        v = v[part]
    return v


def met(value, goal: str) -> str:
    """'yes' / 'no' / '' (no goal or no value) for ``value`` against ``goal``."""
    if not goal or value is None or not isinstance(value, (int, float)):
        return ""
    op, ref = goal.split()
    ref = float(ref)
    ok = {">=": value >= ref, "<=": value <= ref, "==": value == ref}[op]
    return "yes" if ok else "**no**"


def _fmt(v) -> str:
    if v is None:
        return "(missing)"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def write_table(registry: dict, results: Path = RESULTS, table: Path = TABLE
                ) -> dict[str, str]:
    """Rewrite ``table`` (BENCHMARKS.md) from the records in ``results``; returns
    {benchmark: 'goals met/goals'}."""
    rows, summary = [], {}
    for name, entry in registry.items():
        path = results / f"{name}.json"
        if not path.exists():
            rows.append(f"| {name} | (not run) | | | | | | | |")
            continue
        rec = json.loads(path.read_text())
        n_goal = n_met = 0
        for key, goal in entry["metrics"].items():
            v = lookup(rec["figures"], key)
            m = met(v, goal)
            n_goal += bool(goal)
            n_met += m == "yes"
            load = "-".join(f"{x:.1f}" for x in rec["load"])
            rows.append(f"| {name} | {key} | {goal} | {_fmt(v)} | {m} | {rec['commit']} | "
                        f"{rec['date']} | {load} | `{rec['command']}` |")
        summary[name] = f"{n_met}/{n_goal}"
    text = [
        "# Benchmarks",
        "",
        "Generated by `make bench` (= `scripts/env.sh python bench/run_all.py`) from",
        "`bench/results/*.json`; do not edit by hand. Each benchmark ran alone with `--quick` on",
        "this project's 2-core machine (load average at start and end in the table): timings are",
        "indicative of that machine and its load. Goals come from the issues; what each figure",
        "means is in the docstring of `bench/<benchmark>.py`, design decisions behind the figures",
        "in `docs/decisions/`. Full (non-quick) runs are quoted in the README where they matter.",
        "",
        "| benchmark | metric | goal | value | met | commit | date | load | command |",
        "|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        "What each benchmark measures:",
        "",
        *[f"- `{n}`: {e['what']}" for n, e in registry.items()],
        "",
    ]
    table.write_text("\n".join(text))
    return summary


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", default="", help="comma-separated benchmarks to run")
    ap.add_argument("--table-only", action="store_true", help="rebuild the table only")
    ap.add_argument("--timeout", type=float, default=1800.0, help="per benchmark [s]")
    args = ap.parse_args(argv)
    registry = load_registry()
    names = [n for n in args.only.split(",") if n] or list(registry)
    unknown = sorted(set(names) - set(registry))
    if unknown:
        print(f"run_all: unknown benchmarks {unknown}; known: {sorted(registry)}",
              file=sys.stderr)
        return 2
    failed = []
    if not args.table_only:
        RESULTS.mkdir(parents=True, exist_ok=True)
        for name in names:
            print(f"run_all: {name} ...", file=sys.stderr, flush=True)
            try:
                rec = run_one(name, args.timeout, registry[name])
            except (RuntimeError, subprocess.TimeoutExpired) as exc:
                print(f"run_all: {exc}", file=sys.stderr)
                failed.append(name)
                continue
            (RESULTS / f"{name}.json").write_text(json.dumps(rec, indent=1) + "\n")
    summary = write_table(registry)
    print(json.dumps({"goals_met": summary, "failed": failed}))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
