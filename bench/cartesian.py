"""Benchmark of the Cartesian solver: eq 11 with CasADi + IPOPT vs DLS, pink and PMP,
and the jerk of the minimum-jerk trajectories vs a VITE-style and a DLS-driven reach.

    scripts/env.sh python bench/cartesian.py --quick     # < 2 min
    scripts/env.sh python bench/cartesian.py             # more targets for the jerk and PMP

Solver part: a fixed set of N random reachable poses of the 10-DoF torso + right arm chain
(hand frame r_hand_dh_frame), each the hand pose of a configuration drawn uniformly within the
URDF joint limits; every solve starts from the rest posture. Primary run: the iKin shoulder
constraints on, targets drawn from configurations that meet them (the poses the robot may
take). Second run ("free"): constraints off, every uniform draw kept. Success = position error
<= 1 mm (and orientation error <= 1 deg for pose targets). The same targets go to a
damped-least-squares solver, to pink (differential IK on pinocchio, QP solver daqp) and to the
PMP planner of icub_pmp.pmp (a subset: it relaxes a dynamical system, much slower). The
solver runs as configured (IPOPT warm-started from the compiled seed, IkSeed); the same solver
without the seed (IPOPT from rest, "ipopt_noseed") runs in the same process as the baseline.

Jerk part (Sect. 4.1, Table 2 comparison): the 7-DoF right arm reaches pose targets from rest
with (a) the multi-referential min-jerk generator (T = 2 s), (b) the same scheme with VITE
dynamics in both spaces (Hersch & Billard), (c) a DLS velocity controller closed on the pose
error (mu = 1e-5 as in the paper). (b) and (c) are tuned to cover 90 % of the motion at T like
(a). Each joint reference is tracked by the same critically damped 2nd-order servo (5 Hz), as a
robot's position loop would; the jerk is that of the hand path, mean ||d^3x/dt^3|| over 2 T.

Ends with one JSON line. Wall-clock times depend on the machine's load (printed); the CPU times
(process_time) are much less sensitive to it and are reported beside them.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from icub_pmp.baselines import DlsSolver  # noqa: E402
from icub_pmp.cartesian import (  # noqa: E402
    ArmLinearConstraints,
    IkConfig,
    IkSolver,
    KinematicChain,
    MinJerkConfig,
    MinJerkGenerator,
)
from icub_pmp.cartesian.vite_filter import ViteFilter  # noqa: E402
from icub_pmp.kinematics import IcubModel  # noqa: E402
from icub_pmp.kinematics.rotations import rotation_angle  # noqa: E402
from icub_pmp.pmp import PinocchioJacobianProvider  # noqa: E402

CHAIN = "torso_right_arm"
POS_OK = 1e-3  # [m]
ORI_OK = math.radians(1.0)  # [rad]


# ---------------------------------------------------------------------------- targets
def make_targets(model: IcubModel, n: int, seed: int, constrained: bool, torso: bool = True):
    """n hand poses (T_root_hand) of configurations uniform within the joint limits."""
    chain = KinematicChain.from_name(CHAIN)
    alc = ArmLinearConstraints("right")
    idx = model.indices(chain.joints)
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        q = model.random_q(rng)
        if not torso:
            q[model.indices(chain.joints[:3])] = 0.0
        if constrained and alc.violation(chain.joints, q[idx]) > 0:
            continue
        out.append(model.frame_pose(q, chain.frame))
    return out


# ---------------------------------------------------------------------------- solvers
class PinkSolver:
    """pink differential IK iterated to convergence (the 'pink' baseline)."""

    def __init__(self, model: IcubModel, dt: float = 0.1, max_iter: int = 200):
        import pink
        from pink.tasks import FrameTask, PostureTask

        self.pink = pink
        chain = KinematicChain.from_name(CHAIN)
        self.m = IcubModel(joints=chain.joints)  # 10-DoF model: torso + right arm
        self.frame = chain.frame
        self.q0 = self.m.posture("rest")
        self.FrameTask, self.PostureTask = FrameTask, PostureTask
        self.dt, self.max_iter = dt, max_iter

    def solve(self, T: pin.SE3, orientation: bool):
        conf = self.pink.Configuration(self.m.model, self.m.data, self.q0.copy())
        task = self.FrameTask(self.frame, position_cost=1.0,
                              orientation_cost=1.0 if orientation else 0.0)
        task.set_target(T)
        posture = self.PostureTask(cost=1e-3)
        posture.set_target(self.q0)
        for _ in range(self.max_iter):
            M = conf.get_transform_frame_to_world(self.frame)
            pe = float(np.linalg.norm(M.translation - T.translation))
            oe = rotation_angle(T.rotation, M.rotation)
            if pe < 5e-4 and (not orientation or oe < math.radians(0.5)):
                break
            v = self.pink.solve_ik(conf, [task, posture], self.dt, solver="daqp", damping=1e-6)
            conf.integrate_inplace(v, self.dt)
        M = conf.get_transform_frame_to_world(self.frame)
        return conf.q.copy(), M


def run_methods(model, targets, methods, orientation_modes=(False, True)):
    """{method: {mode: arrays of pos err, ori err, time, joint-limit viol, tendon viol, torso}}

    The methods are interleaved target by target (every method solves a target before the next
    target), so a change of the machine's load during the run falls on all of them alike."""
    chain = KinematicChain.from_name(CHAIN)
    alc = ArmLinearConstraints("right")
    idx = model.indices(chain.joints)
    lo, hi = model.lower[idx], model.upper[idx]
    rest = model.posture("rest")
    rows: dict[tuple[str, bool], list] = {(n, o): [] for n in methods for o in orientation_modes}
    for ori in orientation_modes:
        for k, T in enumerate(targets):
            for name, (fn, subset) in methods.items():
                if k >= subset:
                    continue
                c0 = time.process_time()
                t0 = time.perf_counter()
                q = fn(T, ori)
                dt = time.perf_counter() - t0
                dc = time.process_time() - c0
                qf = rest.copy()
                qf[idx] = q
                M = model.frame_pose(qf, chain.frame)
                rows[(name, ori)].append((
                    np.linalg.norm(M.translation - T.translation),
                    rotation_angle(T.rotation, M.rotation),
                    dt,
                    max(0.0, float(np.max(lo - q)), float(np.max(q - hi))),
                    alc.violation(chain.joints, q),
                    float(np.abs(q[:3]).max()),
                    dc,
                ))
    return {name: {("pose" if o else "pos"): np.array(rows[(name, o)])
                   for o in orientation_modes} for name in methods}


def summarise(res):
    s = {}
    for mode, a in res.items():
        ok = a[:, 0] <= POS_OK
        if mode == "pose":
            ok &= a[:, 1] <= ORI_OK
        s[mode] = {
            "n": int(len(a)),
            "success_rate": float(ok.mean()),
            "pos_err_mm_median": float(np.median(a[:, 0]) * 1e3),
            "pos_err_mm_p95": float(np.percentile(a[:, 0], 95) * 1e3),
            "ori_err_deg_median": float(np.degrees(np.median(a[:, 1]))),
            "ori_err_deg_p95": float(np.degrees(np.percentile(a[:, 1], 95))),
            "ms_median": float(np.median(a[:, 2]) * 1e3),
            "ms_p95": float(np.percentile(a[:, 2], 95) * 1e3),
            "cpu_ms_median": float(np.median(a[:, 6]) * 1e3),
            "cpu_ms_p95": float(np.percentile(a[:, 6], 95) * 1e3),
            "joint_limit_violations": int(np.sum(a[:, 3] > 1e-6)),
            "tendon_violations": int(np.sum(a[:, 4] > 1e-6)),
            "torso_deg_median": float(np.degrees(np.median(a[:, 5]))),
        }
    return s


# ---------------------------------------------------------------------------- jerk
def vite_filter(n: int, T: float, Ts: float) -> ViteFilter:
    """The VITE dynamics (icub_pmp.cartesian.vite_filter) critically damped with 90 % of a
    step at t = T, so the kinematic comparison runs both generators on the same T (the
    paper's own VITE settings are used by the executed comparison, ``make paper``)."""
    w = 3.89 / T
    return ViteFilter(n, Ts, alpha=2 * w, beta=w / 2)


def dls_reach(model, chain, q0, q_d, T, Ts, horizon, mu=1e-5):
    """Closed-loop DLS velocity control on the 6-D pose error toward K(q_d); gain K such that
    90 % of the error is gone at t = T (first order)."""
    idx = model.indices(chain.joints)
    fid = model.frame_id(chain.frame)
    qf = q0.copy()
    qf[idx] = q_d
    target = model.frame_pose(qf, fid)
    K = math.log(10.0) / T
    q = q0.copy()
    lo, hi = model.lower[idx], model.upper[idx]
    out = [q[idx].copy()]
    for _ in range(int(round(horizon / Ts))):
        J = model.frame_jacobian(q, fid)[:, idx]
        M = model.data.oMf[fid]
        e = np.concatenate([target.translation - M.translation,
                            pin.log3(target.rotation @ M.rotation.T)])
        qd = J.T @ np.linalg.solve(J @ J.T + mu**2 * np.eye(6), K * e)
        q[idx] = np.clip(q[idx] + Ts * qd, lo, hi)
        out.append(q[idx].copy())
    return np.array(out)


def tracked_hand_jerk(model, chain, q0, q_ref, Ts, horizon, dt=0.002, wn=2 * math.pi * 5.0):
    """Mean hand jerk [m/s^3] when each joint follows q_ref (sampled at Ts, linearly
    interpolated) through a critically damped servo of natural frequency wn, over horizon."""
    idx = model.indices(chain.joints)
    fid = model.frame_id(chain.frame)
    t_ref = Ts * np.arange(len(q_ref))
    n_pre = 5  # samples at rest before the start, so a jump at t = 0 counts
    ts = np.arange(-n_pre, int(round(horizon / dt)) + 1) * dt
    sub = 10
    h = dt / sub
    t_fine = (np.arange(len(ts) * sub) - n_pre * sub) * h
    r_fine = np.stack([np.interp(t_fine, t_ref, q_ref[:, j]) for j in range(q_ref.shape[1])], 1)
    q = q_ref[0].copy()
    v = np.zeros_like(q)
    xs = []
    qf = q0.copy()
    for i in range(len(ts)):
        for k in range(sub):
            a = wn * wn * (r_fine[i * sub + k] - q) - 2 * wn * v
            v = v + h * a
            q = q + h * v
        qf[idx] = q
        xs.append(model.frame_pose(qf, fid).translation.copy())
    x = np.array(xs)
    jerk = np.diff(x, n=3, axis=0) / dt**3
    return float(np.mean(np.linalg.norm(jerk, axis=1)))


def jerk_comparison(model, n_targets, seed):
    chain = KinematicChain.from_name("right_arm")
    solver = IkSolver(model)
    q0 = model.posture("rest")
    T, Ts = 2.0, 0.01
    horizon = 2 * T
    rows = []
    for pose in make_targets(model, 4 * n_targets, seed, constrained=True, torso=False):
        if len(rows) >= n_targets:
            break
        sol = solver.solve("right_arm", pose.translation, pose.rotation, q0)
        if not sol.success:
            continue
        refs = {}
        for name in ("minjerk", "vite"):
            cfg = MinJerkConfig(trajectory_time=T, period=Ts, max_duration_factor=horizon / T,
                                settle_tolerance=1e-12)
            gen = MinJerkGenerator(model, chain, cfg)
            if name == "vite":
                gen.joint_filter = vite_filter(chain.n, T, Ts)
                gen.task_filter = vite_filter(6, T, Ts)
            gen.reset(q0)
            gen.set_target(sol.q)
            refs[name] = gen.rollout().q
        refs["dls"] = dls_reach(model, chain, q0, sol.q, T, Ts, horizon)
        rows.append([tracked_hand_jerk(model, chain, q0, refs[k], Ts, horizon)
                     for k in ("minjerk", "vite", "dls")])
    a = np.array(rows)
    mean = a.mean(axis=0)
    return {
        "n": int(len(a)),
        "jerk_minjerk": float(mean[0]),
        "jerk_vite": float(mean[1]),
        "jerk_dls": float(mean[2]),
        "jerk_reduction_vs_vite": float(1 - mean[0] / mean[1]),
        "jerk_reduction_vs_dls": float(1 - mean[0] / mean[2]),
        "jerk_reduction_vs_vite_per_target_median": float(np.median(1 - a[:, 0] / a[:, 1])),
        "jerk_reduction_vs_dls_per_target_median": float(np.median(1 - a[:, 0] / a[:, 2])),
    }


# ---------------------------------------------------------------------------- main
def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer PMP and jerk targets (< 2 min)")
    ap.add_argument("--n", type=int, default=500, help="number of pose targets (>= 500)")
    ap.add_argument("--seed", type=int, default=2024)
    args = ap.parse_args(argv)
    n = args.n
    n_pmp = 40 if args.quick else 200
    n_jerk = 8 if args.quick else 30
    load0 = os.getloadavg()[0]
    t_start = time.perf_counter()
    model = IcubModel()
    chain = KinematicChain.from_name(CHAIN)

    t0 = time.perf_counter()
    ik = IkSolver(model, IkConfig())
    compiled = ik.problem(CHAIN).compiled
    ik_free = IkSolver(model, IkConfig(shoulder_constraints=False))
    ik_free.problem(CHAIN)
    build_s = time.perf_counter() - t0
    dls = DlsSolver(PinocchioJacobianProvider(model))
    pink_solver = PinkSolver(model)

    iterations: dict[str, list[int]] = {"pos": [], "pose": []}
    seeded: dict[str, list[bool]] = {"pos": [], "pose": []}
    # same-process baseline: IPOPT from the rest posture without the warm-start seed
    ik_noseed = IkSolver(model, IkConfig(seed_warm_start=False))
    ik_noseed.problem(CHAIN)

    def ipopt(solver, record=False):
        def solve(T, ori):
            sol = solver.solve(CHAIN, T.translation, T.rotation if ori else None)
            if record:
                iterations["pose" if ori else "pos"].append(sol.iterations)
                seeded["pose" if ori else "pos"].append(sol.seeded)
            return sol.q

        return solve

    def dls_fn(T, ori):
        return dls.solve_chain(CHAIN, T.translation, T.rotation if ori else None).joint_positions

    def pink_fn(T, ori):
        return pink_solver.solve(T, ori)[0]

    methods = {"ipopt": (ipopt(ik, record=True), n), "ipopt_noseed": (ipopt(ik_noseed), n),
               "dls": (dls_fn, n), "pink": (pink_fn, n)}
    pmp_note = None
    try:
        from icub_pmp.pmp import PmpPlanner, ReachGoal

        planner = PmpPlanner()
        rest_named = model.spec.posture("rest")

        def pmp_fn(T, ori):
            goal = ReachGoal(targets={"right": T.translation},
                             orientations={"right": T.rotation} if ori else {},
                             use_torso=True)
            plan = planner.plan(goal, rest_named)
            final = dict(zip(plan.joint_names, plan.positions[-1]))
            return np.array([final[j] for j in chain.joints])

        methods["pmp"] = (pmp_fn, n_pmp)
    except Exception as exc:  # the PMP library is another issue's work: report, do not fail
        pmp_note = f"PMP planner unavailable: {exc!r}"

    targets = make_targets(model, n, args.seed, constrained=True)
    # warm-up (first calls load libraries), not timed in the results
    for fn, _ in methods.values():
        fn(targets[0], False)
    for v in (*iterations.values(), *seeded.values()):
        v.clear()  # drop the warm-up call
    res = {k: summarise(v) for k, v in run_methods(model, targets, methods).items()}
    its = {k: np.array(v) for k, v in iterations.items()}
    free_targets = make_targets(model, n, args.seed + 1, constrained=False)
    free = {
        k: summarise(v)
        for k, v in run_methods(
            model, free_targets, {"ipopt": (ipopt(ik_free), n), "dls": (dls_fn, n),
                                  "pink": (pink_fn, n)}
        ).items()
    }
    t_jerk = time.perf_counter()
    jerk = jerk_comparison(model, n_jerk, args.seed + 2)
    jerk_s = time.perf_counter() - t_jerk

    report = {
        "n_targets": n,
        "compiled": compiled,
        "build_s": build_s,
        "primary_constrained": res,
        "free_unconstrained": free,
        "jerk": jerk,
        "pmp_note": pmp_note,
        "load_avg_start": load0,
        "load_avg_end": os.getloadavg()[0],
        "jerk_s": jerk_s,
        "total_s": time.perf_counter() - t_start,
    }
    out_dir = Path(__file__).resolve().parent / "out"
    out_dir.mkdir(exist_ok=True)
    (out_dir / "cartesian.json").write_text(json.dumps(report, indent=2))
    for label, block in (("constraints on", res), ("constraints off", free)):
        print(f"== {label} ({n} targets from rest)")
        for name, modes in block.items():
            for mode, s in modes.items():
                print(f"  {name:12s} {mode:4s} n={s['n']:4d} success {s['success_rate']:.4f}  "
                      f"pos {s['pos_err_mm_median']:.3f}/{s['pos_err_mm_p95']:.3f} mm  "
                      f"ori {s['ori_err_deg_median']:.3f}/{s['ori_err_deg_p95']:.3f} deg  "
                      f"time {s['ms_median']:.2f}/{s['ms_p95']:.2f} ms "
                      f"(cpu {s['cpu_ms_median']:.2f}/{s['cpu_ms_p95']:.2f})  "
                      f"limits {s['joint_limit_violations']} tendon {s['tendon_violations']}  "
                      f"torso {s['torso_deg_median']:.1f} deg")
    print(f"== jerk ({jerk['n']} reaches, 7-DoF pose): {json.dumps(jerk)}")
    if pmp_note:
        print(pmp_note)
    r = res["ipopt"]
    summary = {
        "success_rate_pos": r["pos"]["success_rate"],
        "success_rate_pose": r["pose"]["success_rate"],
        "solve_ms_median": r["pos"]["ms_median"],
        "solve_ms_p95": r["pos"]["ms_p95"],
        "solve_cpu_ms_median": r["pos"]["cpu_ms_median"],
        "solve_cpu_ms_p95": r["pos"]["cpu_ms_p95"],
        "solve_ms_median_pose": r["pose"]["ms_median"],
        "solve_ms_p95_pose": r["pose"]["ms_p95"],
        "solve_cpu_ms_median_pose": r["pose"]["cpu_ms_median"],
        "solve_cpu_ms_p95_pose": r["pose"]["cpu_ms_p95"],
        "ipopt_iter_median": float(np.median(its["pos"])),
        "ipopt_iter_p95": float(np.percentile(its["pos"], 95)),
        "ipopt_iter_median_pose": float(np.median(its["pose"])),
        "ipopt_iter_p95_pose": float(np.percentile(its["pose"], 95)),
        "seed_used_rate_pos": float(np.mean(seeded["pos"])),
        "seed_used_rate_pose": float(np.mean(seeded["pose"])),
        "noseed_solve_ms_median": res["ipopt_noseed"]["pos"]["ms_median"],
        "noseed_solve_cpu_ms_median": res["ipopt_noseed"]["pos"]["cpu_ms_median"],
        "noseed_solve_cpu_ms_p95": res["ipopt_noseed"]["pos"]["cpu_ms_p95"],
        "noseed_solve_cpu_ms_median_pose": res["ipopt_noseed"]["pose"]["cpu_ms_median"],
        "noseed_success_rate_pos": res["ipopt_noseed"]["pos"]["success_rate"],
        "noseed_success_rate_pose": res["ipopt_noseed"]["pose"]["success_rate"],
        "pos_err_mm_p95": r["pos"]["pos_err_mm_p95"],
        "ori_err_deg_p95_pose": r["pose"]["ori_err_deg_p95"],
        "joint_limit_violations": r["pos"]["joint_limit_violations"]
        + r["pose"]["joint_limit_violations"],
        "tendon_violations": r["pos"]["tendon_violations"] + r["pose"]["tendon_violations"],
        "free_success_rate_pos": free["ipopt"]["pos"]["success_rate"],
        "free_success_rate_pose": free["ipopt"]["pose"]["success_rate"],
        "dls_success_rate_pos": res["dls"]["pos"]["success_rate"],
        "dls_success_rate_pose": res["dls"]["pose"]["success_rate"],
        "dls_ms_median": res["dls"]["pos"]["ms_median"],
        "dls_cpu_ms_median": res["dls"]["pos"]["cpu_ms_median"],
        "pink_success_rate_pos": res["pink"]["pos"]["success_rate"],
        "pink_success_rate_pose": res["pink"]["pose"]["success_rate"],
        "pink_ms_median": res["pink"]["pos"]["ms_median"],
        "pink_cpu_ms_median": res["pink"]["pos"]["cpu_ms_median"],
        "pmp_success_rate_pos": res["pmp"]["pos"]["success_rate"] if "pmp" in res else None,
        "pmp_success_rate_pose": res["pmp"]["pose"]["success_rate"] if "pmp" in res else None,
        "pmp_n": res["pmp"]["pos"]["n"] if "pmp" in res else 0,
        "jerk_reduction_vs_vite": jerk["jerk_reduction_vs_vite"],
        "jerk_reduction_vs_dls": jerk["jerk_reduction_vs_dls"],
        "n_targets": n,
        "load_avg": round(max(load0, os.getloadavg()[0]), 2),
        "total_s": round(time.perf_counter() - t_start, 1),
    }
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
