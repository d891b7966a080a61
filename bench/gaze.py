"""Benchmark of the gaze controller: fixation accuracy and settling time in the
simulator through the real controller loop, and the motion segmenter's F1 while the head
tracks a moving object.

    scripts/env.sh python bench/gaze.py --quick     # < 2 min
    scripts/env.sh python bench/gaze.py             # 100 points, longer tracking sequences

1. Fixation. The in-process lockstep loop (icub_pmp.control.SimLoop: the MuJoCo simulator, the
   wrench estimator and the 1 kHz impedance controller; ``position`` mode as the demo and the
   graph tests run it, ``--mode`` to change) looks at random points in front of the robot, one
   after the other from wherever the previous look left the head (x -0.65..-0.2, y
   -0.35..0.35, z -0.05..0.45 m in root_link, seed 2026: not the tests' points). Each look goes
   the way the node sends it: GazeController.plan -> a joint trajectory of the six head joints
   -> ImpedanceController.set_trajectory -> torques -> physics. Every 5 ms the point is
   projected into both cameras with the simulator's true camera poses (the optical-frame sites
   ``l_eye_optical`` / ``r_eye_optical`` the eye cameras are mounted at; fx = fy = 343.12,
   320x240). ``fixation_err_px``: the larger distance of the projection from the image centre
   of the two cameras once the motion is over (end of the plan + 0.2 s), median over the
   points (goal <= 2 px). ``settle_ms_median``: from the command until the projection stays
   within 2 px in both cameras (median over the points that settle). ``plan_ms_median``: the
   core's solve + trajectory rollout (wall time, load-dependent).
2. Tracking. The motion segmenter's sequences (icub_sim_bridge.harness.sequence_generator: the
   simulator's scene with textures and an 8 cm textured ball) are rendered from the robot's
   posture in the same physics loop while the gaze controller tracks the ball: the ball moves
   back and forth across the table (+-10 cm in y at 10 and 20 cm/s), and each camera frame
   (30 Hz) gives the gaze controller the ball's position (ground truth: the bench scores the
   segmenter, not a target estimate) as a tracking update (GazeController.update: the head
   continues from its running plan). The left image goes through MotionSegmenter (defaults of
   config/motion_segmenter.yaml); ``tracking_f1``: pixel F1 of its mask against MuJoCo's
   segmentation of the ball inside the grid's region, as bench/motion.py scores it, pooled over
   the frames after a lead-in without the ball (goal >= 0.8). For reference, ``still_f1``: the
   same ball motions with the head still, and ``tracking_err_px_median``: the ball's distance
   from the image centre while tracked.

Ends with ONE JSON line. Timings depend on the machine's load (printed).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MUJOCO_GL", "egl")

import cv2  # noqa: E402
import mujoco  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from motion import _roi  # noqa: E402  (bench/motion.py: the grid region it scores F1 in)

from icub_pmp.baselines.segmentation_metrics import SegmentationCounts  # noqa: E402
from icub_pmp.baselines.synthetic_sequence import triangle_wave  # noqa: E402
from icub_pmp.control.impedance_controller_config import ImpedanceControllerConfig  # noqa: E402
from icub_pmp.gaze import GazeController, GazePlan  # noqa: E402
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics, project_point  # noqa: E402
from icub_pmp.vision import MotionSegmenter, MotionSegmenterConfig  # noqa: E402
from icub_sim_bridge.harness.sequence_generator import SequenceGenerator  # noqa: E402
from icub_sim_bridge.harness.sim_loop import SimLoop  # noqa: E402

SEED = 2026
GOAL_PX = 2.0
SAMPLE = 0.005  # [s] projection sampling
FPS = 30.0
BALL_CENTRE = np.array([-0.42, 0.0, 0.03])  # [m] root_link, above the table
BALL_SWEEP = 0.10  # [m] half range along y
SPEEDS = (0.1, 0.2)  # [m/s]


class Rig:
    """The physics loop, the gaze controller and the true camera poses."""

    def __init__(self, mode: str):
        self.loop = SimLoop(ImpedanceControllerConfig(mode=mode))
        self.sim = self.loop.sim
        self.gaze = GazeController(model=self.loop.controller.model)
        self.camera = CameraIntrinsics()
        m = self.sim.model
        self.sites = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, f"{s}_eye_optical")
                      for s in ("l", "r")]
        self.plan: GazePlan | None = None
        self.plan_start = 0.0
        self.plan_ms: list[float] = []

    def joints(self) -> dict[str, float]:
        return dict(zip(self.sim.joint_names, self.sim.joint_state().position))

    def err_px(self, p: np.ndarray) -> float:
        """Larger distance [px] of ``p``'s projection from the image centre, both cameras
        (the simulator's optical-frame sites; inf when behind a camera)."""
        d = self.sim.data
        out = 0.0
        for sid in self.sites:
            T = np.eye(4)
            T[:3, :3] = d.site_xmat[sid].reshape(3, 3)
            T[:3, 3] = d.site_xpos[sid]
            try:
                uv = project_point(T, p, self.camera)
            except ValueError:
                return float("inf")
            out = max(out, float(np.hypot(uv[0] - self.camera.cx, uv[1] - self.camera.cy)))
        return out

    def look(self, p: np.ndarray, track: bool = False) -> GazePlan:
        """Plan toward ``p`` (a tracking update continues the running plan) and hand the
        trajectory to the controller, as the node publishes it."""
        t0 = time.perf_counter()
        if track and self.plan is not None:
            plan = self.gaze.update(self.plan, self.loop.t - self.plan_start, p, self.joints())
        else:
            plan = self.gaze.plan(p, self.joints())
        self.plan_ms.append(1e3 * (time.perf_counter() - t0))
        c = self.loop.controller
        # the whole plan from its start sample, as the node sends it
        c.set_trajectory(c.make_trajectory(plan.joint_names, plan.t, plan.q, plan.qd,
                                           start=self.loop.t), self.loop.t)
        self.plan, self.plan_start = plan, self.loop.t
        return plan


def bench_fixation(rig: Rig, n: int) -> dict:
    """Part 1 of the module doc."""
    rng = np.random.default_rng(SEED)
    pts = np.column_stack([rng.uniform(-0.65, -0.2, n), rng.uniform(-0.35, 0.35, n),
                           rng.uniform(-0.05, 0.45, n)])
    final, settle, exact = [], [], 0
    rig.loop.run(0.3)
    for k, p in enumerate(pts):
        plan = rig.look(p)
        exact += plan.solution.exact
        steps = int(round((plan.duration + 0.2) / SAMPLE))
        errs = np.empty(steps)
        for i in range(steps):
            rig.loop.run(SAMPLE)
            errs[i] = rig.err_px(p)
        bad = np.flatnonzero(errs > GOAL_PX)
        if bad.size == 0:
            settle.append(SAMPLE)
        elif bad[-1] < steps - 1:
            settle.append((bad[-1] + 2) * SAMPLE)
        final.append(errs[-1])
        print(f"point {k:3d} {np.round(p, 3)}: final {errs[-1]:.3f} px, settle "
              f"{settle[-1] * 1e3 if bad.size == 0 or bad[-1] < steps - 1 else float('nan'):.0f}"
              f" ms, exact {plan.solution.exact}", file=sys.stderr)
    final_a = np.array(final)
    return {
        "fixation_err_px": round(float(np.median(final_a)), 3),
        "fixation_err_px_p95": round(float(np.percentile(final_a, 95)), 3),
        "fixation_err_px_max": round(float(final_a.max()), 3),
        "fixation_within_goal": round(float(np.mean(final_a <= GOAL_PX)), 3),
        "settle_ms_median": round(1e3 * float(np.median(settle)), 1) if settle else None,
        "settle_ms_p95": round(1e3 * float(np.percentile(settle, 95)), 1) if settle else None,
        "settled_points": len(settle),
        "exact_fraction": round(exact / n, 3),
        "points": n,
    }


def ball(k: int, lead_in: int, speed: float) -> np.ndarray | None:
    """Ball centre at frame ``k`` [m] (None while hidden during the lead-in)."""
    if k < lead_in:
        return None
    s = triangle_wave((k - lead_in) / FPS, speed, BALL_SWEEP, 0.0)
    return BALL_CENTRE + np.array([0.0, s, 0.0])


def bench_tracking(rig: Rig, gen: SequenceGenerator, config: MotionSegmenterConfig,
                   n_frames: int, lead_in: int, track: bool) -> tuple[SegmentationCounts, list]:
    """Part 2 of the module doc: one pass over the speeds, head tracking or still."""
    roi = _roi(config)
    counts = SegmentationCounts()
    centre_err = []
    for speed in SPEEDS:
        rig.look(BALL_CENTRE)
        rig.loop.run(rig.plan.duration + 0.3)
        seg = MotionSegmenter(config)
        for k in range(n_frames + lead_in):
            b = ball(k, lead_in, speed)
            if track and b is not None:
                rig.look(b, track=True)
            rig.loop.run(1.0 / FPS)
            frame = gen.frame_at(rig.joints(), b, k)
            mask = seg.process(frame.left).mask > 0
            if b is None:
                continue
            counts.add(mask, frame.left_mask & roi, roi)
            if k >= lead_in + 15:
                T = frame.T_root_left
                uv = project_point(T, b, gen.camera)
                centre_err.append(float(np.hypot(uv[0] - gen.camera.cx, uv[1] - gen.camera.cy)))
    return counts, centre_err


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer points and frames (< 2 min)")
    ap.add_argument("--mode", default="position", choices=("position", "impedance"),
                    help="impedance controller mode")
    ap.add_argument("--points", type=int, default=None, help="fixation points (20 / 100)")
    args = ap.parse_args(argv)
    cv2.setNumThreads(1)
    t_start = time.perf_counter()
    load0 = os.getloadavg()[0]
    n_points = args.points or (20 if args.quick else 100)
    n_frames, lead_in = (45, 8) if args.quick else (150, 10)
    rig = Rig(args.mode)
    summary = bench_fixation(rig, n_points)
    gen = SequenceGenerator(right_camera=False)
    config = MotionSegmenterConfig()
    tracked, centre_err = bench_tracking(rig, gen, config, n_frames, lead_in, track=True)
    still, _ = bench_tracking(rig, gen, config, n_frames, lead_in, track=False)
    gen.close()
    summary.update({
        "tracking_f1": round(tracked.f1, 3),
        "tracking_precision": round(tracked.precision, 3),
        "tracking_recall": round(tracked.recall, 3),
        "tracking_err_px_median": round(float(np.median(centre_err)), 2) if centre_err else None,
        "still_f1": round(still.f1, 3),
        "plan_ms_median": round(float(np.median(rig.plan_ms)), 2),
        "controller_mode": args.mode,
        "frames_per_speed": n_frames,
        "quick": args.quick,
        "wall_s": round(time.perf_counter() - t_start, 1),
        "load_avg_1min": [round(load0, 2), round(os.getloadavg()[0], 2)],
    })
    print(json.dumps(summary))
    return summary


if __name__ == "__main__":
    main()
