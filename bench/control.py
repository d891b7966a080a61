"""Benchmark of the 1 kHz joint controller: lockstep real-time factor, controller
compute time per step, tracking of a 2 s minimum-jerk joint trajectory.

    scripts/env.sh python bench/control.py --quick     # < 2 min
    scripts/env.sh python bench/control.py             # longer RTF window

1. In-process (one Python process, no DDS): the simulator alone stepping 1 ms (baseline), then
   SimLoop = simulator + wrench estimator + impedance controller in lockstep; per-step compute
   time of the controller (perf_counter around ImpedanceController.step, median; and its
   thread CPU time, less sensitive to the load) and of the estimator; the real-time factor of
   both (simulated s / wall s).
2. Tracking: position mode with inverse-dynamics feed-forward and the torque loop closed on
   the estimated torques; 7 joints (torso yaw, right arm 6, left elbow) follow a 2 s
   minimum-jerk move sent as 40 points with velocities (as a planner does). RMS error during
   the 2 s and the final error 0.3 s after, over all 7 joints [deg].
3. Over DDS: sim_bridge (lockstep, cameras off, IMU and ground truth every 10 steps) +
   wrench_estimator (side topics every 10 samples) + impedance_controller (use_sim_time) as
   subprocesses started through their scripts in a private ROS domain; the lockstep real-time
   factor from /clock over a wall-clock window: ``lockstep_rtf`` with the estimator on every
   1 kHz sample, ``lockstep_rtf_estimator_100hz`` with it on one sample in 10 (the rate of
   wholeBodyDynamics on the robot), ``lockstep_rtf_no_estimator`` without it (baseline).
   ``lockstep_rtf`` is the composed ``torque_loop`` process (the estimator and controller
   nodes in one process, the estimate handed over in-process: docs/decisions/0067), the
   shipped way to run the torque loop at 1 kHz; ``lockstep_rtf_separate`` the same loop with
   the two nodes in their own processes (the estimate over DDS).

4. Realism (issue 17), both simulator presets in the same run, nested under ``ideal`` /
   ``icub``: the tracking of 2 (with friction compensation on, for both) and, over DDS,
   ``lockstep_rtf`` with the estimator on every 1 kHz sample on the critical path
   (``wait_for_estimate``, the shipped default, acts in lockstep: each controller step waits
   for the estimate of its own joint state), ``stale_estimate_steps`` (controller steps with
   the torque loop on and no fresh estimate, from /impedance_controller/status; goal 0) and
   ``controller_steps`` (the composed process; ``lockstep_rtf_separate`` and its
   ``separate`` figures beside); for ``icub``, then the estimator stops (in the composed
   process its ``enabled`` parameter is set false: no sample processed, nothing published,
   as a stopped wholeBodyDynamics device): ``estimator_stop_safe_hold_s`` (simulated) and
   ``_wall_s`` until the status says safe_hold, and its reason.
   ``lockstep_rtf_robot_loop`` and its ``robot_loop`` figures (``stale_estimate_steps``,
   ``cpu_us_per_sim_ms``...): the same loop with the simulator, the estimator and the
   controller in one ``robot_loop`` process, the whole 1 kHz loop on the physics thread
   (docs/decisions/0068; opt-in, not the default graph).

Each DDS run also gives ``cpu_us_per_sim_ms``: CPU time [us] per simulated ms of each node
process (/proc), far less load-sensitive than the wall-clock rtf (docs/decisions/0065).

The machine is shared: wall-clock figures depend on its load (printed at start and end).
Ends with one JSON line: lockstep_rtf (DDS), controller_us_median, tracking_rms_deg,
tracking_final_deg, and the in-process figures (all ``ideal``), then ``ideal`` / ``icub``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from icub_pmp.control.impedance_controller_config import ImpedanceControllerConfig  # noqa: E402
from icub_sim_bridge.harness.sim_loop import SimLoop  # noqa: E402
from icub_sim_bridge.harness.sim_scenarios import track_min_jerk  # noqa: E402
from icub_sim_bridge.realism_config import RealismConfig  # noqa: E402
from icub_sim_bridge.sim_config import SimConfig  # noqa: E402
from icub_sim_bridge.simulator import Simulator  # noqa: E402


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def _tree_cpu_s(pid: int) -> float:
    """CPU time [s] (user + system, /proc) of process ``pid`` and its descendants (a node's
    script execs its Python process)."""
    tick = os.sysconf("SC_CLK_TCK")
    total, todo = 0.0, [pid]
    while todo:
        p = todo.pop()
        try:
            fields = Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()
            total += (int(fields[11]) + int(fields[12])) / tick
            for task in Path(f"/proc/{p}/task").iterdir():
                todo += [int(c) for c in (task / "children").read_text().split()]
        except (OSError, IndexError, ValueError):
            continue  # gone meanwhile
    return total


def bench_inprocess(sim: Simulator, seconds: float) -> dict:
    """Sim-only baseline vs the full in-process loop; per-step compute times."""
    sim.reset("rest")
    n = int(seconds * 1000)
    t0 = time.perf_counter()
    sim.step(n)
    sim_rtf = n * 1e-3 / (time.perf_counter() - t0)
    sim.reset("rest")
    loop = SimLoop(ImpedanceControllerConfig(mode="impedance"), sim=sim)
    loop.run(0.05)
    loop.record_timing = True
    t0 = time.perf_counter()
    loop.run(seconds)
    wall = time.perf_counter() - t0
    tm = {k: np.array(v) * 1e6 for k, v in loop.timing.items()}
    cpu = cpu_time_per_step(loop)
    return {
        "controller_cpu_us": cpu,
        "sim_only_rtf": sim_rtf,
        "inprocess_rtf": seconds / wall,
        "controller_us_median": float(np.median(tm["controller"])),
        "controller_us_p95": float(np.percentile(tm["controller"], 95)),
        "estimator_us_median": float(np.median(tm["estimator"])),
        "sim_step_us_median": float(np.median(tm["sim"])),
    }


def cpu_time_per_step(loop: SimLoop, n: int = 2000) -> float:
    """Thread CPU time [us] of ImpedanceController.step on recorded states (less sensitive
    to the machine's load than wall time: no time spent descheduled)."""
    c = loop.controller
    st = loop.sim.joint_state()
    t = loop.t
    t0 = time.thread_time_ns()
    for k in range(n):
        c.step(t + (k + 1) * 1e-6, st.position, st.velocity)
    return (time.thread_time_ns() - t0) / n / 1e3


def bench_tracking(sim: Simulator, friction_compensation: bool = False) -> dict:
    """2 s minimum-jerk joint move in position mode (the test's trajectory)."""
    sim.reset("rest")
    loop = SimLoop(ImpedanceControllerConfig(mode="position", feedforward="inverse_dynamics",
                                             friction_compensation=friction_compensation),
                   sim=sim)
    loop.run(0.05)
    r = track_min_jerk(loop)
    return {
        "tracking_rms_deg": r.rms_deg,
        "tracking_max_deg": r.max_deg,
        "tracking_final_deg": r.final_deg,
        "tracking_saturated_steps": r.saturated_steps,
    }


def bench_dds(window: float, sample_every: int | None, preset: str = "ideal",
              stop_estimator: bool = False,
              extra: dict[str, dict[str, object]] | None = None,
              composed: bool = False, robot_loop: bool = False) -> dict:
    """Lockstep real-time factor of sim_bridge + wrench_estimator (one joint-state sample in
    ``sample_every``; None = no estimator) + impedance_controller, on the realism ``preset``;
    the controller's stale-estimate count; with ``stop_estimator``, the time to the safe hold
    once the estimator is killed (``composed``: disabled); ``extra`` {node: {parameter:
    value}} overrides the bench's parameters (experiments); ``composed``: the estimator and
    the controller in one ``torque_loop`` process; ``robot_loop``: the simulator, the
    estimator and the controller in one ``robot_loop`` process (0068)."""
    from rosgraph_msgs.msg import Clock

    from icub_interfaces.msg import ControllerStatus
    from icub_pmp.ros.qos import LATCHED_QOS
    from icub_pmp.testing import (
        NodeGraph,
        RosProbe,
        reserve_domain_id,
        ros_environment,
        with_realism,
    )

    params = with_realism(preset, {
        "sim_bridge": {"mode": "lockstep", "cameras_enabled": False, "imu_decimation": 10,
                       "ground_truth_decimation": 10},
        "wrench_estimator": {"publish_every": 10,
                             "sample_every": sample_every or 1},
        "impedance_controller": {"use_sim_time": True},
    })
    for node, values in (extra or {}).items():
        params.setdefault(node, {}).update(values)
    nodes = ["sim_bridge", "impedance_controller"]
    if robot_loop and sample_every is not None:
        nodes = ["robot_loop"]
    elif composed and sample_every is not None:
        nodes = ["sim_bridge", "torque_loop"]
    elif sample_every is not None:
        nodes.insert(1, "wrench_estimator")
    with reserve_domain_id() as did:
        with NodeGraph(nodes, params, env=ros_environment(did)) as g:
            probe = RosProbe(did, "bench_control")
            try:
                if not (probe.wait_for_topic("/effort_command", 90) and (
                        sample_every is None
                        or probe.wait_for_topic("/estimated_joint_torques", 90))):
                    raise RuntimeError("graph did not come up:\n" + g.outputs())

                def sim_t() -> float:
                    c = probe.collect("/clock", Clock, 1, 30.0)[0]
                    return c.clock.sec + c.clock.nanosec * 1e-9

                def status() -> ControllerStatus:
                    return probe.collect("/impedance_controller/status", ControllerStatus, 1,
                                         30.0, qos=LATCHED_QOS)[0]

                time.sleep(2.0)  # warm-up
                st0 = status()
                c0 = {n: _tree_cpu_s(p.pid) for n, p in g.procs.items()}
                s0, w0 = sim_t(), time.perf_counter()
                time.sleep(window)
                s1, w1 = sim_t(), time.perf_counter()
                c1 = {n: _tree_cpu_s(p.pid) for n, p in g.procs.items()}
                st1 = status()
                timeouts = g.procs[g.host("sim_bridge")].output().count(
                    "lockstep: no /effort_command")
                out = {"rtf": (s1 - s0) / (w1 - w0), "window_s": w1 - w0,
                       "timeouts": timeouts,
                       "stale_estimate_steps": int(st1.stale_estimate_steps
                                                   - st0.stale_estimate_steps),
                       "controller_steps": int(st1.steps - st0.steps),
                       # CPU [us] per simulated ms, per process: much less load-sensitive
                       # than the wall-clock rtf (0008)
                       "cpu_us_per_sim_ms": {n: round((c1[n] - c0[n]) * 1e3 / (s1 - s0), 1)
                                             for n in c0}}
                if stop_estimator:
                    t_kill, w_kill = sim_t(), time.perf_counter()
                    if composed:
                        _disable_estimator(probe)
                    else:
                        g.kill("wrench_estimator")
                    st = status()
                    while st.status != "safe_hold" and time.perf_counter() - w_kill < 60.0:
                        time.sleep(0.05)
                        st = status()
                    out["estimator_stop_safe_hold_s"] = (
                        st.header.stamp.sec + st.header.stamp.nanosec * 1e-9 - t_kill
                        if st.status == "safe_hold" else -1.0)
                    out["estimator_stop_safe_hold_wall_s"] = time.perf_counter() - w_kill
                    out["estimator_stop_reason"] = st.safe_hold_reason
            finally:
                probe.close()
    return out


def _disable_estimator(probe) -> None:  # noqa: ANN001 (RosProbe: rclpy imported late)
    """Set /wrench_estimator's ``enabled`` false (the estimator of a composed process stops)."""
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters

    value = ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=False)
    req = SetParameters.Request(parameters=[Parameter(name="enabled", value=value)])
    res = probe.call("/wrench_estimator/set_parameters", SetParameters, req)
    if not res.results[0].successful:
        raise RuntimeError(f"enabled: false refused: {res.results[0].reason}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="short windows (< 2 min)")
    args = ap.parse_args()
    inproc_s = 3.0 if args.quick else 10.0
    window = 10.0 if args.quick else 40.0
    load0 = _load()
    print(f"load average at start: {load0} (2 cores, shared machine)", file=sys.stderr)
    sim = Simulator(SimConfig(cameras_enabled=False))
    out: dict = {}
    out.update(bench_inprocess(sim, inproc_s))
    print(f"in-process: {out}", file=sys.stderr)
    out.update(bench_tracking(sim))
    print(f"tracking: rms {out['tracking_rms_deg']:.4f} deg, final "
          f"{out['tracking_final_deg']:.4f} deg", file=sys.stderr)
    dds: dict = {}
    for key, every, composed in (("lockstep_rtf", 1, True), ("lockstep_rtf_separate", 1, False),
                                 ("lockstep_rtf_estimator_100hz", 10, False),
                                 ("lockstep_rtf_no_estimator", None, False)):
        r = bench_dds(window, every, composed=composed)
        dds[key] = dict(r)
        out[key] = r["rtf"]
        out[f"{key}_timeouts"] = r["timeouts"]
        print(f"{key}: {r}", file=sys.stderr)
    for preset in ("ideal", "icub"):
        psim = Simulator(SimConfig(cameras_enabled=False),
                         realism=RealismConfig(preset=preset))
        fig = {k: v for k, v in bench_tracking(psim, friction_compensation=True).items()
               if k != "tracking_max_deg"}
        del psim
        # ideal: the runs above (estimator on every sample) are those figures
        r = dict(dds["lockstep_rtf"]) if preset == "ideal" else bench_dds(
            window, 1, preset, stop_estimator=True, composed=True)
        sep = dict(dds["lockstep_rtf_separate"]) if preset == "ideal" else bench_dds(
            window, 1, preset)
        fig["lockstep_rtf"] = r.pop("rtf")
        fig.update({k: v for k, v in r.items() if k != "window_s"})
        fig["lockstep_rtf_separate"] = sep.pop("rtf")
        fig["separate"] = {k: v for k, v in sep.items() if k != "window_s"}
        # the torque loop inside the simulator's process (0068)
        rl = bench_dds(window, 1, preset, robot_loop=True)
        fig["lockstep_rtf_robot_loop"] = rl.pop("rtf")
        fig["robot_loop"] = {k: v for k, v in rl.items() if k != "window_s"}
        out[preset] = fig
        print(f"{preset}: {fig}", file=sys.stderr)
    out["load_start"] = load0
    out["load_end"] = _load()
    print(json.dumps(_rounded(out)))


def _rounded(v):
    """Floats rounded to 4 decimals, through nested dicts."""
    if isinstance(v, dict):
        return {k: _rounded(x) for k, x in v.items()}
    return round(v, 4) if isinstance(v, float) else v


if __name__ == "__main__":
    main()
