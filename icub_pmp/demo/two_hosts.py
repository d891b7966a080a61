"""The graph split over two hosts, as iCub setups run it: the robot's PC (simulator, 1 kHz
impedance controller, wrench estimator, robot state publisher) and a laptop (PMP planner,
Cartesian solver, gaze controller, motion segmenter), joined by one Ethernet link.

The two hosts are two network namespaces joined by a veth pair (:class:`VethLink`); between
them DDS goes over UDP (the laptop offers UDP locators only: ``config/fastdds_udp.xml``; the
robot's PC keeps shared memory inside itself), discovery stays off multicast beyond each host
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``) and finds the other host through a peers list
(``ROS_STATIC_PEERS``). A driver on the laptop runs the demo's first phase (the bimanual PMP
reach to the box, judged in the physics) and measures:

- ``cross_host_rtt_ms_median``: round trip of a service call from the laptop to a node on the
  robot's PC, beside ``same_host_rtt_ms_median``, the same server called from the robot's PC
  (same client code, same number of calls);
- ``cross_host_lockstep_rtf``: simulated over wall time while the laptop's nodes plan and
  stream over the link (lockstep: the 1 kHz loop stays on the robot's PC, as on the iCub);
- ``link_packets``: packets the laptop sent over the link (the graph really used it).

``--single-host`` runs the same graph and driver in one namespace (the baseline of the same
process). Needs root for the namespaces; without it the error says why.

    sudo scripts/env.sh python -m icub_pmp.demo.two_hosts            # one JSON line
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time

from icub_pmp.config import repo_root
from icub_pmp.graph import (
    Host,
    NodeGraph,
    NodeProcess,
    VethLink,
    VethLinkError,
    reserve_domain_id,
    ros_environment,
)

__all__ = ["ROBOT_NODES", "LAPTOP_NODES", "host_environment", "run_two_hosts", "main"]

ROBOT_NODES = ["sim_bridge", "impedance_controller", "wrench_estimator", "robot_state_publisher"]
LAPTOP_NODES = ["pmp_planner", "cartesian_solver", "gaze_controller", "motion_segmenter"]
#: the service whose round trip is timed (a node on the robot's PC that is idle between calls)
RTT_SERVICE = "/robot_state_publisher/get_parameters"
UDP_PROFILE = "config/fastdds_udp.xml"


def host_environment(domain_id: int, peers: list[str], udp_only: bool) -> dict[str, str]:
    """The environment of every process of one host: the private domain, discovery limited to
    the host plus ``peers`` (unicast); ``udp_only``: no shared-memory transport (else the
    project's default profile, shared memory inside the host)."""
    env = ros_environment(domain_id)
    env["ROS_STATIC_PEERS"] = ";".join(peers)
    profile = UDP_PROFILE if udp_only else "config/fastdds.xml"
    env["FASTRTPS_DEFAULT_PROFILES_FILE"] = str(repo_root() / profile)
    return env


def _parameters(realism: str | None = None) -> dict[str, dict[str, object]]:
    """The demo's node parameters (lockstep, simulated time) on the simulator's ``realism``
    preset (None: the shipped config's)."""
    from icub_pmp.demo.scenario import graph_parameters

    return graph_parameters(realism)


def time_service_calls(service: str, calls: int, timeout: float = 60.0) -> list[float]:
    """Round-trip times [ms] of ``calls`` GetParameters calls to ``service`` from a node of
    this process (after the server is matched)."""
    import rclpy
    from rcl_interfaces.srv import GetParameters
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor

    ctx = Context()
    rclpy.init(context=ctx)
    try:
        node = rclpy.create_node("icub_rtt_probe", context=ctx)
        ex = SingleThreadedExecutor(context=ctx)
        ex.add_node(node)
        client = node.create_client(GetParameters, service)
        deadline = time.monotonic() + timeout
        while not client.service_is_ready():
            if time.monotonic() > deadline:
                raise TimeoutError(f"{service} not available after {timeout} s")
            ex.spin_once(timeout_sec=0.1)
        out = []
        for _ in range(calls + 3):  # 3 warm-up calls
            t0 = time.perf_counter()
            fut = client.call_async(GetParameters.Request(names=["use_sim_time"]))
            ex.spin_until_future_complete(fut, timeout_sec=10.0)
            if not fut.done():
                raise TimeoutError(f"{service} gave no answer within 10 s")
            out.append((time.perf_counter() - t0) * 1e3)
        return out[3:]
    finally:
        rclpy.try_shutdown(context=ctx)


def drive(calls: int) -> dict[str, object]:
    """On the laptop: wait for the graph, time the link, run the demo's phase 1."""
    from icub_pmp.demo.demo_runner import DemoRunner
    from icub_pmp.demo.scenario import bimanual_pregrasp
    from icub_pmp.ros.probe import RosProbe

    rtt = time_service_calls(RTT_SERVICE, calls)
    probe = RosProbe(int(os.environ["ROS_DOMAIN_ID"]), "two_hosts_driver")
    try:
        runner = DemoRunner(probe)
        runner.wait_ready(services=("/pmp/reach", "/sim/set_object_pose"))
        runner.wait_sim(0.5)
        sim0, wall0 = runner.sim_time(), time.monotonic()
        targets = bimanual_pregrasp(runner.object_position("box"))
        result = runner.pmp_reach("bimanual_reach", targets, use_torso=True, tau=2.0)
        rtf = (runner.sim_time() - sim0) / max(1e-9, time.monotonic() - wall0)
    finally:
        probe.close()
    return {
        "reach_success": bool(result.success),
        "reach_message": result.message,
        "hand_err_mm": {h: round(v * 1e3, 2) for h, v in result.physics_residual.items()},
        "rtt_ms_median": statistics.median(rtt),
        "rtt_ms_p95": sorted(rtt)[int(0.95 * (len(rtt) - 1))],
        "lockstep_rtf": rtf,
    }


def _json_line(text: str, key: str) -> dict:
    for line in reversed(text.splitlines()):
        if line.startswith("{") and key in line:
            return json.loads(line)
    raise RuntimeError(f"no JSON line with {key!r} in the output:\n{text[-4000:]}")


def _wait(proc: NodeProcess, timeout: float) -> None:
    """Wait for ``proc`` to exit; stop it after ``timeout`` s."""
    try:
        proc.proc.wait(timeout)
    except Exception:  # subprocess.TimeoutExpired
        proc.stop()


def _python(prefix: list[str], *args: str) -> list[str]:
    return [*prefix, str(repo_root() / "scripts/env.sh"), sys.executable, "-m",
            "icub_pmp.demo.two_hosts", *args]


def run_two_hosts(single_host: bool = False, delay_ms: float = 0.0, calls: int = 50,
                  timeout: float = 600.0, realism: str | None = None) -> dict[str, object]:
    """Start the split graph (or the whole graph on one host) on the ``realism`` preset
    (None: the shipped one), run the driver, return the figures. Raises VethLinkError when
    namespaces cannot be made here."""
    with reserve_domain_id() as domain, VethLink(delay_ms=delay_ms) as link:
        # the robot's PC keeps shared memory inside itself (its 1 kHz loop); the laptop
        # announces UDP locators only, so everything between the two goes over the link even
        # though both namespaces share this machine's /dev/shm
        robot_env = host_environment(domain, [link.laptop.address], udp_only=False)
        laptop_env = host_environment(domain, [link.robot.address], udp_only=True)
        laptop: Host = link.robot if single_host else link.laptop
        if single_host:
            laptop_env = robot_env
        params = _parameters(realism)
        packets0 = link.tx_packets(link.laptop)
        with NodeGraph(ROBOT_NODES, params, env=robot_env, prefix=link.prefix(link.robot)) \
                as robot_graph, \
             NodeGraph(LAPTOP_NODES, params, env=laptop_env, prefix=link.prefix(laptop)) \
                as laptop_graph:
            # one after the other: the same-host calls first, then the laptop's driver
            local = NodeProcess(command=_python(link.prefix(link.robot), "--time-calls",
                                                "--calls", str(calls)), env=robot_env)
            driver = None
            try:
                _wait(local, timeout)
                driver = NodeProcess(command=_python(link.prefix(laptop), "--drive",
                                                     "--calls", str(calls)), env=laptop_env)
                _wait(driver, timeout)
                same = _json_line(local.output(), "rtt_ms_median")
                figures = _json_line(driver.output(), "reach_success")
            except RuntimeError as exc:
                raise RuntimeError(f"{exc}\n{robot_graph.outputs()[-3000:]}\n"
                                   f"{laptop_graph.outputs()[-3000:]}") from None
            finally:
                for proc in (local, driver):
                    if proc is not None:
                        proc.stop()
        packets = link.tx_packets(link.laptop) - packets0
    prefix = "single_host" if single_host else "cross_host"
    return {
        "setup": "single host" if single_host else "two hosts (veth, UDP, static peers)",
        f"{prefix}_reach_success": figures["reach_success"],
        f"{prefix}_reach_message": figures["reach_message"],
        f"{prefix}_hand_err_mm": figures["hand_err_mm"],
        f"{prefix}_rtt_ms_median": round(figures["rtt_ms_median"], 3),
        f"{prefix}_rtt_ms_p95": round(figures["rtt_ms_p95"], 3),
        f"{prefix}_lockstep_rtf": round(figures["lockstep_rtf"], 3),
        "same_host_rtt_ms_median": round(same["rtt_ms_median"], 3),
        "link_packets": packets,
        "delay_ms": delay_ms,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--single-host", action="store_true",
                    help="every node in one namespace (the baseline)")
    ap.add_argument("--delay-ms", type=float, default=0.0,
                    help="one-way link delay added with tc netem [ms]")
    ap.add_argument("--calls", type=int, default=50, help="timed service calls")
    ap.add_argument("--drive", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--time-calls", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.drive:
        print(json.dumps(drive(args.calls)), flush=True)
        return 0
    if args.time_calls:
        rtt = time_service_calls(RTT_SERVICE, args.calls)
        print(json.dumps({"rtt_ms_median": statistics.median(rtt)}), flush=True)
        return 0
    try:
        out = run_two_hosts(args.single_host, args.delay_ms, args.calls)
    except VethLinkError as exc:
        print(f"two_hosts: network namespaces cannot be created here: {exc}", file=sys.stderr)
        return 2
    print(json.dumps(out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
