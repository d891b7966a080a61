"""Benchmark of the PMP planner against a damped-least-squares baseline.

    scripts/env.sh python bench/pmp.py --quick          # 200 targets, < 2 min
    scripts/env.sh python bench/pmp.py                  # 1000 targets
    scripts/env.sh python bench/pmp.py --quick --plot   # + Fig 4/9 and Fig 7 PNGs in bench/out/

Targets: a fixed set (seed) of random reachable bimanual targets for the 17-DoF left arm -
torso - right arm chain: both hand positions are those of one configuration drawn uniformly
within the URDF joint limits (so a solution exists). Every plan starts from the rest posture,
tau = 2 s, default config/pmp_planner.yaml gains. Success = both hands within 1 mm of their
targets at t = tau, checked by an independent forward kinematics of the plan's last sample.
Plan time = wall time of ``PmpPlanner.plan`` (CPU time of the thread also reported: on a
loaded machine it stays near the unloaded wall time) (relaxation, posture-memory fallback when used,
TBG sampling of the trajectory, residuals); the posture memory is built once before timing
(reported as memory_build_s) and the predicted hand paths (computed on demand, for the node's
nav_msgs/Path) are timed separately. The same targets go to DLS (icub_pmp.baselines.DlsSolver, same
joints, limits and start): once from the rest posture (the ``dls_*`` keys) and, for a fair
comparison with PMP's posture-memory retries, with restarts: the same budget of tries as PMP
(1 + ``posture_memory_attempts``), each restart from a configuration drawn uniformly within the
joint limits (seeded), stopping at the first success (the ``dls_restart_*`` keys; the time is
that of all the tries). Joint-limit violations: plans with any trajectory sample (PMP) or final
configuration (DLS) outside the URDF limits (goal 0). Ends with one JSON line. Timings depend on
the machine's load.

The request fields of /pmp/reach (built as pmp_planner builds them, config/pmp_planner.yaml's
defaults of icub_pmp.ros.reach_request.ReachRequestConfig), on scenes of their own seeds, each
judged by an independent forward kinematics of the sampled plan (50 scenes each, 10 --quick):

- transport (Sect. 3.2, Fig 8): the object held between the hands at rest goes to a random goal
  (within +-8 cm in x, y and 0..15 cm up); ``transport_hand_dist_err_mm_max`` = the largest
  change of the hand-to-hand distance along any plan; baseline in the same scenes: both hands
  sent to independent targets moved by the same offset (the demo's former transport);
- obstacles: a random right-hand target (a random right-arm posture), a sphere (radius 2-4 cm)
  centred on the free plan's mid-path point, clearance 2 cm: ``obstacle_success_rate`` (target
  reached and the clearance kept) and ``obstacle_clearance_min_mm`` (smallest distance of the
  hand frame and of the hand's, wrist's and forearm's collision hulls to the surface over the
  successful plans; scenes where that arm starts within the clearance are skipped);
  ``obstacle_hand_frames_only_rate``: scenes answered with the hand frames kept clear only
  (no plan keeping the arm's volume clear reached; decision 0063);
- force targets (Sect. 2.3, Fig 3): the same kind of targets with a 10 N force in a random
  direction; the joint needing the largest fraction of its rating is limited to half the torque
  the free plan needs there: ``force_target_torque_ok_rate`` = plans reaching the target with
  every network joint within its limit (baseline: the free plan under the same limit).
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

from icub_pmp.baselines import PMP_DLS_CONFIG, DlsSolver  # noqa: E402
from icub_pmp.peripersonal import ArmBodyModel  # noqa: E402
from icub_pmp.pmp import (  # noqa: E402
    HeldObject,
    ObstacleField,
    PmpPlanner,
    ReachGoal,
    TimeBaseGenerator,
)
from icub_pmp.pmp.body_volume import hull_distances  # noqa: E402
from icub_pmp.ros.reach_request import ReachRequestConfig  # noqa: E402

OUT = Path(__file__).resolve().parent / "out"
SUCCESS = 1e-3  # [m]
TAU = 2.0  # [s]


def make_targets(planner: PmpPlanner, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(targets (n, 2, 3) [m], the configurations (n, nq) that reach them)."""
    prov, spec = planner.provider, planner.spec
    joints = spec.torso_joints + spec.left_arm_joints + spec.right_arm_joints
    idx = [prov.joint_names.index(j) for j in joints]
    frames = [spec.hand_frame("left"), spec.hand_frame("right")]
    rng = np.random.default_rng(seed)
    rest = planner.start_configuration(None)
    qs = np.repeat(rest[None], n, axis=0)
    qs[:, idx] = rng.uniform(prov.lower[idx], prov.upper[idx], size=(n, len(idx)))
    return np.array([prov.positions(q, frames) for q in qs]), qs


def outside_limits(planner: PmpPlanner, joints, positions: np.ndarray) -> bool:
    """Whether any row of ``positions`` (k, len(joints)) [rad] leaves the URDF joint range."""
    idx = [planner.provider.joint_names.index(j) for j in joints]
    lo, hi = planner.provider.lower[idx], planner.provider.upper[idx]
    return bool(np.any(positions < lo - 1e-9) or np.any(positions > hi + 1e-9))


def run_pmp(planner: PmpPlanner, targets: np.ndarray) -> dict:
    prov, spec = planner.provider, planner.spec
    frames = [spec.hand_frame("left"), spec.hand_frame("right")]
    rest = planner.start_configuration(None)
    times, cpu, paths_times, residuals, steps, fallback = [], [], [], [], [], 0
    violations = 0
    for x in targets:
        goal = ReachGoal(targets={"left": x[0], "right": x[1]}, tau=TAU)
        c0 = time.thread_time()
        t0 = time.perf_counter()
        plan = planner.plan(goal, rest)
        t1 = time.perf_counter()
        cpu.append(time.thread_time() - c0)
        _ = plan.hand_paths
        t2 = time.perf_counter()
        final = prov.positions(plan.q_final, frames)  # independent check of the verdict
        residuals.append(float(np.linalg.norm(final - x, axis=1).max()))
        times.append(t1 - t0)
        paths_times.append(t2 - t0)
        steps.append(plan.trace.steps)
        fallback += plan.attempts > 1
        violations += outside_limits(planner, plan.joint_names, plan.positions)
    return {
        "violations": violations,
        "times": np.array(times) * 1e3,
        "cpu": np.array(cpu) * 1e3,
        "paths_times": np.array(paths_times) * 1e3,
        "residuals": np.array(residuals),
        "steps": np.array(steps),
        "fallback": fallback,
    }


def run_dls(planner: PmpPlanner, targets: np.ndarray, tries: int = 1, seed: int = 0) -> dict:
    """DLS on every target from the rest posture; when it fails and ``tries`` > 1, up to
    ``tries`` - 1 restarts from uniform random configurations within the limits (seeded)."""
    spec, prov = planner.spec, planner.provider
    joints = spec.torso_joints + spec.left_arm_joints + spec.right_arm_joints
    idx = [prov.joint_names.index(j) for j in joints]
    dls = DlsSolver(prov, PMP_DLS_CONFIG)
    hands = [spec.hand_frame("left"), spec.hand_frame("right")]
    rest = planner.start_configuration(None)
    rng = np.random.default_rng(seed)
    times, cpu, residuals, iters, used, violations = [], [], [], [], [], 0
    for x in targets:
        c0 = time.thread_time()
        t0 = time.perf_counter()
        start, best, n_tries = rest, None, 0
        while n_tries < tries:
            n_tries += 1
            sol = dls.solve(start, joints, hands, x)
            if best is None or sol.position_error < best.position_error:
                best = sol
            if sol.success:
                break
            start = rest.copy()
            start[idx] = rng.uniform(prov.lower[idx], prov.upper[idx])
        times.append(time.perf_counter() - t0)
        cpu.append(time.thread_time() - c0)
        residuals.append(best.position_error)
        iters.append(best.iterations)
        used.append(n_tries)
        violations += outside_limits(planner, joints, best.q[idx][None])
    return {"times": np.array(times) * 1e3, "cpu": np.array(cpu) * 1e3,
            "residuals": np.array(residuals),
            "iterations": np.array(iters), "tries": np.array(used), "violations": violations}


# ---------------------------------------------------------------------------- request fields
def _hands_at(planner: PmpPlanner, q: np.ndarray) -> np.ndarray:
    spec = planner.spec
    return planner.provider.positions(q, [spec.hand_frame("left"), spec.hand_frame("right")])


def _hand_distance_error(planner: PmpPlanner, plan) -> float:
    """Largest change of the hand-to-hand distance along the plan [m] (forward kinematics of
    every sample, other joints at the start)."""
    names = planner.provider.joint_names
    idx = [names.index(j) for j in plan.joint_names]
    d = []
    for row in plan.positions:
        q = plan.q_start.copy()
        q[idx] = row
        x = _hands_at(planner, q)
        d.append(np.linalg.norm(x[0] - x[1]))
    return float(np.max(np.abs(np.array(d) - d[0])))


def run_transport(planner: PmpPlanner, n: int, seed: int) -> dict:
    """Coupled transport (held object) vs independent hand targets, same goals."""
    cfg = ReachRequestConfig()
    rng = np.random.default_rng(seed)
    rest = planner.start_configuration(None)
    x0 = _hands_at(planner, rest)
    mid = x0.mean(axis=0)
    coupled, independent, ok, times = [], [], 0, []
    for _ in range(n):
        offset = rng.uniform([-0.08, -0.08, 0.0], [0.08, 0.08, 0.15])
        held = HeldObject(mid, mid + offset, {"left": x0[0] - mid, "right": x0[1] - mid},
                          goal_stiffness=cfg.object_goal_stiffness,
                          grasp_stiffness=cfg.object_grasp_stiffness,
                          admittance=cfg.object_admittance)
        t0 = time.perf_counter()
        plan = planner.plan(ReachGoal(held_object=held, tau=TAU), rest)
        times.append(time.perf_counter() - t0)
        ok += plan.success
        coupled.append(_hand_distance_error(planner, plan))
        free = planner.plan(ReachGoal(targets={"left": x0[0] + offset, "right": x0[1] + offset},
                                      tau=TAU), rest)
        independent.append(_hand_distance_error(planner, free))
    return {"coupled": np.array(coupled), "independent": np.array(independent),
            "success": ok / n, "times": np.array(times) * 1e3}


def _right_targets(planner: PmpPlanner, rng, min_dist: float) -> np.ndarray:
    """A reachable right-hand target (a random right-arm posture) at least ``min_dist`` [m]
    from the rest hand."""
    prov, spec = planner.provider, planner.spec
    idx = [prov.joint_names.index(j) for j in spec.right_arm_joints]
    rest = planner.start_configuration(None)
    start = _hands_at(planner, rest)[1]
    while True:
        q = rest.copy()
        q[idx] = rng.uniform(prov.lower[idx], prov.upper[idx])
        x = _hands_at(planner, q)[1]
        if np.linalg.norm(x - start) >= min_dist:
            return x


#: the right arm's links whose collision hulls (what the physics collides) the obstacle scenes
#: judge, besides the hand frame
OBSTACLE_LINKS = ("hand", "wrist_1", "forearm")


def run_obstacles(planner: PmpPlanner, n: int, seed: int, clearance: float = 0.02) -> dict:
    """A sphere on the free plan's path; plan around it with the clearance."""
    cfg = ReachRequestConfig()
    rng = np.random.default_rng(seed)
    rest = planner.start_configuration(None)
    start = _hands_at(planner, rest)[1]
    success, kept, through, times, hand_only = [], [], 0, [], 0
    hulls = ArmBodyModel.from_urdf(planner.provider, links=OBSTACLE_LINKS).hulls["right"]
    while len(success) < n:
        target = _right_targets(planner, rng, 0.15)
        free = planner.plan(ReachGoal(targets={"right": target}, tau=TAU), rest)
        if not free.success:
            continue
        path = free.hand_paths["right"]
        centre, radius = path[len(path) // 2], float(rng.uniform(0.02, 0.04))
        if min(np.linalg.norm(start - centre), np.linalg.norm(target - centre)) < \
                radius + clearance + 0.01:
            continue  # start or target within the clearance: the request would be rejected
        ob = ObstacleField(centre, radius, cfg.obstacle_influence, cfg.obstacle_gain,
                           inflation=clearance + cfg.obstacle_margin)
        goal = ReachGoal(targets={"right": target}, tau=TAU, obstacles=(ob,))
        if planner.build_network(goal, rest).body_clearances(rest[None])[1][0] < 0.0:
            continue  # the arm (hand, wrist, forearm) starts within the clearance
        through += np.min(np.linalg.norm(path - centre, axis=1)) < radius
        t0 = time.perf_counter()
        plan = planner.plan(goal, rest)
        times.append(time.perf_counter() - t0)
        hand_only += plan.hand_frames_only
        final = _hands_at(planner, plan.q_final)[1]
        d = min(float(np.min(ob.surface_distance(plan.hand_paths["right"]))),
                float(hull_distances(planner.provider, hulls,
                                     plan.configurations(planner.provider.joint_names),
                                     ob).min()))
        reached = np.linalg.norm(final - target) <= SUCCESS
        success.append(bool(reached and d >= clearance))
        kept.append(d if reached else np.inf)
    kept_ok = [k for k, s in zip(kept, success) if s]
    return {"success": float(np.mean(success)), "through": through / n,
            "hand_frames_only": hand_only / n,
            "clearance_min": min(kept_ok) if kept_ok else float("nan"),
            "times": np.array(times) * 1e3}


def run_force_targets(planner: PmpPlanner, n: int, seed: int, force: float = 10.0) -> dict:
    """A force target with the most loaded joint limited to half its free-plan torque."""
    rng = np.random.default_rng(seed)
    rest = planner.start_configuration(None)
    ok, free_ok, times = [], [], []
    while len(ok) < n:
        target = _right_targets(planner, rng, 0.05)
        f = rng.normal(size=3)
        f *= force / np.linalg.norm(f)
        goal = ReachGoal(targets={"right": target}, tau=TAU, target_forces={"right": f})
        free = planner.plan(goal, rest)
        if not free.success:
            continue
        ratio = np.abs(free.final_torques) / free.torque_limits
        k = int(np.argmax(ratio))
        joint, limit = free.joint_names[k], 0.5 * abs(float(free.final_torques[k]))
        free_ok.append(bool(np.all(np.abs(free.final_torques) <= np.where(
            np.arange(len(ratio)) == k, limit, free.torque_limits))))
        t0 = time.perf_counter()
        plan = planner.plan(ReachGoal(targets={"right": target}, tau=TAU,
                                      target_forces={"right": f},
                                      torque_limits={joint: limit}), rest)
        times.append(time.perf_counter() - t0)
        final = _hands_at(planner, plan.q_final)[1]
        within = bool(np.all(np.abs(plan.final_torques) <= plan.torque_limits))
        ok.append(bool(within and np.linalg.norm(final - target) <= SUCCESS))
    return {"ok": float(np.mean(ok)), "free_ok": float(np.mean(free_ok)),
            "times": np.array(times) * 1e3}


# ---------------------------------------------------------------------------- plots
def plot_fig4_fig9(planner: PmpPlanner, targets: np.ndarray) -> list[str]:
    """Fig 4 / Fig 9 equivalents: joint and hand trajectories, speed profile, xi and Gamma."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rest = planner.start_configuration(None)
    x = targets[0]
    plan = planner.plan(ReachGoal(targets={"left": x[0], "right": x[1]}, tau=TAU), rest)
    tbg = TimeBaseGenerator(TAU)
    t = np.linspace(0, TAU, 400)
    fig, ax = plt.subplots(2, 2, figsize=(11, 7.5))
    for j, name in enumerate(plan.joint_names):
        ax[0, 0].plot(plan.t, plan.positions[:, j], lw=1, label=name)
    ax[0, 0].set(title="joint trajectories q(t) (17-DoF network)", xlabel="t [s]",
                 ylabel="[rad]")
    ax[0, 0].legend(fontsize=5, ncol=3)
    for h, c in (("left", "tab:blue"), ("right", "tab:red")):
        p = plan.hand_paths[h]
        for k, ls in zip(range(3), ("-", "--", ":")):
            ax[0, 1].plot(plan.t, p[:, k], ls, color=c, label=f"{h} {'xyz'[k]}")
        ax[1, 0].plot(plan.t, plan.hand_speed(h), color=c, label=f"{h} hand")
    ax[0, 1].set(title="hand trajectories x(t), root_link", xlabel="t [s]", ylabel="[m]")
    ax[0, 1].legend(fontsize=6, ncol=2)
    ax[1, 0].set(title="hand speed (bell-shaped, Appendix A)", xlabel="t [s]", ylabel="[m/s]")
    ax[1, 0].legend()
    ax[1, 1].plot(t, tbg.xi(t), label="xi(t) (min-jerk TBG, eq 7)")
    ax2 = ax[1, 1].twinx()
    ax2.plot(t[:-1], tbg.gamma(t[:-1]), color="tab:orange", label="Gamma(t)")
    ax2.set_yscale("log")
    ax2.set_ylabel("Gamma [1/s]")
    ax[1, 1].set(title="TBG: xi(t) and Gamma(t) = xi_dot/(1 - xi)", xlabel="t [s]")
    ax[1, 1].legend(loc="upper left")
    ax2.legend(loc="center right")
    fig.suptitle(f"PMP bimanual reach, tau = {TAU} s: {plan.message}", fontsize=8)
    fig.tight_layout()
    out = OUT / "pmp_fig4_fig9.png"
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return [str(out)]


def plot_fig7(planner: PmpPlanner) -> list[str]:
    """Fig 7 equivalent: trunk recruitment vs target distance, stiff vs compliant trunk."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    prov, spec = planner.provider, planner.spec
    rest = planner.start_configuration(None)
    frames = [spec.hand_frame("left"), spec.hand_frame("right")]
    x0 = prov.positions(rest, frames)
    torso = [prov.joint_names.index(j) for j in spec.torso_joints]
    dists = np.linspace(0.0, 0.24, 13)
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for scale, style in ((0.0, "k--"), (0.2, "b-"), (1.0, "g-"), (5.0, "r-")):
        motion, res = [], []
        for d in dists:
            targets = {"left": x0[0] + [-d, 0, d], "right": x0[1] + [-d, 0, d]}
            plan = planner.plan(ReachGoal(targets=targets, trunk_admittance_scale=scale), rest)
            motion.append(np.degrees(np.linalg.norm(plan.q_final[torso] - rest[torso])))
            res.append(plan.max_residual * 1e3)
        label = "stiff trunk (A_trunk = 0)" if scale == 0 else f"A_trunk x {scale}"
        ax[0].plot(dists * np.sqrt(2) * 100, motion, style, label=label)
        ax[1].plot(dists * np.sqrt(2) * 100, res, style, label=label)
    ax[0].set(title="trunk recruitment (Fig 7)", xlabel="target distance from rest hands [cm]",
              ylabel="|trunk motion| [deg]")
    ax[1].set(title="residual at tau (mental simulation)", xlabel="target distance [cm]",
              ylabel="[mm]")
    ax[1].set_yscale("symlog", linthresh=1.0)
    for a in ax:
        a.legend(fontsize=8)
    fig.tight_layout()
    out = OUT / "pmp_fig7_trunk.png"
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return [str(out)]


# ---------------------------------------------------------------------------- main
def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="200 targets (< 2 min)")
    ap.add_argument("--n", type=int, default=None, help="number of targets")
    ap.add_argument("--seed", type=int, default=2009)
    ap.add_argument("--plot", action="store_true", help="write PNG figures to bench/out/")
    args = ap.parse_args()
    n = args.n or (200 if args.quick else 1000)
    load = os.getloadavg()[0]

    planner = PmpPlanner()
    t0 = time.perf_counter()
    planner.warm_up()
    memory_s = time.perf_counter() - t0
    targets, _ = make_targets(planner, n, args.seed)
    rest = planner.start_configuration(None)
    for x in targets[:5]:  # warm-up plans (imports, caches), not timed
        planner.plan(ReachGoal(targets={"left": x[0], "right": x[1]}, tau=TAU), rest)

    pmp = run_pmp(planner, targets)
    dls = run_dls(planner, targets)
    n_scenes = 10 if args.quick else 50
    transport = run_transport(planner, n_scenes, args.seed + 1)
    obstacles = run_obstacles(planner, n_scenes, args.seed + 2)
    forces = run_force_targets(planner, n_scenes, args.seed + 3)
    budget = 1 + planner.config.posture_memory_attempts  # PMP's tries: relaxation + recalls
    dls_r = run_dls(planner, targets, budget, args.seed)

    ok = pmp["residuals"] <= SUCCESS
    dok = dls["residuals"] <= SUCCESS
    rok = dls_r["residuals"] <= SUCCESS
    r = {
        "n_targets": n,
        "seed": args.seed,
        "tau_s": TAU,
        "success_rate": float(ok.mean()),
        "plan_ms_median": float(np.median(pmp["times"])),
        "plan_ms_p95": float(np.percentile(pmp["times"], 95)),
        "plan_ms_max": float(pmp["times"].max()),
        "plan_cpu_ms_median": float(np.median(pmp["cpu"])),
        "plan_cpu_ms_p95": float(np.percentile(pmp["cpu"], 95)),
        "plan_with_paths_ms_median": float(np.median(pmp["paths_times"])),
        "residual_mm_median": float(np.median(pmp["residuals"]) * 1e3),
        "residual_mm_p95": float(np.percentile(pmp["residuals"], 95) * 1e3),
        "relaxation_steps_median": float(np.median(pmp["steps"])),
        "memory_fallback_plans": int(pmp["fallback"]),
        "memory_build_s": memory_s,
        "dls_success_rate": float(dok.mean()),
        "dls_ms_median": float(np.median(dls["times"])),
        "dls_ms_p95": float(np.percentile(dls["times"], 95)),
        "dls_cpu_ms_median": float(np.median(dls["cpu"])),
        "dls_residual_mm_median": float(np.median(dls["residuals"]) * 1e3),
        "dls_iterations_median": float(np.median(dls["iterations"])),
        "plan_to_dls_time_ratio": float(np.median(pmp["times"]) / np.median(dls["times"])),
        "field_scenes": n_scenes,
        "transport_hand_dist_err_mm_max": float(transport["coupled"].max() * 1e3),
        "transport_hand_dist_err_mm_median": float(np.median(transport["coupled"]) * 1e3),
        "transport_success_rate": float(transport["success"]),
        "transport_independent_hand_dist_err_mm_max": float(
            transport["independent"].max() * 1e3),
        "transport_plan_ms_median": float(np.median(transport["times"])),
        "obstacle_success_rate": obstacles["success"],
        "obstacle_clearance_min_mm": float(obstacles["clearance_min"] * 1e3),
        "obstacle_free_plan_through_rate": float(obstacles["through"]),
        "obstacle_hand_frames_only_rate": float(obstacles["hand_frames_only"]),
        "obstacle_plan_ms_median": float(np.median(obstacles["times"])),
        "force_target_torque_ok_rate": forces["ok"],
        "force_target_free_plan_ok_rate": forces["free_ok"],
        "force_target_plan_ms_median": float(np.median(forces["times"])),
        "joint_limit_violations": int(pmp["violations"]),
        "dls_joint_limit_violations": int(dls["violations"]),
        "tries_budget": budget,
        "dls_restart_success_rate": float(rok.mean()),
        "dls_restart_ms_median": float(np.median(dls_r["times"])),
        "dls_restart_ms_p95": float(np.percentile(dls_r["times"], 95)),
        "dls_restart_residual_mm_median": float(np.median(dls_r["residuals"]) * 1e3),
        "dls_restart_tries_mean": float(dls_r["tries"].mean()),
        "dls_restart_joint_limit_violations": int(dls_r["violations"]),
        "load_avg_1min": load,
    }
    print(f"PMP  success {r['success_rate']:.3f}  plan median {r['plan_ms_median']:.2f} ms  "
          f"p95 {r['plan_ms_p95']:.2f} ms  residual median {r['residual_mm_median']:.4f} mm  "
          f"p95 {r['residual_mm_p95']:.4f} mm  steps median {r['relaxation_steps_median']:.0f}  "
          f"posture-memory fallback {r['memory_fallback_plans']}/{n}  (CPU time median "
          f"{r['plan_cpu_ms_median']:.2f} ms, p95 {r['plan_cpu_ms_p95']:.2f} ms)")
    print(f"DLS  success {r['dls_success_rate']:.3f}  median {r['dls_ms_median']:.2f} ms  "
          f"p95 {r['dls_ms_p95']:.2f} ms  iterations median {r['dls_iterations_median']:.0f}")
    print(f"transport: hand-to-hand distance change max {r['transport_hand_dist_err_mm_max']:.2f}"
          f" mm (independent targets {r['transport_independent_hand_dist_err_mm_max']:.1f} mm), "
          f"success {r['transport_success_rate']:.2f}; obstacles: success "
          f"{r['obstacle_success_rate']:.2f}, clearance min {r['obstacle_clearance_min_mm']:.1f} "
          f"mm (asked 20); force targets: torques ok {r['force_target_torque_ok_rate']:.2f} "
          f"(free plan {r['force_target_free_plan_ok_rate']:.2f})")
    print(f"DLS with up to {budget} tries (PMP's budget)  success "
          f"{r['dls_restart_success_rate']:.3f}  median {r['dls_restart_ms_median']:.2f} ms  "
          f"tries mean {r['dls_restart_tries_mean']:.2f}; joint-limit violations PMP "
          f"{r['joint_limit_violations']}, DLS {r['dls_joint_limit_violations']}, "
          f"DLS with restarts {r['dls_restart_joint_limit_violations']}")
    failed = np.flatnonzero(~ok)
    if failed.size:
        print("PMP failures (target index: residual mm):",
              ", ".join(f"{i}: {pmp['residuals'][i] * 1e3:.1f}" for i in failed[:20]))
    if args.plot:
        OUT.mkdir(parents=True, exist_ok=True)
        files = plot_fig4_fig9(planner, targets) + plot_fig7(planner)
        print("plots:", ", ".join(files))
    print(json.dumps(r))


if __name__ == "__main__":
    main()
