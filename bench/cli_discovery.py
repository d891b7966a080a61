"""Benchmark: how long a fresh CLI participant takes to discover the graph (what the ``icub``
verbs wait for), on this machine as it is loaded now.

    scripts/env.sh python bench/cli_discovery.py --quick    # 3 trials (~1 min)
    scripts/env.sh python bench/cli_discovery.py            # 10 trials

A simulator (free run, no cameras) and the impedance controller run in a private ROS domain,
started as a user starts them. Each trial opens a new rclpy context (a new DDS participant,
as every ``icub`` command does; the Python start-up of the command is not counted) and times:

- ``topic_type_s``: until /joint_states is in the graph with a publisher (``icub echo``);
- ``first_message_s``: until the first /joint_states message arrived (matched);
- ``service_ready_s``: until a /sim/reset client is matched with its server (``icub call``);
- ``action_ready_s``: until the controller's trajectory action server is matched
  (``icub send-goal``, ``icub reach``);
- ``after_restart_action_ready_s``: the controller is restarted and a new participant times
  from the restart until the action server is matched (the issue's "right after a node
  restart": node start-up plus discovery).

Each figure is given as median / p90 / max over the trials, with the 1-minute load average at
the start and the end. The CLI defaults (``icub_pmp.cli.session.DISCOVERY_TIMEOUT``) are sized
from the max. Ends with one JSON line.
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

from icub_pmp.config import config_dir  # noqa: E402
from icub_pmp.testing import NodeProcess, reserve_domain_id, ros_environment  # noqa: E402

LIMIT = 120.0  # [s] give up a measurement after this long


def _stats(values: list[float]) -> dict[str, float]:
    a = np.asarray(values, dtype=float)
    return {"median": round(float(np.median(a)), 3), "p90": round(float(np.quantile(a, 0.9)), 3),
            "max": round(float(a.max()), 3)}


def _trial(domain: int) -> dict[str, float]:
    """One fresh participant: the four waits, in seconds from its creation."""
    from rclpy.action import ActionClient
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import JointState

    from icub_interfaces.action import FollowJointTrajectory
    from icub_interfaces.srv import ResetSim
    from icub_pmp.cli.session import cli_node, spin_until, wait_for_topic_type

    os.environ["ROS_DOMAIN_ID"] = str(domain)
    out: dict[str, float] = {}
    t0 = time.monotonic()
    with cli_node("bench_discovery") as (node, executor):
        got: list[int] = []
        if wait_for_topic_type(node, executor, "/joint_states", LIMIT) is None:
            raise TimeoutError("no /joint_states publisher")
        out["topic_type_s"] = time.monotonic() - t0
        node.create_subscription(JointState, "/joint_states", lambda _m: got.append(1),
                                 qos_profile_sensor_data)
        client = node.create_client(ResetSim, "/sim/reset")
        action = ActionClient(node, FollowJointTrajectory,
                              "/impedance_controller/follow_joint_trajectory")
        pending = {"first_message_s": lambda: bool(got),
                   "service_ready_s": client.service_is_ready,
                   "action_ready_s": action.server_is_ready}

        def check() -> bool:
            for k, ready in list(pending.items()):
                if ready():
                    out[k] = time.monotonic() - t0
                    del pending[k]
            return not pending

        if not spin_until(executor, check, LIMIT):
            raise TimeoutError(f"not ready after {LIMIT} s: {sorted(pending)}")
        action.destroy()
    return out


def _after_restart(domain: int, controller: NodeProcess) -> tuple[float, NodeProcess]:
    from rclpy.action import ActionClient

    from icub_interfaces.action import FollowJointTrajectory
    from icub_pmp.cli.session import cli_node, spin_until

    controller.stop()
    t0 = time.monotonic()
    controller = _controller(domain)
    with cli_node("bench_restart") as (node, executor):
        action = ActionClient(node, FollowJointTrajectory,
                              "/impedance_controller/follow_joint_trajectory")
        if not spin_until(executor, action.server_is_ready, LIMIT):
            raise TimeoutError("the restarted controller's action was not matched")
        dt = time.monotonic() - t0
        action.destroy()
    return dt, controller


def _controller(domain: int) -> NodeProcess:
    return NodeProcess("impedance_controller", env=ros_environment(domain),
                       params_file=config_dir() / "impedance_controller.yaml")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="3 trials instead of 10")
    args = ap.parse_args()
    trials = 3 if args.quick else 10
    load0 = os.getloadavg()[0]
    with reserve_domain_id() as domain:
        env = ros_environment(domain)
        sim = NodeProcess("sim_bridge", env=env, params_file=config_dir() / "sim_bridge.yaml",
                          parameters={"cameras_enabled": False})
        controller = _controller(domain)
        try:
            _trial(domain)  # warm-up: both nodes up and discoverable
            rows = [_trial(domain) for _ in range(trials)]
            restarts = []
            for _ in range(max(1, trials // 3)):
                dt, controller = _after_restart(domain, controller)
                restarts.append(dt)
        finally:
            controller.stop()
            sim.stop()
    figures = {k: _stats([r[k] for r in rows]) for k in rows[0]}
    figures["after_restart_action_ready_s"] = _stats(restarts)
    for k, v in figures.items():
        print(f"{k:32s} median {v['median']:6.2f} s  p90 {v['p90']:6.2f} s  max {v['max']:6.2f} s")
    result = {"bench": "cli_discovery", "trials": trials, "load_start": round(load0, 2),
              "load_end": round(os.getloadavg()[0], 2), **figures}
    print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
