"""The demo report: PNG plots from the recorded bag and a Markdown summary table.

Plots: hand paths (top and side views) with the phase targets; hand speed profiles with the
time-base generator's Gamma(t) (PMP eq 7, Appendix A); joint tracking error (planned
trajectory vs measured joints); FT sensor and estimated external wrench vs ground truth.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from icub_pmp.demo.bag_series import BagSeries, read_bag_series
from icub_pmp.kinematics import IcubModel

__all__ = ["write_report", "min_jerk_gamma"]


def min_jerk_gamma(t: np.ndarray, tau: float) -> np.ndarray:
    """Gamma(t) = xi_dot / (1 - xi) of the minimum-jerk TBG (PMP eq 7), 0 outside [0, tau)."""
    z = np.clip(t / tau, 0.0, 1.0)
    xi = 6 * z**5 - 15 * z**4 + 10 * z**3
    xid = (30 * z**4 - 60 * z**3 + 30 * z**2) / tau
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where((z > 0) & (z < 1), xid / np.maximum(1 - xi, 1e-9), 0.0)
    return g


def _hand_series(series: BagSeries, model: IcubModel) -> dict[str, np.ndarray]:
    js = series.joints
    out: dict[str, list[np.ndarray]] = {"left": [], "right": []}
    for p in js.position:
        q = model.q_from_dict(dict(zip(js.names, p)))
        model.forward(q)
        for h in out:
            fid = model.frame_id(model.spec.hand_frame(h))
            out[h].append(model.data.oMf[fid].translation.copy())
    return {h: np.array(v) for h, v in out.items()}


def write_report(out_dir: Path, bag_dir: Path, results: list[Any],
                 replay: dict[str, Any]) -> Path:
    """Write PNGs, results.json and report.md into ``out_dir``; returns the report path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "results.json").write_text(json.dumps(
        {"phases": [asdict(r) for r in results],
         "replay": {k: v for k, v in replay.items() if k != "info"}}, indent=2))
    figures: list[str] = []
    notes: list[str] = []
    series: BagSeries | None = None
    try:
        series = read_bag_series(bag_dir)
    except Exception as exc:  # the report still lists the phases
        notes.append(f"bag could not be read: {exc}")
    if series is not None and series.joints is not None:
        model = IcubModel()
        hands = _hand_series(series, model)
        t = series.joints.t
        # 1. hand paths
        fig, ax = plt.subplots(1, 2, figsize=(11, 4.5))
        for h, c in (("left", "tab:blue"), ("right", "tab:red")):
            ax[0].plot(hands[h][:, 1], -hands[h][:, 0], c, label=f"{h} hand")
            ax[1].plot(-hands[h][:, 0], hands[h][:, 2], c, label=f"{h} hand")
        for r in results:
            for p in r.targets.values():
                ax[0].plot(p[1], -p[0], "kx")
                ax[1].plot(-p[0], p[2], "kx")
                ax[0].annotate(r.name, (p[1], -p[0]), fontsize=7)
        ax[0].set(xlabel="y (right) [m]", ylabel="forward (-x) [m]", title="top view")
        ax[1].set(xlabel="forward (-x) [m]", ylabel="z [m]", title="side view")
        for a in ax:
            a.axis("equal")
            a.grid(True)
            a.legend()
        fig.tight_layout()
        fig.savefig(out_dir / "hand_paths.png", dpi=110)
        plt.close(fig)
        figures.append("hand_paths.png")
        # 2. speed profiles + Gamma
        fig, ax = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
        for h, c in (("left", "tab:blue"), ("right", "tab:red")):
            v = np.linalg.norm(np.gradient(hands[h], t, axis=0), axis=1)
            ax[0].plot(t, v, c, label=f"{h} hand speed")
        for r in results:
            if r.sim_end > r.sim_start:
                ax[0].axvspan(r.sim_start, r.sim_end, alpha=0.08)
                ax[0].text(r.sim_start, 0, r.name, fontsize=7, rotation=90, va="bottom")
                if r.name.startswith("cartesian"):
                    continue  # minimum-jerk controller, no time-base generator
                tau = max(r.sim_end - r.sim_start - 1.0, 0.1)
                tt = np.linspace(0, tau, 200)
                ax[1].plot(r.sim_start + tt, min_jerk_gamma(tt, tau), label=r.name)
        ax[0].set(ylabel="speed [m/s]", title="hand speed (measured in the physics)")
        ax[1].set(xlabel="sim time [s]", ylabel="Gamma(t) [1/s]", ylim=(0, 20),
                  title="time-base generator Gamma(t) = xi_dot / (1 - xi) (eq 7)")
        for a in ax:
            a.grid(True)
            a.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(out_dir / "speed_profiles.png", dpi=110)
        plt.close(fig)
        figures.append("speed_profiles.png")
        # 3. tracking error against the last trajectory that covers each sample
        if series.trajectories:
            fig, ax = plt.subplots(figsize=(10, 4))
            name_idx = {n: i for i, n in enumerate(series.joints.names)}
            for k, (t0, names, times, pos) in enumerate(series.trajectories):
                t_end = series.trajectories[k + 1][0] if k + 1 < len(series.trajectories) else 1e18
                mask = (t >= t0) & (t <= min(t0 + times[-1] + 1.0, t_end))
                if mask.sum() < 2:
                    continue
                cols = [name_idx[n] for n in names if n in name_idx]
                sel = [i for i, n in enumerate(names) if n in name_idx]
                des = np.array([np.interp(t[mask] - t0, times, pos[:, j]) for j in sel]).T
                err = np.degrees(np.abs(series.joints.position[mask][:, cols] - des))
                ax.plot(t[mask], err.max(axis=1), "k", lw=0.8)
                ax.plot(t[mask], np.sqrt((err**2).mean(axis=1)), "tab:orange", lw=0.8)
            ax.set(xlabel="sim time [s]", ylabel="[deg]",
                   title="joint tracking error: max (black), RMS (orange) over the moving joints")
            ax.grid(True)
            fig.tight_layout()
            fig.savefig(out_dir / "tracking_error.png", dpi=110)
            plt.close(fig)
            figures.append("tracking_error.png")
    if series is not None and series.wrenches:
        wanted = [k for k in series.wrenches if k.endswith(("r_arm_ft", "right_hand"))]
        if wanted:
            fig, ax = plt.subplots(len(wanted), 1, figsize=(10, 2.4 * len(wanted)), sharex=True)
            ax = np.atleast_1d(ax)
            for a, k in zip(ax, wanted):
                ws = series.wrenches[k]
                for i, lab in enumerate(("fx", "fy", "fz")):
                    a.plot(ws.t, ws.wrench[:, i], lw=0.7, label=lab)
                a.set(title=f"{k} [{ws.frame_id}]", ylabel="[N]")
                a.grid(True)
                a.legend(fontsize=7, loc="upper right")
            ax[-1].set(xlabel="sim time [s]")
            fig.tight_layout()
            fig.savefig(out_dir / "wrenches.png", dpi=110)
            plt.close(fig)
            figures.append("wrenches.png")
    lines = ["# icub_pmp demo report", "",
             "| phase | result | planned residual [mm] | residual in the physics [mm] | "
             "other | sim time [s] | wall time [s] |", "|---|---|---|---|---|---|---|"]
    for r in results:
        pr = ", ".join(f"{h} {v * 1e3:.2f}" for h, v in r.planned_residual.items()) or "-"
        ph = ", ".join(f"{h} {v * 1e3:.1f}" for h, v in r.physics_residual.items()) or "-"
        ex = ", ".join(f"{k} {v:.3f}" for k, v in r.extra.items()) or "-"
        lines.append(f"| {r.name} | {_status(r)} | {pr} | "
                     f"{ph} | {ex} | {r.sim_end - r.sim_start:.2f} | {r.wall_s:.1f} |")
    lines += ["", f"Replay: {replay.get('message', '-')}", ""]
    if series is not None:
        lines += ["## Recorded messages", "", "| topic | messages |", "|---|---|"]
        lines += [f"| {k} | {v} |" for k, v in sorted(series.counts.items())]
    lines += [""] + [f"![{f}]({f})" for f in figures] + [""] + notes
    path = out_dir / "report.md"
    path.write_text("\n".join(lines) + "\n")
    return path


def _status(r: Any) -> str:
    """A phase's outcome for the report table (a provisional phase's failure says so)."""
    if r.success:
        return "ok"
    if getattr(r, "required", True):
        return f"FAILED: {r.message}"
    return f"NOT MET (judged, not yet failing the demo: issue 20): {r.message}"
