"""The simulated time a test probe reads on /clock."""

from __future__ import annotations

import time

from rosgraph_msgs.msg import Clock

from icub_pmp.ros.probe import RosProbe

__all__ = ["sim_time", "wait_sim"]


def sim_time(probe: RosProbe) -> float:
    """The latest /clock [s] (AssertionError when none within 30 s)."""
    c = probe.collect("/clock", Clock, 1, 30.0)
    assert c, "no /clock within 30 s"
    return c[0].clock.sec + c[0].clock.nanosec * 1e-9


def wait_sim(probe: RosProbe, dt: float, timeout: float = 120.0) -> None:
    """Wait until ``dt`` s of simulated time have passed (AssertionError after ``timeout`` s
    of wall time)."""
    t0 = t = sim_time(probe)
    deadline = time.monotonic() + timeout
    while t - t0 < dt and time.monotonic() < deadline:
        time.sleep(0.2)
        t = sim_time(probe)
    assert t - t0 >= dt, f"simulated time advanced only {t - t0:.3f} s in {timeout} s"
