"""A stand-in for the simulator's traffic at known rates, for bag tests and ``bench/bag.py``.

    python -m icub_pmp.testing.bag_traffic --duration 3 [--no-cameras] [--no-clock]

Publishes, from one process, what the node graph records: ``/clock`` and
``/joint_states`` (23 joints) and the four FT wrenches ``/ft/*`` at 1 kHz (best effort), both
cameras ``/cam/left|right/image_raw`` (rgb8 320x240, 30 Hz, sensor-data QoS),
``/joint_trajectory`` (reliable, 2 Hz) and reach requests: a ``/pmp/reach`` service with
service introspection on (so ``/pmp/reach/_service_event`` carries every request and response)
called by the same process at 2 Hz. Message ``k`` of a topic carries ``k`` (header stamp =
``k`` ms of "sim time" for the 1 kHz topics; the first pixel byte of image ``k`` is
``k % 256``) so a test can check order and content. ``--reliable`` makes every topic reliable
with depth 1000, so DDS cannot drop (the default is the graph's QoS).

It waits until every publisher has a subscriber (``--subscribers``), publishes for
``--duration`` s on an absolute 1 ms schedule, waits until its subscribers acknowledged every
reliable sample, then prints ONE JSON line
``{"published": {topic: count}, "duration_s": ..., "late_ticks": ..., "acked": ...}``.
"""

from __future__ import annotations

import argparse
import json
import sys
import threading
import time

import numpy as np
import rclpy
from builtin_interfaces.msg import Time
from geometry_msgs.msg import WrenchStamped
from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rclpy.service_introspection import ServiceIntrospectionState
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Image, JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from icub_interfaces.srv import Reach

__all__ = ["TrafficNode", "main", "FT_TOPICS", "CAMERA_TOPICS", "JOINTS"]

FT_TOPICS = ("/ft/l_arm_ft", "/ft/r_arm_ft", "/ft/l_leg_ft", "/ft/r_leg_ft")
CAMERA_TOPICS = ("/cam/left/image_raw", "/cam/right/image_raw")
JOINTS = (
    "torso_pitch torso_roll torso_yaw l_shoulder_pitch l_shoulder_roll l_shoulder_yaw l_elbow "
    "l_wrist_prosup l_wrist_pitch l_wrist_yaw r_shoulder_pitch r_shoulder_roll r_shoulder_yaw "
    "r_elbow r_wrist_prosup r_wrist_pitch r_wrist_yaw neck_pitch neck_roll neck_yaw eyes_tilt "
    "eyes_version eyes_vergence"
).split()
WIDTH, HEIGHT = 320, 240


def _stamp(ms: int) -> Time:
    return Time(sec=ms // 1000, nanosec=(ms % 1000) * 1_000_000)


class TrafficNode(Node):
    """Publishers of the recorded topics and a /pmp/reach server with introspection."""

    def __init__(self, cameras: bool = True, clock: bool = True, reach: bool = True,
                 reliable: bool = False):
        super().__init__("bag_traffic")
        # The graph's QoS (best effort for sensors), or reliable with a deep history: then DDS
        # itself cannot lose a sample, and a count mismatch can only come from the recorder.
        sensor = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE) if reliable \
            else qos_profile_sensor_data
        self.clock_pub = self.create_publisher(Clock, "/clock", sensor) if clock else None
        self.js_pub = self.create_publisher(JointState, "/joint_states", sensor)
        self.ft_pubs = [self.create_publisher(WrenchStamped, t, sensor) for t in FT_TOPICS]
        self.cam_pubs = (
            [self.create_publisher(Image, t, sensor) for t in CAMERA_TOPICS] if cameras else []
        )
        self.traj_pub = self.create_publisher(
            JointTrajectory, "/joint_trajectory",
            QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE),
        )
        self.reach_srv = self.reach_cli = None
        if reach:
            self.reach_srv = self.create_service(Reach, "/pmp/reach", self._on_reach)
            self.reach_srv.configure_introspection(
                self.get_clock(), QoSProfile(depth=100), ServiceIntrospectionState.CONTENTS
            )
            self.reach_cli = self.create_client(Reach, "/pmp/reach")
        self.counts: dict[str, int] = {}
        self.reach_answered = 0

    def _on_reach(self, req: Reach.Request, res: Reach.Response) -> Reach.Response:
        self.reach_answered += 1
        res.success = True
        res.message = f"request {req.tau:.0f}"
        return res

    def publishers(self) -> list:
        """All topic publishers (for the wait on subscribers)."""
        pubs = [self.js_pub, *self.ft_pubs, *self.cam_pubs, self.traj_pub]
        return pubs + ([self.clock_pub] if self.clock_pub else [])

    def _pub(self, pub, msg) -> None:
        pub.publish(msg)
        self.counts[pub.topic_name] = self.counts.get(pub.topic_name, 0) + 1

    def run(self, duration: float) -> int:
        """Publish for ``duration`` s on an absolute 1 ms schedule; returns late ticks."""
        js = JointState(name=list(JOINTS), position=[0.0] * len(JOINTS),
                        velocity=[0.0] * len(JOINTS), effort=[0.0] * len(JOINTS))
        ft = [WrenchStamped() for _ in FT_TOPICS]
        for w, t in zip(ft, FT_TOPICS):
            w.header.frame_id = t.rsplit("/", 1)[1]
        images = []
        # A smooth image with sensor noise (compresses about like a rendered frame; a
        # constant image would make zstd look unrealistically good). Byte 0 carries the index.
        rng = np.random.default_rng(0)
        yy, xx = np.mgrid[0:HEIGHT, 0:WIDTH]
        base = np.stack([xx * 255 // WIDTH, yy * 255 // HEIGHT, (xx + yy) % 256], axis=-1)
        pixels = np.clip(base + rng.normal(0, 6, base.shape), 0, 255).astype(np.uint8).tobytes()
        for i, _ in enumerate(self.cam_pubs):
            im = Image(height=HEIGHT, width=WIDTH, encoding="rgb8", step=3 * WIDTH)
            im.header.frame_id = ("l_eye_optical", "r_eye_optical")[i]
            images.append(im)
        traj = JointTrajectory(joint_names=list(JOINTS[:7]))
        n_ticks = int(round(duration * 1000))
        late = 0
        t0 = time.perf_counter()
        for k in range(n_ticks):
            target = t0 + k * 1e-3
            delay = target - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
            elif delay < -2e-3:
                late += 1
            stamp = _stamp(k)
            if self.clock_pub is not None:
                self._pub(self.clock_pub, Clock(clock=stamp))
            js.header.stamp = stamp
            js.position[0] = k * 1e-3
            self._pub(self.js_pub, js)
            for pub, w in zip(self.ft_pubs, ft):
                w.header.stamp = stamp
                w.wrench.force.x = float(k)
                self._pub(pub, w)
            if images and k % 33 == 0:
                n = k // 33
                for pub, im in zip(self.cam_pubs, images):
                    im.header.stamp = stamp
                    im.data = bytes([n % 256]) + pixels[1:]
                    self._pub(pub, im)
            if k % 500 == 250:
                traj.header.stamp = stamp
                traj.points = [JointTrajectoryPoint(positions=[k * 1e-3] * 7)]
                self._pub(self.traj_pub, traj)
                if self.reach_cli is not None:
                    req = Reach.Request(hands=["right"], tau=float(k))
                    self.reach_cli.call_async(req)
                    self.counts["/pmp/reach (calls)"] = self.counts.get("/pmp/reach (calls)", 0) + 1
        return late


def main(argv: list[str] | None = None) -> int:
    """Entry point: publish, then print the JSON line of counts."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=3.0, help="publishing time [s]")
    ap.add_argument("--subscribers", type=float, default=20.0,
                    help="wait up to this long [s] for a subscriber on every topic")
    ap.add_argument("--settle", type=float, default=0.5, help="extra wait after matching [s]")
    ap.add_argument("--no-cameras", action="store_true")
    ap.add_argument("--no-clock", action="store_true")
    ap.add_argument("--no-reach", action="store_true")
    ap.add_argument("--reliable", action="store_true",
                    help="reliable QoS, depth 1000 for every topic (default: the graph's QoS)")
    args = ap.parse_args(argv)
    rclpy.init()
    node = TrafficNode(cameras=not args.no_cameras, clock=not args.no_clock,
                       reach=not args.no_reach, reliable=args.reliable)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    done = threading.Event()

    def spin() -> None:
        while not done.is_set():
            executor.spin_once(timeout_sec=0.05)

    spinner = threading.Thread(target=spin, daemon=True)
    spinner.start()
    try:
        deadline = time.monotonic() + args.subscribers
        while time.monotonic() < deadline and not all(
            p.get_subscription_count() > 0 for p in node.publishers()
        ):
            time.sleep(0.02)
        unmatched = [p.topic_name for p in node.publishers() if p.get_subscription_count() == 0]
        print(json.dumps({"ready": True, "unmatched": unmatched}), flush=True)
        time.sleep(args.settle)
        t0 = time.perf_counter()
        late = node.run(args.duration)
        elapsed = time.perf_counter() - t0
        time.sleep(0.5)  # let the last service answers go out
        acked = all(  # reliable: every subscriber holds every sample (nothing in flight)
            p.wait_for_all_acked(Duration(seconds=20)) for p in node.publishers()
            if p.qos_profile.reliability == ReliabilityPolicy.RELIABLE
        )
        node.counts["/pmp/reach (answered)"] = node.reach_answered
        print(json.dumps({"published": node.counts, "duration_s": round(elapsed, 3),
                          "late_ticks": late, "acked": acked}), flush=True)
    except KeyboardInterrupt:
        pass
    finally:
        done.set()
        spinner.join(2.0)
        executor.shutdown(timeout_sec=1.0)
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
