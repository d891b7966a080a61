"""Benchmark of the wrench estimator: compute time per sample, FT prediction in
contact-free motion (the paper's Table 1), external-force error vs the simulator's ground
truth, and the incremental RFRR (Sect. 3.1): update time per sample and nMSE for D = 200,
500, 1000, with the nominal model and with a 10 % heavier left forearm in the estimator.

    scripts/env.sh python bench/wrench.py --quick     # < 2 min
    scripts/env.sh python bench/wrench.py             # longer motion, more RFRR samples

All in-process (simulator + estimator + impedance controller in lockstep, SimLoop):

1. Table 1: both arms move periodically (10 joints, 0.4-0.7 Hz, 10-30 deg, raised clear of
   the table) in position mode; per axis mean and std of (measured - predicted) FT wrench,
   predicted by RNEA with null hand wrenches. Estimator time per sample (perf_counter,
   median) from this run, and its thread CPU time on 2000 further samples (less sensitive
   to the load).
2. External force: 4 N on the right hand (scripted, 1.5 s) and the left hand pressing on the
   table; error of the estimated force (root_link, about the hand origin) vs the ground truth
   over the last 0.5 s, in % of the true force (median and 95th percentile).
3. RFRR: from the run of 1, the estimator's inputs (torso + left arm q, q_dot, q_ddot: 30)
   and the left FT residual (measured - model) are streamed to RandomFeaturesRidge (one
   sample in 5 learnt); trained on the first 75 % of the motion, tested on the last 25 %.
   nMSE = mean over the 6 axes of MSE / variance of the measured wrench in the test window;
   "model" = no learning. The mismatch case recomputes the model prediction with the left
   forearm's mass and inertia x 1.1 (FtDynamicsModel(link_mass_scale)).

The machine is shared: timings depend on its load (printed). Ends with one JSON line.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from icub_pmp.control.impedance_controller_config import ImpedanceControllerConfig  # noqa: E402
from icub_pmp.dynamics.ft_dynamics_model import FtDynamicsModel  # noqa: E402
from icub_pmp.dynamics.random_features_ridge import RandomFeaturesRidge  # noqa: E402
from icub_pmp.dynamics.wrench_estimator_config import WrenchEstimatorConfig  # noqa: E402
from icub_sim_bridge.harness.sim_loop import SimLoop  # noqa: E402
from icub_sim_bridge.harness.sim_scenarios import (  # noqa: E402
    press_left_hand_on_table,
    raised_posture,
    start_periodic_motion,
)
from icub_sim_bridge.sim_config import SimConfig  # noqa: E402
from icub_sim_bridge.simulator import Simulator  # noqa: E402

HANDS = ("left", "right")


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def periodic_motion(sim: Simulator, seconds: float) -> tuple[SimLoop, list, float]:
    """Contact-free periodic motion of both arms; returns the loop, its steps, start time."""
    sim.reset(q=raised_posture(sim.spec))
    loop = SimLoop(ImpedanceControllerConfig(mode="position", feedforward="inverse_dynamics"),
                   sim=sim)
    loop.run(0.02)
    t0 = start_periodic_motion(loop, seconds)
    loop.record_timing = True
    steps = loop.run(seconds)
    return loop, steps, t0


def table1(steps: list, t0: float) -> dict:
    window = [s for s in steps if s.t - t0 >= 1.2]
    out = {}
    for h in HANDS:
        err = np.array([s.estimate.ft_measured[h] - s.estimate.ft_predicted[h] for s in window])
        out[f"ft_err_mean_{h}"] = [round(float(x), 4) for x in err.mean(0)]
        out[f"ft_err_std_{h}"] = [round(float(x), 4) for x in err.std(0)]
    out["contact_false_positives"] = int(sum(s.estimate.contact[h] for s in steps for h in HANDS))
    return out


def external_force(sim: Simulator) -> dict:
    """Scripted 4 N on the right hand; left hand pressing on the table."""
    errs = {}
    sim.reset("rest")
    loop = SimLoop(ImpedanceControllerConfig(mode="impedance"), sim=sim)
    loop.run(0.1)
    f = 4.0 * np.array([1.0, -2.0, 3.0]) / np.linalg.norm([1.0, -2.0, 3.0])
    sim.apply_wrench("r_hand_dh_frame", f, np.zeros(3), 1.5)
    steps = loop.run(1.5)[-500:]
    errs["applied"] = [100 * np.linalg.norm(s.estimate.ext_root["right"][:3] -
                                            s.ground_truth["right"][:3]) /
                       np.linalg.norm(s.ground_truth["right"][:3]) for s in steps]
    sim.reset("rest")
    loop = SimLoop(ImpedanceControllerConfig(mode="impedance"), sim=sim)
    loop.run(0.05)
    press_left_hand_on_table(loop)
    steps = loop.run(2.0)[-500:]
    errs["table"] = [100 * np.linalg.norm(s.estimate.ext_root["left"][:3] -
                                          s.ground_truth["left"][:3]) /
                     np.linalg.norm(s.ground_truth["left"][:3]) for s in steps]
    press = float(np.mean([np.linalg.norm(s.ground_truth["left"][:3]) for s in steps]))
    return {
        "ext_force_err_pct": float(np.percentile(errs["applied"], 95)),
        "ext_force_err_pct_median": float(np.median(errs["applied"])),
        "table_press_force_n": press,
        "table_press_err_pct": float(np.percentile(errs["table"], 95)),
    }


def rfrr(loop: SimLoop, steps: list, t0: float, features: tuple[int, ...], every: int) -> dict:
    """Stream the left-arm residual to RFRR^D; nominal model and 10 % forearm mismatch."""
    est = loop.estimator
    data = [s for s in steps if s.t - t0 >= 1.0]
    x = np.array([est.rfrr_input("left", s.estimate.state) for s in data])
    meas = np.array([s.estimate.ft_measured["left"] for s in data])  # sensor convention
    sign = 1.0 if est.config.ft_convention == "parent_on_child" else -1.0
    wrong = FtDynamicsModel(est.spec, {"l_forearm": 1.1})
    pred = {
        "": np.array([s.estimate.ft_predicted["left"] for s in data]),
        "_mismatch": np.array([sign * wrong.rnea(s.estimate.state.q, s.estimate.state.v,
                                                 s.estimate.state.a).sensor["left"]
                               for s in data]),
    }
    n_train = int(0.75 * len(data))
    test = slice(n_train, len(data))
    var = meas[test].var(0)
    cfg = WrenchEstimatorConfig()
    scale = np.concatenate([np.full(10, cfg.rfrr_position_scale),
                            np.full(10, cfg.rfrr_velocity_scale),
                            np.full(10, cfg.rfrr_acceleration_scale)])
    out = {"rfrr_train_samples": len(range(0, n_train, every)),
           "rfrr_test_samples": len(data) - n_train}
    for tag, p in pred.items():
        resid = meas - p
        out[f"model_nmse{tag}"] = float(np.mean(np.mean(resid[test] ** 2, 0) / var))
        for d in features:
            r = RandomFeaturesRidge(30, 6, d, cfg.rfrr_bandwidth, cfg.rfrr_ridge, 1.0, scale,
                                    cfg.rfrr_seed)
            times = []
            for k in range(0, n_train, every):
                t1 = time.perf_counter()
                r.update(x[k], resid[k])
                times.append(time.perf_counter() - t1)
            corr = np.array([r.predict(xi) for xi in x[test]])
            e = resid[test] - corr
            out[f"rfrr_nmse_d{d}{tag}"] = float(np.mean(np.mean(e**2, 0) / var))
            if tag == "":
                out[f"rfrr_update_us_d{d}"] = float(np.median(times) * 1e6)
                ptimes = []
                for xi in x[test][:300]:
                    t1 = time.perf_counter()
                    r.predict(xi)
                    ptimes.append(time.perf_counter() - t1)
                out[f"rfrr_predict_us_d{d}"] = float(np.median(ptimes) * 1e6)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="short run (< 2 min)")
    args = ap.parse_args()
    seconds = 12.0 if args.quick else 40.0
    every = 5
    load0 = _load()
    print(f"load average at start: {load0} (2 cores, shared machine)", file=sys.stderr)
    sim = Simulator(SimConfig(cameras_enabled=False))
    loop, steps, t0 = periodic_motion(sim, seconds)
    est = loop.estimator
    st = steps[-1].estimate.state
    ft = {h: steps[-1].estimate.ft_measured[h] for h in HANDS}
    t_cpu = time.thread_time_ns()
    for k in range(2000):
        est.update(loop.t + (k + 1) * 1e-3, st.q, st.v, ft)
    cpu = (time.thread_time_ns() - t_cpu) / 2000 / 1e3
    out: dict = {"estimator_us_median": float(np.median(loop.timing["estimator"]) * 1e6),
                 "estimator_cpu_us": cpu,
                 "estimator_us_p95": float(np.percentile(loop.timing["estimator"], 95) * 1e6),
                 "motion_s": seconds}
    out.update(table1(steps, t0))
    print(f"table 1: {out}", file=sys.stderr)
    out.update(rfrr(loop, steps, t0, (200, 500, 1000), every))
    del steps
    out.update(external_force(sim))
    out["load_start"] = load0
    out["load_end"] = _load()
    print(json.dumps({k: (round(v, 5) if isinstance(v, float) else v) for k, v in out.items()}))


if __name__ == "__main__":
    main()
