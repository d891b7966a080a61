"""Benchmark: reliability of the graph (issue 22): fuzzed interfaces, node faults, soak.

    scripts/env.sh python bench/reliability.py --quick   # < 10 min: half the fuzz cases,
                                                         # each node faulted once (the
                                                         # signal CI does not try), 2 min soak
    scripts/env.sh python bench/reliability.py           # full fuzz, every node x SIGKILL
                                                         # and SIGTERM, 30 min soak

1. Fuzz: the graph of ``scripts/graph.sh`` (cameras off), every service, action and subscribed
   topic (icub_pmp.testing.graph_interfaces) over DDS with cases drawn from the types
   (icub_pmp.testing.message_fuzz); the controller's torques watched against the limits.
2. Faults: the lockstep graph (full run: every node of the project, cameras on); each node
   killed in the middle of a reach, restarted, the next reach goal executed
   (icub_pmp.testing.fault_injection); the table is printed.
3. Soak: reach / squeeze / release / look (/ vision in the full run) cycles on that graph
   (icub_pmp.testing.soak): RSS growth per process, loop-rate drift, warnings, goals answered.

4. Bags and hosts: ``bench/bag.py --quick`` (the recorder SIGKILLed mid-recording, messages
   lost beyond the last chunk) and ``bench/two_hosts.py --quick`` (the lockstep graph across a
   veth pair), run from here so one JSON line holds the issue's figures.

Ends with one JSON line: fuzz_cases, fuzz_crashes, fuzz_hangs, fuzz_unclear,
torque_violations, faults_tried, faults_recovered, recovery_s_max (restart -> the node serves
again), soak_minutes, rss_growth_mb_per_h_max, loop_rate_drift_pct, bag_sigkill_msgs_lost,
cross_host_lockstep_rtf, and details.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
import time
from pathlib import Path

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from icub_pmp.testing import NodeGraph, RosProbe, reserve_domain_id, ros_environment  # noqa: E402
from icub_pmp.testing import graph_interfaces as gi  # noqa: E402
from icub_pmp.testing.fault_injection import (  # noqa: E402
    FAULT_GRAPH,
    FAULT_PARAMS,
    FULL_FAULT_GRAPH,
    FULL_FAULT_PARAMS,
    FaultInjector,
    format_table,
)
from icub_pmp.testing.fuzz_tally import FuzzTally  # noqa: E402
from icub_pmp.testing.interface_fuzzer import InterfaceFuzzer  # noqa: E402
from icub_pmp.testing.soak import SoakRunner  # noqa: E402
from icub_pmp.testing.torque_watch import TorqueWatch  # noqa: E402


def fuzz(probe: RosProbe, env: dict[str, str], scale: float) -> dict:
    """Phase 1: every interface fuzzed; the tally's totals."""
    from icub_interfaces.srv import Reach

    with NodeGraph(gi.FUZZ_GRAPH, gi.FUZZ_PARAMS, env=env) as graph:
        if not probe.wait_for_service("/pmp/reach", Reach, 240.0):
            raise RuntimeError(f"the fuzz graph did not come up\n{graph.outputs()}")
        probe.wait_for(lambda: probe.node.count_publishers("/effort_command") >= 1, 60.0)
        watch = TorqueWatch(probe)
        fuzzer = InterfaceFuzzer(probe, graph, tally=FuzzTally())
        t0 = time.monotonic()
        gi.fuzz_services(fuzzer, scale)
        gi.fuzz_actions(fuzzer, scale)
        gi.fuzz_topics(fuzzer, scale)
        watch.pause()
        gi.fuzz_effort(fuzzer, scale)
        tally = fuzzer.tally
        print(tally.table(), flush=True)
        for p in tally.problems():
            print("PROBLEM", p, flush=True)
        return {
            "fuzz_cases": tally.total("cases"), "fuzz_crashes": tally.total("crashes"),
            "fuzz_hangs": tally.total("hangs"), "fuzz_unclear": tally.total("unclear"),
            "fuzz_rejected": tally.total("rejected"),
            "fuzz_cases_per_interface": {k: t.cases for k, t in tally.interfaces.items()},
            "fuzz_rejections_top": {k: t.reasons.most_common(3)
                                    for k, t in tally.interfaces.items() if t.reasons},
            "torque_commands_watched": watch.messages, "torque_violations": watch.violations,
            "torque_max_ratio": round(watch.worst, 3), "fuzz_s": round(time.monotonic() - t0),
        }


def faults(probe: RosProbe, env: dict[str, str], quick: bool, soak_minutes: float) -> dict:
    """Phases 2 and 3 on the lockstep graph: with ``quick`` the reach path (+ gaze controller
    for the soak's look), cameras off; else every node, cameras on (the soak's vision step)."""
    rows = []
    nodes, params = FULL_FAULT_GRAPH, FULL_FAULT_PARAMS
    plan = [(n, s) for n in nodes for s in (signal.SIGKILL, signal.SIGTERM)]
    if quick:  # each node once, the complement of the CI subset where it can be
        nodes, params = FAULT_GRAPH + ["gaze_controller"], FAULT_PARAMS
        plan = [("sim_bridge", signal.SIGTERM), ("wrench_estimator", signal.SIGKILL),
                ("impedance_controller", signal.SIGTERM), ("pmp_planner", signal.SIGKILL)]
    with NodeGraph(nodes, params, env=env) as graph:
        inj = FaultInjector(probe, graph)
        if not inj.wait_ready():
            raise RuntimeError(f"the lockstep graph did not come up\n{graph.outputs()}")
        inj.reach()  # warm-up
        for node, sig in plan:
            row = inj.run(node, sig)
            rows.append(row)
            print(row.row(), flush=True)
        print(format_table(rows), flush=True)
        soak = SoakRunner(probe, graph, inj.client).run(soak_minutes)
    rejoin = [r.rejoin_s for r in rows if math.isfinite(r.rejoin_s)]
    return {
        "faults_tried": len(rows), "faults_recovered": sum(r.recovered for r in rows),
        "recovery_s_max": round(max(rejoin), 2) if len(rejoin) == len(rows) else None,
        "fault_rows": [{"node": r.node, "fault": r.fault, "others_alive": r.others_alive,
                        "controller": r.controller, "simulator": r.simulator,
                        "interrupted_goal": r.interrupted_goal, "early_call": r.early_call,
                        "rejoin_s": round(r.rejoin_s, 2), "next_goal": r.next_goal,
                        "recovered": r.recovered} for r in rows],
        **soak.summary(),
    }


def companions(quick: bool) -> dict:
    """Phase 4: the crash-safe bags and the two hosts, measured in this run by their own
    benchmarks (``bench/bag.py``: the recorder SIGKILLed mid-recording;
    ``bench/two_hosts.py``: the lockstep graph split over a veth pair), each as a subprocess
    with ``--quick`` (their full runs add longer traffic and a delayed link). Returns their
    headline keys, or None with the reason when one could not run (e.g. no network
    namespaces without root)."""
    import subprocess

    root = Path(__file__).resolve().parent.parent
    out: dict = {}
    for bench, keys in (("bag", ("bag_sigkill_msgs_lost", "bag_sigkill_recovered")),
                        ("two_hosts", ("cross_host_lockstep_rtf", "single_host_lockstep_rtf",
                                       "cross_host_reach_success",
                                       "cross_host_rtt_ms_median"))):
        cmd = [str(root / "scripts" / "env.sh"), "python", f"bench/{bench}.py", "--quick"]
        proc = subprocess.run(cmd, cwd=root, capture_output=True, text=True, timeout=1800)
        lines = [ln for ln in proc.stdout.splitlines() if ln.strip().startswith("{")]
        figures = json.loads(lines[-1]) if lines else {}
        for k in keys:
            out[k] = figures.get(k)
        if proc.returncode != 0 or not lines:
            out[f"{bench}_error"] = (figures.get("error")
                                     or f"bench/{bench}.py exited {proc.returncode}: "
                                        f"{proc.stderr.strip()[-300:]}")
        print(f"{bench}: " + ", ".join(f"{k} {out[k]}" for k in keys), flush=True)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="half the fuzz cases, each node faulted once, a 2-minute soak")
    ap.add_argument("--soak-minutes", type=float, default=None,
                    help="soak duration [min] (default 2 with --quick, else 30)")
    ap.add_argument("--fuzz-only", action="store_true",
                    help="phase 1 only (the fuzz tally), no faults and no soak")
    args = ap.parse_args()
    scale = 0.5 if args.quick else 1.0
    soak_minutes = args.soak_minutes or (2.0 if args.quick else 30.0)
    load0 = os.getloadavg()[0]
    t0 = time.monotonic()
    with reserve_domain_id() as domain:
        env = ros_environment(domain)
        probe = RosProbe(domain, "reliability_bench")
        try:
            result = {"bench": "reliability", "quick": args.quick, **fuzz(probe, env, scale)}
            if not args.fuzz_only:
                result.update(faults(probe, env, args.quick, soak_minutes))
                result.update(companions(args.quick))
        finally:
            probe.close()
    result["load_start"] = round(load0, 2)
    result["load_end"] = round(os.getloadavg()[0], 2)
    result["total_s"] = round(time.monotonic() - t0)
    print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
