"""JointStateCache over DDS: the newest joint state on demand, and ``latest(wait=...)`` for a
request that comes right after start-up, before the first sample."""

from __future__ import annotations

import threading
import time

from sensor_msgs.msg import JointState

from icub_pmp.ros.joint_state_cache import JointStateCache


def _publish_later(probe, delay: float, positions: list[float], stop: threading.Event):
    pub = probe.node.create_publisher(JointState, "/cache_test/joint_states", 10)

    def run():
        time.sleep(delay)
        while not stop.is_set():
            msg = JointState(name=["a", "b"], position=positions)
            msg.header.stamp.sec = 12
            pub.publish(msg)
            time.sleep(0.01)

    t = threading.Thread(target=run, daemon=True)
    t.start()
    return t


def test_latest_waits_for_the_first_sample_only_when_asked(ros_probe):
    cache = JointStateCache(ros_probe.node, topic="/cache_test/joint_states")
    stop = threading.Event()
    try:
        assert cache.latest() is None  # nothing published yet, no wait asked
        assert cache.latest(wait=0.2) is None  # nobody publishes: None after the wait
        thread = _publish_later(ros_probe, 0.5, [0.25, -1.5], stop)
        st = cache.latest(wait=30.0)  # published 0.5 s later: the wait returns it
        assert st is not None
        assert st.positions == {"a": 0.25, "b": -1.5}
        assert st.t == 12.0
        assert cache.latest() is not None
    finally:
        stop.set()
        cache.close()
    thread.join(timeout=2.0)
