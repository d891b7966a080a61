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

4. Realism (issue 17): 1-3 again on both simulator presets in the same run, ``ideal`` (the
   simulator without imperfections) and ``icub`` (FT noise, offsets, drift and bandwidth,
   model mismatch, friction, actuation delay, encoder and IMU noise; seed 0), each under the
   same treatment: the estimator's FT offsets calibrated (``calibrate_from_recent``) in the
   still raised posture before the motion and at rest before the push. Nested under
   ``ideal`` / ``icub``: ``ft_pred_err_std_N`` {left, right} (the Table 1 quantity: std of
   measured - predicted FT force, mean over the 3 axes, test window = last 25 % of the
   motion) for the rigid-body model and ``ft_pred_err_std_N_rfrr`` for model + RFRR (D = 200,
   learnt online on the first 75 %, one sample in 5); ``false_contact_rate`` (fraction of
   estimator samples with a contact flag during the contact-free motion);
   ``ext_force_err_pct`` (95th percentile of the per-sample error of the 4 N push, as in 2),
   ``ext_force_mean_err_pct`` (error of its 0.5 s mean), the paper-style per-axis error mean
   and std [N]; ``contact_detect_ms`` (push start to the right-hand contact flag).
   The top-level figures (1-3) are those of ``ideal`` (the shipped default preset).

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
from icub_pmp.dynamics.ft_offset_calibration import CalibrationError  # noqa: E402
from icub_pmp.dynamics.random_features_ridge import RandomFeaturesRidge  # noqa: E402
from icub_pmp.dynamics.wrench_estimator_config import WrenchEstimatorConfig  # noqa: E402
from icub_sim_bridge.harness.sim_loop import SimLoop  # noqa: E402
from icub_sim_bridge.harness.sim_scenarios import (  # noqa: E402
    press_left_hand_on_table,
    raised_posture,
    start_periodic_motion,
)
from icub_sim_bridge.realism_config import RealismConfig  # noqa: E402
from icub_sim_bridge.sim_config import SimConfig  # noqa: E402
from icub_sim_bridge.simulator import Simulator  # noqa: E402

HANDS = ("left", "right")


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def calibrate(loop: SimLoop, timeout: float = 6.0) -> float:
    """Hold still until the estimator's FT offset calibration succeeds; returns the
    simulated time it took [s] (raises if the robot never came to rest)."""
    t0 = loop.t
    while True:
        loop.run(0.25)
        try:
            loop.estimator.calibrate_from_recent()
            return loop.t - t0
        except CalibrationError:
            if loop.t - t0 > timeout:
                raise


def periodic_motion(sim: Simulator, seconds: float, calibrated: bool = False,
                    estimator: WrenchEstimatorConfig | None = None
                    ) -> tuple[SimLoop, list, float]:
    """Contact-free periodic motion of both arms; returns the loop, its steps, start time.
    ``calibrated``: calibrate the FT offsets in the still raised posture first."""
    sim.reset(q=raised_posture(sim.spec))
    loop = SimLoop(ImpedanceControllerConfig(mode="position", feedforward="inverse_dynamics",
                                             friction_compensation=calibrated),
                   estimator, sim=sim)
    loop.run(0.02)
    if calibrated:
        calibrate(loop)
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


#: the estimator of section 4, the same for both presets: the FT wrenches low-passed at 15 Hz
#: and contact thresholds above the noise of the icub preset's sensors (docs/decisions/0037)
REALISM_ESTIMATOR = WrenchEstimatorConfig(ft_cutoff_hz=15.0, contact_force_on=1.5,
                                          contact_force_off=0.75, contact_min_samples=10)


def realism_figures(preset: str, seconds: float, every: int,
                    estimator: WrenchEstimatorConfig = REALISM_ESTIMATOR) -> dict:
    """Section 4 of the module doc for one preset."""
    sim = Simulator(SimConfig(cameras_enabled=False), realism=RealismConfig(preset=preset))
    loop, steps, t0 = periodic_motion(sim, seconds, calibrated=True, estimator=estimator)
    est = loop.estimator
    data = [s for s in steps if s.t - t0 >= 1.0]
    n_train = int(0.75 * len(data))
    cfg = WrenchEstimatorConfig()
    out: dict = {"ft_pred_err_std_N": {}, "ft_pred_err_std_N_rfrr": {}}
    for h in HANDS:
        x = np.array([est.rfrr_input(h, s.estimate.state) for s in data])
        resid = np.array([s.estimate.ft_measured[h] - s.estimate.ft_predicted[h]
                          for s in data])
        n_j = x.shape[1] // 3
        scale = np.concatenate([np.full(n_j, cfg.rfrr_position_scale),
                                np.full(n_j, cfg.rfrr_velocity_scale),
                                np.full(n_j, cfg.rfrr_acceleration_scale)])
        r = RandomFeaturesRidge(x.shape[1], 6, 200, cfg.rfrr_bandwidth, cfg.rfrr_ridge, 1.0,
                                scale, cfg.rfrr_seed)
        for k in range(0, n_train, every):
            r.update(x[k], resid[k])
        test = resid[n_train:]
        corr = test - np.array([r.predict(xi) for xi in x[n_train:]])
        out["ft_pred_err_std_N"][h] = float(test[:, :3].std(0).mean())
        out["ft_pred_err_std_N_rfrr"][h] = float(corr[:, :3].std(0).mean())
    flags = [s.estimate.contact[h] for s in steps if s.estimate for h in HANDS]
    out["false_contact_rate"] = float(np.mean(flags))
    del steps, data
    # the 4 N push on the right hand, from rest, offsets calibrated at rest
    sim.reset("rest")
    loop = SimLoop(ImpedanceControllerConfig(mode="impedance"), estimator, sim=sim)
    loop.run(0.1)
    calibrate(loop)
    on_before = bool(loop.step().estimate.contact["right"])
    f = 4.0 * np.array([1.0, -2.0, 3.0]) / np.linalg.norm([1.0, -2.0, 3.0])
    t_push = loop.t
    sim.apply_wrench("r_hand_dh_frame", f, np.zeros(3), 1.5)
    steps = loop.run(1.5)
    first = None if on_before else next(
        (s.t for s in steps if s.estimate and s.estimate.contact["right"]), None)
    last = steps[-500:]
    est_f = np.array([s.estimate.ext_root["right"][:3] for s in last])
    true_f = np.array([s.ground_truth["right"][:3] for s in last])
    err = est_f - true_f
    pct = 100 * np.linalg.norm(err, axis=1) / np.linalg.norm(true_f, axis=1)
    out.update({
        "ext_force_err_pct": float(np.percentile(pct, 95)),
        "ext_force_err_pct_median": float(np.median(pct)),
        "ext_force_mean_err_pct": float(100 * np.linalg.norm(err.mean(0))
                                        / np.linalg.norm(true_f.mean(0))),
        "ext_force_err_mean_N": [round(float(v), 4) for v in err.mean(0)],
        "ext_force_err_std_N": [round(float(v), 4) for v in err.std(0)],
        "contact_detect_ms": -1.0 if first is None else float(1000 * (first - t_push)),
        "contact_on_before_push": on_before,
    })
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
    for preset in ("ideal", "icub"):
        out[preset] = realism_figures(preset, seconds, every)
        print(f"{preset}: {out[preset]}", file=sys.stderr)
    out["load_start"] = load0
    out["load_end"] = _load()
    print(json.dumps(_rounded(out)))


def _rounded(v):
    """Floats rounded to 5 decimals, through nested dicts."""
    if isinstance(v, dict):
        return {k: _rounded(x) for k, x in v.items()}
    return round(v, 5) if isinstance(v, float) else v


if __name__ == "__main__":
    main()
