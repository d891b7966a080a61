"""SoakRunner: repeated reach / squeeze / release / look cycles on the lockstep graph, with
each process's resident memory, the 1 kHz loop's rate and the warnings sampled per cycle
(issue 22, "soak").

One cycle: a reach goal (``/pmp/reach_action``, executed), a squeeze (``/sim/apply_wrench``: a
scripted push on the right hand, as an object squeezed against it would), a release (the push
ends; the controller holds), a gaze ``/gaze/look_at`` of the table (when the gaze
controller runs) and, when the motion segmenter runs on the simulator's cameras, a vision step:
the cylinder is moved across the table on the robot's left (away from the reaches) and the
segmenter must give a still stereo target of it (``/motion/target/estimate``) after it stops.
Every goal and call must be answered.

Figures: RSS growth per process [MB/h] (least-squares slope over the samples after the first
cycle), the loop rate [simulated steps per wall second, 1 kHz steps] in the first and the last
third of the run and its drift [%], warnings per cycle in the nodes' logs (first vs last third).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.graph import NodeGraph
from icub_pmp.ros.probe import RosProbe

__all__ = ["SoakRunner", "SoakReport", "group_rss_mb"]


def group_rss_mb(pgid: int) -> float:
    """Resident memory [MB] of every process in process group ``pgid`` (from /proc)."""
    total_kb = 0
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            stat = (d / "stat").read_text()
            fields = stat[stat.rindex(")") + 2:].split()
            if int(fields[2]) != pgid:
                continue
            for line in (d / "status").read_text().splitlines():
                if line.startswith("VmRSS:"):
                    total_kb += int(line.split()[1])
        except (OSError, ValueError, IndexError):
            continue
    return total_kb / 1024.0


def _warnings(text: str) -> int:
    return text.count("[WARN]") + text.count("[ERROR]")


@dataclasses.dataclass
class SoakReport:
    """What a soak measured (module doc)."""

    minutes: float
    cycles: int
    goals_sent: int
    goals_answered: int
    goals_succeeded: int
    rss_mb: dict[str, list[float]]
    rss_growth_mb_per_h: dict[str, float]
    loop_rate_first: float
    loop_rate_last: float
    warnings_first: float
    warnings_last: float
    vision_tried: int = 0
    vision_found: int = 0

    @property
    def loop_rate_drift_pct(self) -> float:
        """Change of the loop rate from the first to the last third [%]."""
        if self.loop_rate_first <= 0:
            return float("nan")
        return 100.0 * (self.loop_rate_last - self.loop_rate_first) / self.loop_rate_first

    def summary(self) -> dict[str, Any]:
        """The figures as a JSON-ready dict."""
        return {
            "soak_minutes": round(self.minutes, 2), "soak_cycles": self.cycles,
            "soak_goals_sent": self.goals_sent, "soak_goals_answered": self.goals_answered,
            "soak_goals_succeeded": self.goals_succeeded,
            "rss_growth_mb_per_h": {k: round(v, 1) for k, v in
                                    self.rss_growth_mb_per_h.items()},
            "rss_growth_mb_per_h_max": round(max(self.rss_growth_mb_per_h.values(),
                                                 default=float("nan")), 1),
            "rss_mb_last": {k: round(v[-1], 1) for k, v in self.rss_mb.items() if v},
            "loop_rate_first_hz": round(self.loop_rate_first, 1),
            "loop_rate_last_hz": round(self.loop_rate_last, 1),
            "loop_rate_drift_pct": round(self.loop_rate_drift_pct, 1),
            "warnings_per_cycle_first": round(self.warnings_first, 2),
            "warnings_per_cycle_last": round(self.warnings_last, 2),
            "soak_vision_steps": self.vision_tried, "soak_vision_found": self.vision_found,
        }


class SoakRunner:
    """Cycles on ``graph`` (lockstep: sim_bridge, wrench_estimator, impedance_controller,
    pmp_planner, optionally gaze_controller and motion_segmenter) through ``probe``."""

    def __init__(self, probe: RosProbe, graph: NodeGraph, reach_client: Any):
        from rclpy.qos import qos_profile_sensor_data
        from rosgraph_msgs.msg import Clock

        self.probe = probe
        self.graph = graph
        self.client = reach_client
        self.sim_time = 0.0
        self.estimates: list[Any] = []
        self.vision = [0, 0]  # vision steps tried, still targets found
        probe.node.create_subscription(Clock, "/clock", self._on_clock,
                                       qos_profile_sensor_data)
        if "motion_segmenter" in graph.procs:
            from icub_interfaces.msg import VisualTarget

            probe.node.create_subscription(VisualTarget, "/motion/target/estimate",
                                           self.estimates.append, 10)

    def _on_clock(self, m: Any) -> None:
        self.sim_time = m.clock.sec + m.clock.nanosec * 1e-9

    def _call(self, name: str, srv: Any, req: Any) -> bool | None:
        """True/False = answered (success), None = no answer."""
        try:
            return bool(self.probe.call(name, srv, req, timeout=60.0).success)
        except TimeoutError:
            return None

    def cycle(self, k: int) -> tuple[int, int, int]:
        """One cycle: (sent, answered, succeeded)."""
        from icub_interfaces.srv import ApplyWrench, LookAt
        from icub_pmp.testing.fault_injection import TARGETS, reach_goal
        from icub_pmp.testing.graph_interfaces import good_look_at

        sent = answered = ok = 0
        sent += 1
        try:
            res = self.probe.send_goal(self.client, reach_goal(TARGETS[k % 2]), timeout=180.0)
            answered += 1
            ok += int(res.result.success)
        except (TimeoutError, RuntimeError):
            pass
        push = ApplyWrench.Request()
        push.target, push.duration = "r_hand", 0.5
        push.wrench.force.z = -5.0  # 5 N down: a squeeze against the hand
        sent += 1
        r = self._call("/sim/apply_wrench", ApplyWrench, push)
        answered += r is not None
        ok += bool(r)
        t_end = self.sim_time + 0.7  # the push ends (release): the controller holds
        self.probe.wait_for(lambda: self.sim_time >= t_end, 60.0)
        if "gaze_controller" in self.graph.procs:
            sent += 1
            r = self._call("/gaze/look_at", LookAt, good_look_at())
            answered += r is not None
            ok += bool(r)
        if "motion_segmenter" in self.graph.procs and \
                self.probe.node.count_publishers("/cam/left/image_raw") > 0:
            sent += 1
            r = self.vision_step()
            self.vision[0] += 1
            self.vision[1] += bool(r)
            answered += r is not None
            ok += bool(r)
        return sent, answered, ok

    def vision_step(self, start: tuple[float, float, float] = (-0.36, 0.0, -0.03),
                    speed_y: float = -0.15, duration: float = 1.2) -> bool | None:
        """Move the cylinder from ``start`` [m, root_link] along y at ``speed_y`` [m/s] for
        ``duration`` [s] (60 poses per second of simulated time), then wait up to 3 s of
        simulated time for a still target stamped after the motion began. True = found,
        False = none, None = a pose call not answered."""
        from geometry_msgs.msg import Pose

        from icub_interfaces.srv import SetObjectPose

        def place(y: float) -> bool | None:
            req = SetObjectPose.Request(name="cylinder", pose=Pose())
            req.pose.position.x, req.pose.position.y, req.pose.position.z = start[0], y, start[2]
            req.pose.orientation.w = 1.0
            return self._call("/sim/set_object_pose", SetObjectPose, req)

        if place(start[1]) is None:
            return None
        settle = self.sim_time + 0.3
        self.probe.wait_for(lambda: self.sim_time >= settle, 60.0)
        self.estimates.clear()
        t0 = self.sim_time
        for k in range(int(duration * 60.0) + 1):
            if place(start[1] + speed_y * k / 60.0) is None:
                return None
            t_next = t0 + (k + 1) / 60.0
            self.probe.wait_for(lambda t_next=t_next: self.sim_time >= t_next, 60.0)
        end = self.sim_time + 3.0

        def still() -> bool:
            return any(m.state == "still" and m.points > 0
                       and m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 > t0
                       for m in list(self.estimates))

        self.probe.wait_for(lambda: still() or self.sim_time >= end, 120.0)
        return still()

    def run(self, minutes: float, min_cycles: int = 2) -> SoakReport:
        """Cycles for ``minutes`` of wall time, and at least ``min_cycles`` (``run(0, 3)``:
        exactly three cycles, the fewest that give an RSS slope over two samples after the
        first cycle)."""
        if min_cycles < 1:
            raise InvalidInput(f"min_cycles: expected at least 1 cycle, got {min_cycles}")
        names = list(self.graph.procs)
        rss: dict[str, list[float]] = {n: [] for n in names}
        stamps: list[float] = []
        rates: list[float] = []
        warns: list[int] = []
        totals = [0, 0, 0]
        t0 = time.monotonic()
        prev_warn = sum(_warnings(p.output()) for p in self.graph.procs.values())
        k = 0
        while k < min_cycles or time.monotonic() - t0 < minutes * 60.0:
            w0, s0 = time.monotonic(), self.sim_time
            for i, v in enumerate(self.cycle(k)):
                totals[i] += v
            w1, s1 = time.monotonic(), self.sim_time
            rates.append(1000.0 * (s1 - s0) / max(w1 - w0, 1e-6))
            now_warn = sum(_warnings(p.output()) for p in self.graph.procs.values())
            warns.append(now_warn - prev_warn)
            prev_warn = now_warn
            stamps.append(w1 - t0)
            for n in names:
                rss[n].append(group_rss_mb(self.graph.procs[n].pid))
            k += 1
        third = max(1, len(rates) // 3)
        growth = {}
        for n in names:
            t = np.array(stamps[1:]) / 3600.0
            y = np.array(rss[n][1:])
            growth[n] = float(np.polyfit(t, y, 1)[0]) if len(t) >= 2 and np.ptp(t) > 0 \
                else float("nan")
        return SoakReport(
            minutes=(time.monotonic() - t0) / 60.0, cycles=k, goals_sent=totals[0],
            goals_answered=totals[1], goals_succeeded=totals[2], rss_mb=rss,
            rss_growth_mb_per_h=growth,
            loop_rate_first=float(np.median(rates[:third])),
            loop_rate_last=float(np.median(rates[-third:])),
            warnings_first=float(np.mean(warns[:third])),
            warnings_last=float(np.mean(warns[-third:])),
            vision_tried=self.vision[0], vision_found=self.vision[1])
