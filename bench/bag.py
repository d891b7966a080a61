"""Bag benchmark: record the graph's streams at full rate, count drops, replay, time it.

    scripts/env.sh python bench/bag.py --quick          # 10 s of traffic, < 1 min
    scripts/env.sh python bench/bag.py                  # 60 s of traffic
    scripts/env.sh python bench/bag.py --quick --compression zstd

In a private ROS_DOMAIN_ID: ``icub bag record --all --all-services`` runs as its own process
while ``icub_pmp.testing.bag_traffic`` publishes what the simulator will (``/clock``,
``/joint_states`` and four FT wrenches at 1 kHz best effort, two 320x240 rgb8 cameras at
30 Hz, trajectories and introspected ``/pmp/reach`` calls at 2 Hz). Then the bag is replayed
at rate 1 by ``icub bag play`` while a second recorder records the replay. Figures:

- published vs recorded per topic, ``dropped`` = published - recorded (total);
- throughput (messages/s, MB/s), bag size per minute, CPU of the recorder process;
- ``replay_timing_err_ms``: median over the 1 kHz joint states of
  |(t_replay_k - t_replay_0) - (t_rec_k - t_rec_0)|, both receive times taken by a recorder,
  with p99 and max; baseline in the same run: the recording's own receive jitter against the
  publisher's 1 ms schedule (``record_jitter_ms``), and their ratio.

Crash safety (``bag_sigkill_*``): a second recorder of the 1 kHz ``/joint_states`` (reliable,
so DDS drops nothing) is SIGKILLed in the middle of the traffic. ``bag_sigkill_msgs_lost`` counts
the messages received more than ``SIGKILL_ALLOWANCE_S`` (one flush interval, 0.5 s, plus the
flusher's period, 0.25 s, plus 0.25 s) before the kill that the bag does not hold (goal 0: only
the last, unflushed chunk may be lost); ``bag_sigkill_unflushed_s`` is how much was lost at the
end; ``bag_sigkill_repaired`` says whether ``icub bag repair`` made it a bag that rosbags'
rosbag2 Reader opens with every recovered message.

Ends with ONE JSON line. The machine is shared (2 cores): the load average is reported.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from icub_pmp.bags import BagReader  # noqa: E402
from icub_pmp.testing import NodeProcess, reserve_domain_id, ros_environment  # noqa: E402

ENV = str(ROOT / "scripts/env.sh")
EXCLUDE = "^/rosout$|^/parameter_events$"


def _json(proc: NodeProcess, key: str) -> dict:
    for line in reversed(proc.output().splitlines()):
        if line.startswith("{") and key in line:
            return json.loads(line)
    raise RuntimeError(f"no JSON line with {key!r}:\n{proc.output()[-3000:]}")


def _recorder(bag: Path, env: dict, compression: str) -> NodeProcess:
    rec = NodeProcess(command=[ENV, "icub", "bag", "record", "--json", "-o", str(bag), "--all",
                               "--all-services", "--exclude", EXCLUDE, "--compression",
                               compression], env=env)
    if not rec.wait_for_output("recording to", 60):
        raise RuntimeError(rec.output())
    return rec


def _stamps_ms(bag: Path) -> tuple[np.ndarray, np.ndarray]:
    """(k, log time [ms]) of the /joint_states messages (k = header stamp in ms)."""
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import JointState

    ks, ts = [], []
    for m in BagReader(bag).messages(["/joint_states"]):
        st = deserialize_message(m.data, JointState).header.stamp
        ks.append(st.sec * 1000 + st.nanosec // 1_000_000)
        ts.append(m.log_time)
    return np.array(ks), (np.array(ts, dtype=np.int64) - (ts[0] if ts else 0)) * 1e-6


SIGKILL_ALLOWANCE_S = 1.0


def sigkill_run(env: dict, out: Path, before_kill_s: float = 3.0) -> dict:
    """Record /joint_states, SIGKILL the recorder mid-traffic, count what the bag lost."""
    import signal

    from rclpy.serialization import deserialize_message
    from rosbags.rosbag2 import Reader
    from sensor_msgs.msg import JointState

    from icub_pmp.bags import BagRepair

    bag = out / "killed"
    rec = NodeProcess(command=[ENV, "icub", "bag", "record", "-o", str(bag), "/joint_states"],
                      env=env)
    if not rec.wait_for_output("recording to", 60):
        raise RuntimeError(rec.output())
    traffic = NodeProcess(command=[ENV, "python", "-m", "icub_pmp.testing.bag_traffic",
                                   "--duration", str(before_kill_s + 3.0), "--no-cameras",
                                   "--no-reach", "--no-clock", "--reliable",
                                   "--subscribers", "30"], env=env)
    if not traffic.wait_for_output('"ready"', 90):
        raise RuntimeError(traffic.output())
    time.sleep(before_kill_s)
    t_kill = time.time_ns()
    rec.signal(signal.SIGKILL)
    rec.proc.wait(10)
    traffic.proc.wait(120)
    ks, logs = [], []
    for m in BagReader(bag).messages(["/joint_states"]):
        st = deserialize_message(m.data, JointState).header.stamp
        ks.append(st.sec * 1000 + st.nanosec // 1_000_000)
        logs.append(m.log_time)
    k, log = np.array(ks, dtype=np.int64), np.array(logs, dtype=np.int64)
    if k.size == 0:
        return {"bag_sigkill_msgs_lost": None, "bag_sigkill_recovered": 0,
                "bag_sigkill_error": "no message recovered"}
    offset = float(np.median(log - k * 1_000_000))  # receive time of message k: offset + k ms
    k_cut = int((t_kill - SIGKILL_ALLOWANCE_S * 1e9 - offset) // 1_000_000)
    expected = np.arange(k[0], k_cut + 1)
    lost = int(np.setdiff1d(expected, k).size)
    repaired = BagRepair(bag).run()
    with Reader(bag) as r:
        readable = r.message_count
    return {
        "bag_sigkill_msgs_lost": lost,
        "bag_sigkill_recovered": int(k.size),
        "bag_sigkill_unflushed_s": round((t_kill - int(log.max())) / 1e9, 3),
        "bag_sigkill_repaired": bool(repaired.repaired and readable == k.size),
    }


def run(duration: float, compression: str, out: Path) -> dict:
    load0 = os.getloadavg()[0]
    with reserve_domain_id() as did:
        env = ros_environment(did)
        # ---------------------------------------------------------------- record
        bag = out / "recorded"
        rec = _recorder(bag, env, compression)
        traffic = NodeProcess(command=[ENV, "python", "-m", "icub_pmp.testing.bag_traffic",
                                       "--duration", str(duration)], env=env)
        traffic.proc.wait(duration + 120)
        published = {k: v for k, v in _json(traffic, "published")["published"].items()
                     if not k.startswith("/pmp/reach")}
        answered = _json(traffic, "published")["published"].get("/pmp/reach (answered)", 0)
        late_ticks = _json(traffic, "published")["late_ticks"]
        rec.stop(60)
        rstats = _json(rec, "cpu_s")
        written = rstats["written"]
        # ---------------------------------------------------------------- replay
        again = out / "replayed"
        rec2 = _recorder(again, env, "none")
        play = NodeProcess(command=[ENV, "icub", "bag", "play", str(bag), "--json",
                                    "--wait-for-subscribers", "30"], env=env)
        play.proc.wait(duration + 120)
        pstats = _json(play, "published")
        time.sleep(0.5)
        rec2.stop(60)
        replay_written = _json(rec2, "cpu_s")["written"]
        # ---------------------------------------------------------------- SIGKILL
        killed = sigkill_run(env, out)
    # -------------------------------------------------------------------- figures
    recorded_total = sum(written.get(t, 0) for t in published)
    published_total = sum(published.values())
    dropped = {t: n - written.get(t, 0) for t, n in published.items()}
    events = written.get("/pmp/reach/_service_event", 0)
    k0, t0 = _stamps_ms(bag)
    k1, t1 = _stamps_ms(again)
    common = np.intersect1d(k0, k1)
    a = t0[np.searchsorted(k0, common)]
    b = t1[np.searchsorted(k1, common)]
    a, b = a - a[0], b - b[0]
    err = np.abs(b - a)
    jitter = np.abs(t0 - (k0 - k0[0]))  # receive time vs the publisher's 1 ms schedule
    size = sum(f.stat().st_size for f in (bag).glob("*.mcap"))
    total_msgs = recorded_total + events
    return {
        "published": published_total,
        "recorded": recorded_total,
        "dropped": published_total - recorded_total,
        "dropped_per_topic": dropped,
        "reach_events_recorded": events,
        "reach_events_expected": 2 * answered,
        "dds_lost": sum(rstats.get("lost", {}).values()),
        "publisher_late_ticks": late_ticks,
        "duration_s": duration,
        "throughput_msgs_per_s": round(total_msgs / duration, 1),
        "throughput_mb_per_s": round(size / 1e6 / duration, 2),
        "bag_mb_per_min": round(size / 1e6 / duration * 60, 1),
        "compression": compression,
        "recorder_cpu_percent": round(100 * rstats["cpu_s"] / rstats["duration_s"], 1),
        "recorder_cpu_us_per_msg": round(1e6 * rstats["cpu_s"] / max(1, total_msgs), 1),
        "replayed": sum(pstats["published"].values()),
        "replay_recorded": sum(replay_written.values()),
        "replay_timing_err_ms": round(float(np.median(err)), 3),
        "replay_timing_err_p99_ms": round(float(np.percentile(err, 99)), 3),
        "replay_timing_err_max_ms": round(float(err.max()), 3),
        "player_late_median_ms": round(pstats["late_median_ms"], 3),
        "player_late_p99_ms": round(pstats["late_p99_ms"], 3),
        "record_jitter_ms": round(float(np.median(jitter)), 3),
        "replay_err_vs_record_jitter": round(float(np.median(err) / max(np.median(jitter), 1e-6)),
                                             2),
        **killed,
        "load_avg_1min": [round(load0, 2), round(os.getloadavg()[0], 2)],
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="10 s of traffic (< 1 min in all)")
    ap.add_argument("--duration", type=float, default=None, help="traffic duration [s]")
    ap.add_argument("--compression", choices=("none", "zstd"), default="none")
    ap.add_argument("--keep", type=Path, default=None, help="keep the bags in this directory")
    args = ap.parse_args()
    duration = args.duration or (10.0 if args.quick else 60.0)
    if args.keep:
        args.keep.mkdir(parents=True, exist_ok=True)
        result = run(duration, args.compression, args.keep)
    else:
        with tempfile.TemporaryDirectory(prefix="bench_bag_") as tmp:
            result = run(duration, args.compression, Path(tmp))
    print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
