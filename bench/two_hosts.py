"""Benchmark: the graph split over two hosts (robot's PC: simulator, 1 kHz controller,
estimator; laptop: planners and vision), joined by a veth link between two network
namespaces, DDS over UDP with a peers list; baseline: the same graph and driver on one host,
run in the same process.

    sudo scripts/env.sh python bench/two_hosts.py --quick   # 20 timed calls per setup
    sudo scripts/env.sh python bench/two_hosts.py           # 100 timed calls, 2 ms link delay too

Figures (one JSON line): ``cross_host_reach_success`` (the demo's first phase, judged in the
physics, across the link), ``cross_host_lockstep_rtf`` vs ``single_host_lockstep_rtf``
(simulated over wall time during that reach: the lockstep loop stays on the robot's PC), the
service round trip laptop -> robot's PC ``cross_host_rtt_ms_median`` vs
``same_host_rtt_ms_median`` (the same server called from its own host), ``link_packets``.
Needs root (network namespaces); without it the JSON line says why and the figures are null.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from icub_pmp.demo.two_hosts import run_two_hosts  # noqa: E402
from icub_pmp.graph import VethLinkError  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="20 timed calls, no delayed link")
    ap.add_argument("--calls", type=int, default=None)
    args = ap.parse_args()
    calls = args.calls or (20 if args.quick else 100)
    out: dict[str, object] = {"load_1min_start": round(os.getloadavg()[0], 2)}
    try:
        single = run_two_hosts(single_host=True, calls=calls)
        cross = run_two_hosts(single_host=False, calls=calls)
        out.update({k: v for k, v in single.items() if k.startswith("single_host")})
        out.update({k: v for k, v in cross.items() if k not in ("setup", "delay_ms")})
        out["rtf_ratio_cross_vs_single"] = round(
            cross["cross_host_lockstep_rtf"] / max(1e-9, single["single_host_lockstep_rtf"]), 3)
        if not args.quick:
            slow = run_two_hosts(single_host=False, delay_ms=2.0, calls=calls)
            out["delayed_2ms_reach_success"] = slow["cross_host_reach_success"]
            out["delayed_2ms_lockstep_rtf"] = slow["cross_host_lockstep_rtf"]
            out["delayed_2ms_rtt_ms_median"] = slow["cross_host_rtt_ms_median"]
    except VethLinkError as exc:
        out["error"] = f"network namespaces cannot be created here: {exc}"
        out["cross_host_reach_success"] = None
    out["load_1min_end"] = round(os.getloadavg()[0], 2)
    for k, v in out.items():
        print(f"{k}: {v}", flush=True)
    print(json.dumps(out), flush=True)
    return 0 if "error" not in out else 2


if __name__ == "__main__":
    sys.exit(main())
