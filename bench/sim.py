"""Benchmark of the simulated iCub: physics alone, the node, the node with cameras,
lockstep with a controller in another process.

    scripts/env.sh python bench/sim.py [--quick]

Figures (real-time factors = simulated s per wall s, medians of 20 windows; each RTF also
as ``*_p5`` (5th percentile of the windows) and ``*_slowest`` (the slowest window), so a stall
the median hides shows):
- physics_rtf: ``Simulator.step`` alone (1 ms steps, robot held, objects on the table).
- node_rtf: the ``sim_bridge`` node as a subprocess, free-running as fast as possible,
  publishing /clock, /joint_states and the 4 FT every step to a listener process that
  subscribes to them (the node skips streams nobody subscribes to), no cameras.
- node_rtf_cameras: the same with both cameras at 30 Hz (sim time), rendered on the worker,
  the listener also subscribing to both images.
- *_cpu_rtf: sim seconds per CPU second of the node process (user + system), a figure less
  sensitive to other processes on a shared machine than the wall-clock RTF.
- lockstep_rtf: ``mode:=lockstep`` with a trivial controller in another process that answers
  every /joint_states with a PD /effort_command on all 23 joints (stamp copied).
- render_ms: one frame of both cameras rendered in this process (median) [ms].
Goals: physics >= 5, node >= 2, node with cameras >= 1, lockstep >= 1.
Ends by printing one JSON line.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import threading
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"


WINDOWS = 20  # RTF windows per measurement


class Windows(NamedTuple):
    """Real-time factors of consecutive windows: median, 5th percentile, slowest."""

    median: float
    p5: float
    slowest: float

    @classmethod
    def of(cls, rates: list[float]) -> "Windows":
        q = statistics.quantiles(rates, n=20, method="inclusive")  # q[0]: 5th percentile
        return cls(statistics.median(rates), q[0], min(rates))

    def keys(self, name: str) -> dict[str, float]:
        """{name: median, name_p5: p5, name_slowest: slowest}, rounded."""
        return {name: round(self.median, 2), f"{name}_p5": round(self.p5, 2),
                f"{name}_slowest": round(self.slowest, 2)}


def physics_rtf(seconds: float) -> Windows:
    """Real-time factor of Simulator.step alone over WINDOWS windows."""
    from icub_sim_bridge import SimConfig, Simulator

    sim = Simulator(SimConfig(cameras_enabled=False))
    sim.step(200)
    rates = []
    for _ in range(WINDOWS):
        n = 0
        t0 = time.perf_counter()
        while time.perf_counter() - t0 < seconds / WINDOWS:
            sim.step(10)
            n += 10
        rates.append(n * sim.config.timestep / (time.perf_counter() - t0))
    return Windows.of(rates)


def render_ms(frames: int) -> float:
    """Median time [ms] to render both eye cameras once (this thread)."""
    from icub_sim_bridge import CameraRenderer, SimConfig, Simulator

    sim = Simulator(SimConfig())
    cams = CameraRenderer(sim.model, sim.built.camera, threaded=False)
    cams.render(sim.data)
    times = []
    for _ in range(frames):
        sim.step(33)
        t0 = time.perf_counter()
        cams.render(sim.data)
        times.append((time.perf_counter() - t0) * 1e3)
    cams.close()
    return statistics.median(times)


def _clock_rtf(probe, seconds: float, warmup: float, pid: int) -> tuple[Windows, float]:
    """(wall RTF windows, median sim s per node CPU s) from /clock stamps over ``seconds``."""
    from rosgraph_msgs.msg import Clock

    from icub_pmp.ros.conversions import time_to_sec

    last = {"t": None}

    def cb(msg: Clock) -> None:
        last["t"] = time_to_sec(msg.clock)

    from rclpy.qos import QoSProfile, ReliabilityPolicy

    sub = probe.node.create_subscription(
        Clock, "/clock", cb, QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))
    try:
        if not probe.wait_for(lambda: last["t"] is not None, 60.0):
            raise RuntimeError("no /clock from sim_bridge")
        time.sleep(warmup)
        rates, cpu = [], []
        windows = WINDOWS
        for _ in range(windows):
            t_sim0, t0, c0 = last["t"], time.perf_counter(), _cpu_seconds(pid)
            time.sleep(seconds / windows)
            rates.append((last["t"] - t_sim0) / (time.perf_counter() - t0))
            cpu.append((last["t"] - t_sim0) / max(_cpu_seconds(pid) - c0, 1e-6))
        return Windows.of(rates), statistics.median(cpu)
    finally:
        probe.node.destroy_subscription(sub)


def _cpu_seconds(pid: int) -> float:
    """user + system CPU time [s] of process ``pid`` and its threads (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def node_rtf(domain: int, seconds: float, params: dict, helper: list[str]
             ) -> tuple[Windows, float]:
    """Start sim_bridge and a helper process (``--listener`` / ``--controller``); measure the
    wall-clock RTF and the sim time per CPU second of the node."""
    from icub_pmp.testing import NodeProcess, RosProbe, ros_environment

    env = ros_environment(domain)
    procs = []
    probe = RosProbe(domain, name="bench_sim_probe")
    try:
        node = NodeProcess("sim_bridge", env=env,
                           params_file=ROOT / "config" / "sim_bridge.yaml", parameters=params)
        procs.append(node)
        procs.append(NodeProcess(command=[sys.executable, str(Path(__file__).resolve()),
                                          *helper], env=env))
        return _clock_rtf(probe, seconds, warmup=2.0, pid=node.pid)  # run_node.sh execs: same pid
    finally:
        probe.close()
        for p in reversed(procs):
            rc = p.stop()
            if rc not in (0, None, -2):
                print(f"bench/sim.py: {p.name} exited with {rc}:\n{p.output()[-2000:]}",
                      file=sys.stderr)


def _spin_until_interrupted(node) -> None:
    """Spin ``node`` on an EventsExecutor (spin_once loop: its spin() ignores SIGINT)."""
    import rclpy
    from rclpy.executors import ExternalShutdownException
    from rclpy.experimental import EventsExecutor

    ex = EventsExecutor()
    ex.add_node(node)
    try:
        while rclpy.ok():
            ex.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):  # SIGINT, before or in rclpy
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def controller_main() -> None:
    """A trivial lockstep controller: PD to the first state, answers every /joint_states."""
    import rclpy
    from rclpy.node import Node
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import JointState

    rclpy.init()
    node = Node("bench_controller")
    pub = node.create_publisher(JointState, "/effort_command", qos_profile_sensor_data)
    out = JointState()
    state = {"q0": None}

    def cb(msg: JointState) -> None:
        q = np.asarray(msg.position)
        v = np.asarray(msg.velocity)
        if state["q0"] is None:
            state["q0"] = q.copy()
            out.name = list(msg.name)
        tau = 20.0 * (state["q0"] - q) - 1.0 * v
        out.header.stamp = msg.header.stamp
        out.effort = tau.tolist()
        pub.publish(out)

    node.create_subscription(JointState, "/joint_states", cb, qos_profile_sensor_data)
    _spin_until_interrupted(node)


def listener_main(cameras: bool) -> None:
    """Subscribe (no-op) to /joint_states, the 4 FT and optionally both images."""
    import rclpy
    from geometry_msgs.msg import WrenchStamped
    from rclpy.node import Node
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import Image, JointState

    rclpy.init()
    node = Node("bench_listener")
    count = [0]

    def cb(msg: object) -> None:
        count[0] += 1

    node.create_subscription(JointState, "/joint_states", cb, qos_profile_sensor_data)
    for ft in ("l_arm_ft", "r_arm_ft", "l_leg_ft", "r_leg_ft"):
        node.create_subscription(WrenchStamped, f"/ft/{ft}", cb, qos_profile_sensor_data)
    if cameras:
        for side in ("left", "right"):
            node.create_subscription(Image, f"/cam/{side}/image_raw", cb,
                                     qos_profile_sensor_data)
    _spin_until_interrupted(node)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="short windows (< 2 min)")
    ap.add_argument("--controller", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--listener", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--cameras", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.controller:
        controller_main()
        return
    if a.listener:
        listener_main(a.cameras)
        return
    from icub_pmp.testing import reserve_domain_id

    seconds = 4.0 if a.quick else 15.0
    res: dict[str, object] = {}
    t_start = time.perf_counter()
    res.update(physics_rtf(seconds).keys("physics_rtf"))
    res["render_ms"] = round(render_ms(15 if a.quick else 60), 2)
    with reserve_domain_id() as domain:
        runs = {
            "node_rtf": ({"real_time_factor": 0.0, "cameras_enabled": False}, ["--listener"]),
            "node_rtf_cameras": ({"real_time_factor": 0.0, "cameras_enabled": True},
                                 ["--listener", "--cameras"]),
            "lockstep_rtf": ({"real_time_factor": 0.0, "cameras_enabled": False,
                              "mode": "lockstep", "lockstep_timeout": 0.05}, ["--controller"]),
        }
        for key, (params, helper) in runs.items():
            wall, cpu = node_rtf(domain, seconds, params, helper)
            res.update(wall.keys(key))
            res[key.replace("_rtf", "_cpu_rtf")] = round(cpu, 2)
    res["cpu_count"] = os.cpu_count()
    res["load_avg_1min"] = round(os.getloadavg()[0], 2)
    res["wall_s"] = round(time.perf_counter() - t_start, 1)
    res["goals_met"] = bool(res["physics_rtf"] >= 5 and res["node_rtf"] >= 2
                            and res["node_rtf_cameras"] >= 1 and res["lockstep_rtf"] >= 1)
    print(json.dumps(res))


if __name__ == "__main__":
    threading.current_thread().name = "bench_sim"
    main()
