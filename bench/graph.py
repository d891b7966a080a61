"""Benchmark of the everyday graph: reach goals executed one after the other, judged in the
physics.

    scripts/env.sh python bench/graph.py --quick      # < 3 min: the default graph, 10 goals
    scripts/env.sh python bench/graph.py              # free_run and lockstep, 10 goals each

The graph is started exactly as the README's "Everyday use" does: ``scripts/graph.sh`` with
its defaults (every node, the simulator free-running with its cameras, simulated time), in a
private ROS domain; ``MODE=lockstep`` for the lockstep variant. Goals go through the
``/pmp/reach_action`` action; targets are the hand positions of random postures within the
joint limits (seeded, one hand per goal, alternating, tau 1.5 s), so every one is reachable.

Figures (per mode; the lockstep ones prefixed ``lockstep_``):
- ``graph_rtf``: simulated time / wall time over the whole run (``graph_rtf_min``: the slowest
  5 s window);
- ``executed_success_rate``: goals whose hand ended within 1 cm of its target, measured from
  the simulator's /joint_states (forward kinematics) after the result;
- ``arrival_err_mm_median``;
- ``watchdog_trips``: safe holds the controller logged during the run (0 while healthy);
- ``goal_to_motion_ms_median``: wall time from sending a goal to the first "executing" feedback
  (the plan is made and the controller has accepted its trajectory);
  ``goal_to_hand_moved_ms_median``: to the first joint state in which the hand moved 2 mm (the
  TBG starts slowly, and the graph may run slower than real time).
Ends with one JSON line.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402

from icub_pmp.kinematics import IcubModel  # noqa: E402
from icub_pmp.ros.reach_goal_message import reach_goal_message  # noqa: E402
from icub_pmp.testing import (  # noqa: E402
    NodeProcess,
    RosProbe,
    repo_root,
    reserve_domain_id,
    ros_environment,
)


def _targets(model: IcubModel, n: int, seed: int) -> list[tuple[str, np.ndarray]]:
    """Hand positions of random postures of one arm (alternating), rest elsewhere."""
    rng = np.random.default_rng(seed)
    spec = model.spec
    out = []
    while len(out) < n:
        hand = ("right", "left")[len(out) % 2]
        q = model.posture("rest").copy()
        idx = model.indices(spec.arm_joints(hand))
        lo, hi = model.lower[idx], model.upper[idx]
        q[idx] = lo + (hi - lo) * rng.uniform(0.2, 0.8, len(idx))
        p = model.frame_position(q, spec.hand_frame(hand))
        # in front of the robot, above the objects on the table (their tops are at z <= 0.03
        # m: a target there is a collision, not an execution test), off the torso
        if p[0] < -0.15 and p[2] > 0.06 and abs(p[1]) > 0.05:
            out.append((hand, p))
    return out


class _Watch:
    def __init__(self, probe: RosProbe, model: IcubModel):
        from rclpy.qos import qos_profile_sensor_data
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import JointState

        self.model = model
        self.js = None
        self.clock: list[tuple[float, float]] = []  # (wall, sim)
        probe.node.create_subscription(JointState, "/joint_states", self._on_js,
                                       qos_profile_sensor_data)
        probe.node.create_subscription(Clock, "/clock", self._on_clock,
                                       qos_profile_sensor_data)
        self.moved_at: float | None = None
        self._watch: tuple[str, np.ndarray] | None = None

    def _on_js(self, m) -> None:
        self.js = m
        w = self._watch
        if w is not None and self.moved_at is None:
            if np.linalg.norm(self.hand(w[0]) - w[1]) > 0.002:
                self.moved_at = time.monotonic()

    def _on_clock(self, m) -> None:
        self.clock.append((time.monotonic(), m.clock.sec + m.clock.nanosec * 1e-9))

    def hand(self, hand: str) -> np.ndarray:
        q = self.model.q_from_dict(dict(zip(self.js.name, self.js.position)))
        return self.model.frame_position(q, self.model.spec.hand_frame(hand))

    def watch(self, hand: str) -> None:
        self.moved_at = None
        self._watch = (hand, self.hand(hand))


class _Hook(list):
    """A feedback list that also calls ``fn`` on every feedback message."""

    def __init__(self, fn):
        super().__init__()
        self.fn = fn

    def append(self, item) -> None:
        self.fn(item)


def _rtf(clock: list[tuple[float, float]], window: float = 5.0) -> tuple[float, float]:
    if len(clock) < 2:
        return float("nan"), float("nan")
    w = np.array(clock)
    total = (w[-1, 1] - w[0, 1]) / (w[-1, 0] - w[0, 0])
    mins = []
    k = 0
    for i in range(len(w)):
        while w[i, 0] - w[k, 0] > window:
            k += 1
        if w[i, 0] - w[k, 0] >= window * 0.99:
            mins.append((w[i, 1] - w[k, 1]) / (w[i, 0] - w[k, 0]))
    return float(total), float(min(mins)) if mins else float(total)


def run_mode(mode: str, goals: int, seed: int, model: IcubModel) -> dict:
    from icub_interfaces.action import Reach

    with reserve_domain_id() as did:
        env = ros_environment(did, dict(os.environ))
        env["MODE"] = mode
        graph = NodeProcess(command=[str(repo_root() / "scripts/graph.sh")], env=env)
        probe = RosProbe(did, "bench_graph")
        try:
            watch = _Watch(probe, model)
            client = probe.action_client("/pmp/reach_action", Reach, timeout=240.0)
            if not probe.wait_for(lambda: watch.js is not None, 60.0):
                raise RuntimeError("no /joint_states: " + graph.output()[-2000:])
            trips0 = graph.output().count("safe hold at the last measured posture")
            clock0 = len(watch.clock)
            errs, ok, lat, start = [], 0, [], []
            for hand, target in _targets(model, goals, seed):
                g = reach_goal_message({hand: target}, 1.5)
                watch.watch(hand)
                fb: list = []
                executing: list[float] = []
                sent = time.monotonic()

                def on_fb(m, fb=fb, executing=executing) -> None:
                    if m.phase == "executing" and not executing:
                        executing.append(time.monotonic())

                res = probe.send_goal(client, g, 240.0, feedback=_Hook(on_fb))
                if executing:
                    start.append((executing[0] - sent) * 1e3)
                probe.wait_for(lambda: False, 0.2)
                err = float(np.linalg.norm(watch.hand(hand) - target))
                errs.append(err)
                ok += err < 0.01
                if watch.moved_at is not None:
                    lat.append((watch.moved_at - sent) * 1e3)
                print(f"  {mode}: {hand} -> {np.round(target, 3)}: {res.result.outcome}, "
                      f"measured {err * 1e3:.1f} mm", file=sys.stderr)
            rtf, rtf_min = _rtf(watch.clock[clock0:])
            trips = graph.output().count("safe hold at the last measured posture") - trips0
            probe.destroy(client)
        finally:
            probe.close()
            graph.stop(30.0)
    return {
        "graph_rtf": round(rtf, 3),
        "graph_rtf_min": round(rtf_min, 3),
        "executed_success_rate": ok / goals,
        "arrival_err_mm_median": round(float(np.median(errs)) * 1e3, 2),
        "arrival_err_mm_max": round(float(np.max(errs)) * 1e3, 2),
        "watchdog_trips": int(trips),
        "goal_to_motion_ms_median": round(float(np.median(start)), 1) if start else None,
        "goal_to_hand_moved_ms_median": round(float(np.median(lat)), 1) if lat else None,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="the default graph only")
    ap.add_argument("--goals", type=int, default=10)
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args(argv)
    model = IcubModel()
    print(f"load at start: {os.getloadavg()}", file=sys.stderr)
    out = {"mode": "free_run", **run_mode("free_run", args.goals, args.seed, model)}
    if not args.quick:
        lock = run_mode("lockstep", args.goals, args.seed, model)
        out.update({f"lockstep_{k}": v for k, v in lock.items()})
    out["load"] = round(os.getloadavg()[0], 2)
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
