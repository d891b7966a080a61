"""Benchmark of seeing and reaching: the hand lands above the object the eyes found,
judged against the object in the physics.

    scripts/env.sh python bench/vision_reach.py --quick    # 5 trials
    scripts/env.sh python bench/vision_reach.py            # 20 trials

The running graph, as ``make demo`` starts it (private ROS domain; the simulator in lockstep
with its cameras, the impedance controller in position mode, the PMP planner, the motion
segmenter with its stereo target, the gaze controller). Each trial (random placements and
motions, ``--seed`` 23 by default, not the tests' or the demo's; ``--only K`` runs trial K
alone): the head looks at the table where the cylinder will move and then tracks the stereo
target; the cylinder is placed, moved at a constant speed (0.1-0.25 m/s, any direction on
the table, 0.6-1.2 s) and stops; once the target is still, the hand on the object's side
(``scenario.reaching_arm``) reaches the pre-grasp point 6 cm above the estimated top centre
(``icub_pmp.demo.scenario.vision_reach``, the demo's phase 3), then goes back. Each trial
prints the target's history (taken, switched, dropped, the goal) with the thing nearest to
each position: the cylinder, the box, a segment of the robot's arms, the table's edge.

Figures (one JSON line at the end):
- ``target_err_mm_median`` / ``_p95``: every measured stereo estimate (/motion/target/estimate
  with points > 0, moving and still) vs the cylinder's ground truth at the estimate's image
  stamp (goal median <= 10);
- ``arrival_err_mm_median``: the hand (forward kinematics of the simulator's joint states)
  vs the point 6 cm above the cylinder's true top centre after the reach (goal <= 20);
- ``success_rate``: trials the demo's judge passes (hand within 2 cm of that point, estimate
  within 1 cm, the cylinder not pushed; goal >= 0.95);
- ``detect_to_goal_ms_median``: simulated time from the first camera image after the motion
  began to the first reach goal sent (the reach waits for the object to stop, so this includes
  the motion itself); ``still_to_goal_ms_median``: from the end of the motion to that goal;
- ``method``: ``geometric`` (rays from the kinematic camera poses) or ``eye_hand_map``
  (``--eye-hand-map FILE``: the map learned from babbling); ``wall_s``, ``sim_s``.

The cylinder is moved by the simulator along its trajectory in simulated time
(/sim/move_object), so the motions are the same at any load. A failed trial prints the stereo
estimates that followed the motion (state/source/points/error in mm).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections import deque
from pathlib import Path

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402

from icub_pmp.demo.demo_runner import DemoRunner  # noqa: E402
from icub_pmp.demo.scenario import graph_parameters, vision_reach  # noqa: E402
from icub_pmp.graph import NodeGraph, reserve_domain_id, ros_environment  # noqa: E402
from icub_pmp.ros.conversions import time_to_sec  # noqa: E402
from icub_pmp.ros.probe import RosProbe  # noqa: E402

GRAPH = ["sim_bridge", "impedance_controller", "pmp_planner", "motion_segmenter",
         "gaze_controller"]


def graph_params(realism: str | None, eye_hand_map: str = "") -> dict[str, dict[str, object]]:
    """The demo's parameters of the bench's nodes (``realism``: the simulator's preset, with
    the eye calibration of the ``icub`` robot; None = config/sim_bridge.yaml's;
    ``eye_hand_map``: a learned eye-hand map (.npz) as the segmenter's 3-D source, '' =
    triangulation)."""
    params = {n: dict(p) for n, p in graph_parameters(realism).items() if n in GRAPH}
    if eye_hand_map:
        params["motion_segmenter"].update({"target_source": "eye_hand_map",
                                           "eye_hand_map_file": eye_hand_map})
    return params


PARAMS = graph_params(None)
#: where the hands wait between trials [m, root_link]: above the table's near corners, out of
#: the way of the objects and of the other hand's reach
HOME = np.array([-0.22, 0.25, 0.12])
HOME_LEFT = np.array([-0.22, -0.25, 0.12])


def trials(n: int, seed: int = 23) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """(start, velocity, duration) of ``n`` motions on the table, starting and ending in the
    region in front of the robot that both eyes see when looking at it."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        start = np.array([rng.uniform(-0.44, -0.32), rng.uniform(-0.16, 0.12), -0.03])
        ang = rng.uniform(0.0, 2.0 * math.pi)
        speed, dur = rng.uniform(0.1, 0.25), rng.uniform(0.6, 1.2)
        vel = speed * np.array([math.cos(ang), math.sin(ang), 0.0])
        end = start + vel * dur
        if -0.46 <= end[0] <= -0.30 and -0.18 <= end[1] <= 0.14:
            out.append((start, vel, dur))
    return out


#: the robot's parts a wrong target may be on: (name, from frame, to frame) segments
ROBOT_PARTS = tuple((f"{s}_{part}", f"{p}_{a}", f"{p}_{b}")
                    for p, s in (("l", "left"), ("r", "right"))
                    for part, a, b in (("upper_arm", "shoulder_1", "elbow_1"),
                                       ("forearm", "elbow_1", "wrist_1"),
                                       ("hand", "wrist_1", "hand_dh_frame")))
TABLE_NEAR_EDGE_X = -0.22  # the table's edge on the robot's side [m] (config/sim_bridge.yaml)


class JointHistory:
    """The simulator's /joint_states of the last 20 s, one sample per 20 ms of simulated time
    (the robot's pose at an estimate's stamp, for :func:`nearest_thing`)."""

    def __init__(self, runner: DemoRunner):
        from rclpy.qos import qos_profile_sensor_data
        from sensor_msgs.msg import JointState

        self._rows: deque = deque(maxlen=1000)
        self._sub = runner.probe.node.create_subscription(
            JointState, "/joint_states", self._on, qos_profile_sensor_data)

    def _on(self, msg) -> None:  # noqa: ANN001 - ROS type
        t = time_to_sec(msg.header.stamp)
        if not self._rows or t - self._rows[-1][0] >= 0.02:
            self._rows.append((t, msg))

    def at(self, t: float):  # noqa: ANN201 - JointState or None
        """The sample nearest to ``t`` [s] (None before the first)."""
        rows = list(self._rows)
        return min(rows, key=lambda r: abs(r[0] - t))[1] if rows else None


def nearest_thing(runner: DemoRunner, joints: JointHistory, p: np.ndarray, t: float
                  ) -> tuple[str, float]:
    """What the point ``p`` [m] estimated at ``t`` [s] lies on: the nearest of the scene's
    objects (ground truth), the robot's arm segments (forward kinematics of the joint states
    at ``t``) and the table's near edge: (name, distance [m]) (diagnosis of wrong targets)."""
    from icub_pmp.peripersonal.segment_distance import segment_distance

    cands: dict[str, float] = {}
    for obj in ("cylinder", "box"):
        try:
            cands[obj] = float(np.linalg.norm(p - runner.object_position_at(obj, t)))
        except KeyError:
            pass
    js = joints.at(t)
    if js is not None:
        q = runner.q(js)
        for name, a, b in ROBOT_PARTS:
            pa, pb = runner.model.frame_position(q, a), runner.model.frame_position(q, b)
            cands[name] = float(segment_distance(p, p, pa, pb))
    cands["table_edge"] = abs(float(p[0]) - TABLE_NEAR_EDGE_X)
    name = min(cands, key=cands.get)
    return name, cands[name]


def target_events(runner: DemoRunner, joints: JointHistory, r) -> list[str]:  # noqa: ANN001
    """The target's history in a trial, from the stereo estimates (/motion/target/estimate):
    taken (the first), switched (a jump of more than 3 cm between two estimates: a new
    object or a restart), dropped (no estimate for 0.2 s, the node publishes only while there
    is a target), and the goal (the first still estimate after the stop), each with its time
    after the motion's start [s], state/source, position [mm] and the nearest thing."""
    end = r.sim_start + r.extra.get("motion_s", 0.0)
    out, prev_t, prev_p, goal_done = [], None, None, False

    def row(kind: str, t: float, m, p: np.ndarray) -> str:  # noqa: ANN001
        thing, d = nearest_thing(runner, joints, p, t)
        return (f"{kind}@{t - r.sim_start:.2f}:{m.state}/{m.source}/{m.points} "
                f"[{p[0] * 1e3:.0f},{p[1] * 1e3:.0f},{p[2] * 1e3:.0f}] {thing}+{d * 1e3:.0f}mm")

    for m in list(runner.estimates):
        t = time_to_sec(m.header.stamp)
        p = np.array([m.position.x, m.position.y, m.position.z])
        if prev_t is None:
            out.append(row("taken", t, m, p))
        elif t - prev_t > 0.2:
            out.append(f"dropped@{prev_t - r.sim_start:.2f}")
            out.append(row("taken", t, m, p))
        elif np.linalg.norm(p - prev_p) > 0.03:
            out.append(row("switched", t, m, p))
        if not goal_done and t > end and m.state == "still" and m.points > 0:
            out.append(row("goal", t, m, p))
            goal_done = True
        prev_t, prev_p = t, p
    return out


def run(n: int, realism: str | None = None, eye_hand_map: str = "", seed: int = 23,
        only: list[int] | None = None) -> dict:
    """Run ``n`` trials in a fresh graph (``realism``: the simulator's preset;
    ``eye_hand_map``: the learned map as the 3-D source, '' = triangulation; ``seed``: of the
    placements and motions; ``only``: run just these indices of the ``n`` trials); returns
    the figures."""
    errs, arrivals, ok, d2g, s2g = [], [], [], [], []
    wall0 = time.monotonic()
    with reserve_domain_id() as domain:
        env = ros_environment(domain)
        with NodeGraph(GRAPH, graph_params(realism, eye_hand_map), env=env) as graph:
            probe = RosProbe(domain, "bench_vision_reach")
            try:
                runner = DemoRunner(probe)
                joints = JointHistory(runner)
                runner.wait_ready(services=("/pmp/reach", "/sim/set_object_pose",
                                             "/sim/move_object",
                                             "/gaze/look_at"))
                runner.set_object("box", np.array([-0.52, -0.40, -0.05]))
                sim0 = runner.sim_time()
                for k, (start, vel, dur) in enumerate(trials(n, seed)):
                    if only is not None and k not in only:
                        continue
                    runner.pmp_reach("home", {"right": HOME, "left": HOME_LEFT},
                                     use_torso=True, tau=1.0, judge_physics=False)
                    q0 = dict(zip(runner.model.joint_names, runner.q()))
                    r = vision_reach(runner, start, vel, dur, name=f"trial{k}")
                    for m in list(runner.estimates):
                        t = time_to_sec(m.header.stamp)
                        if m.points > 0 and t >= r.sim_start:
                            p = np.array([m.position.x, m.position.y, m.position.z])
                            errs.append(np.linalg.norm(
                                p - runner.object_position_at("cylinder", t)))
                    ok.append(bool(r.success))
                    if "arrival_vs_object_m" in r.extra:
                        arrivals.append(r.extra["arrival_vs_object_m"])
                    if "goal_sent_s" in r.extra:
                        first_image = math.ceil(r.sim_start * 30.0 - 1e-6) / 30.0
                        d2g.append(r.sim_start + r.extra["goal_sent_s"] - first_image)
                        s2g.append(r.extra["goal_sent_s"] - dur)
                    print(f"trial {k}: {'ok' if r.success else 'FAILED'} {r.message} "
                          f"{ {a: round(b, 4) for a, b in r.extra.items()} }", flush=True)
                    print("  torso at the start [deg]: " + " ".join(
                        f"{j}={math.degrees(q0[j]):.1f}" for j in runner.model.spec.torso_joints),
                        flush=True)
                    print("  target: " + " | ".join(target_events(runner, joints, r)),
                          flush=True)
                    if not r.success:
                        print(f"  estimates after the motion: {estimate_trace(runner, r)}",
                              flush=True)
                sim_s = runner.sim_time() - sim0
            except Exception:
                print(graph.outputs()[-4000:], file=sys.stderr)
                raise
            finally:
                probe.close()

    def pct(a: list[float], q: float) -> float:
        return float(np.percentile(a, q) * 1000) if len(a) else math.nan

    return {
        "bench": "vision_reach", "method": "eye_hand_map" if eye_hand_map else "geometric",
        "realism": realism or "config",
        "trials": len(ok), "seed": seed,
        "target_err_mm_median": pct(errs, 50), "target_err_mm_p95": pct(errs, 95),
        "target_estimates": len(errs),
        "arrival_err_mm_median": pct(arrivals, 50),
        "success_rate": float(np.mean(ok)) if ok else 0.0,
        "detect_to_goal_ms_median": pct(d2g, 50), "still_to_goal_ms_median": pct(s2g, 50),
        "sim_s": round(sim_s, 2), "wall_s": round(time.monotonic() - wall0, 1),
        "load": round(os.getloadavg()[0], 2),
    }


def estimate_trace(runner: DemoRunner, r) -> str:  # noqa: ANN001 - PhaseResult
    """The stereo estimates of a failed trial from the end of the motion: stamp [s] after the
    motion's start, state, source, points, error vs the ground truth [mm] (for diagnosis)."""
    end = r.sim_start + r.extra.get("motion_s", 0.0)
    rows = []
    for m in list(runner.estimates):
        t = time_to_sec(m.header.stamp)
        if t < end - 0.1:
            continue
        p = np.array([m.position.x, m.position.y, m.position.z])
        try:
            e = f"{np.linalg.norm(p - runner.object_position_at('cylinder', t)) * 1e3:.0f}"
        except KeyError:
            e = "?"
        rows.append(f"{t - r.sim_start:.2f}:{m.state}/{m.source}/{m.points}/{e}")
    return " ".join(rows[:40]) or "none"


def main(argv: list[str] | None = None) -> int:
    """Entry point."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="5 trials instead of 20")
    ap.add_argument("--trials", type=int, default=None)
    ap.add_argument("--realism", choices=("ideal", "icub"), default=None,
                    help="the simulator's realism preset (icub: the miscalibrated cameras and "
                         "this robot's eye calibration; default: config/sim_bridge.yaml's)")
    ap.add_argument("--eye-hand-map", default="", metavar="FILE",
                    help="the segmenter's 3-D target from this learned eye-hand map (.npz, e.g. "
                         "bench/body_schema.py --eye-hand-only --rendered --save-models DIR "
                         "writes DIR/eye_hand_rendered_icub.npz for the icub cameras) instead of "
                         "triangulation")
    ap.add_argument("--seed", type=int, default=23, help="of the placements and motions")
    ap.add_argument("--only", type=int, nargs="+", default=None, metavar="K",
                    help="run only these trial indices (0-based) of the seed's trials, e.g. to "
                         "reproduce a failed one")
    args = ap.parse_args(argv)
    n = args.trials or (5 if args.quick else 20)
    if args.only is not None and not all(0 <= k < n for k in args.only):
        ap.error(f"--only: indices must be in 0..{n - 1} (the --trials count), got {args.only}")
    eye_hand = str(Path(args.eye_hand_map).resolve()) if args.eye_hand_map else ""
    if eye_hand and not Path(eye_hand).is_file():
        ap.error(f"--eye-hand-map: no file {eye_hand}")
    print(json.dumps(run(n, args.realism, eye_hand, args.seed, args.only)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
