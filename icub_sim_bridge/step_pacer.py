"""StepPacer: free-run pacing of the simulator, simulated time at ``real_time_factor`` x wall
time.

The anchor (a wall time and the simulated time then) is re-set when the factor changes, after
a pause (:meth:`restart`) and when the loop has fallen far behind (a stall of the machine):
the simulator then goes on at the factor from where it is instead of catching up with a burst
of unpaced steps.
"""

from __future__ import annotations

import time
from typing import Callable

from icub_pmp.errors import InvalidInput

__all__ = ["StepPacer"]


class StepPacer:
    """How long to wait after a step so that simulated time follows wall time.

    Args:
        clock: wall clock [s] (default ``time.perf_counter``).
        min_wait: waits shorter than this are skipped [s] (a sleep overshoots by ~1 ms).
        wake_early: a wait ends this much before the target time [s].
        max_lag: behind the target by more than this, re-anchor instead of catching up [s].
    """

    def __init__(
        self,
        clock: Callable[[], float] = time.perf_counter,
        min_wait: float = 0.002,
        wake_early: float = 0.001,
        max_lag: float = 0.1,
    ) -> None:
        for name, v in (("min_wait", min_wait), ("wake_early", wake_early),
                        ("max_lag", max_lag)):
            if not v >= 0:
                raise InvalidInput(f"StepPacer {name}: expected a value >= 0 s, got {v}")
        self._clock = clock
        self.min_wait, self.wake_early, self.max_lag = min_wait, wake_early, max_lag
        self._wall0 = clock()
        self._sim0 = 0.0
        self._factor: float | None = None
        self.restarts = 0

    def restart(self, sim_time: float) -> None:
        """Anchor pacing at now = ``sim_time`` [s] (after a pause or a mode change)."""
        self._wall0, self._sim0 = self._clock(), float(sim_time)
        self.restarts += 1

    def wait_time(self, sim_time: float, real_time_factor: float) -> float:
        """Seconds to wait after reaching ``sim_time`` [s] at ``real_time_factor`` (> 0;
        0 = as fast as possible: never waits). 0 when no wait is due."""
        if real_time_factor <= 0:
            self._factor = None
            return 0.0
        if real_time_factor != self._factor:
            self._factor = real_time_factor
            self.restart(sim_time)
            return 0.0
        target = self._wall0 + (sim_time - self._sim0) / real_time_factor
        ahead = target - self._clock()
        if ahead > self.min_wait:
            return ahead - self.wake_early
        if ahead < -self.max_lag:
            self.restart(sim_time)
        return 0.0
