"""EstimateGate: in lockstep, a joint state waits for the joint-torque estimate of its stamp.

The impedance controller closes its torque loop on the wrench estimator's joint torques
(eq 5 of the force-control paper). In lockstep with the simulator, the controller answers the
joint state stamped t with the estimate of the same t when it can: a joint state that arrives
before its estimate is held (the newest replaces an older one) and released when an estimate
at least as new arrives (:meth:`estimate`), or after ``timeout`` of wall time without it
(:meth:`expired`: the simulator waits for the controller, so simulated time stands still and a
wall-clock timeout is the only one that can fire).
"""

from __future__ import annotations

import time
from typing import Callable, Generic, TypeVar

__all__ = ["EstimateGate"]

T = TypeVar("T")


class EstimateGate(Generic[T]):
    """Hold one joint-state item until its estimate arrives (module doc).

    Args:
        clock: wall clock [s] (default ``time.monotonic``).
    """

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._clock = clock
        self.estimate_ns = -1  # stamp of the newest estimate [ns]
        self._held: tuple[int, T] | None = None
        self._since = 0.0

    @property
    def holding(self) -> bool:
        """Whether a joint state is waiting for its estimate."""
        return self._held is not None

    def offer(self, stamp_ns: int, item: T) -> T | None:
        """A joint state stamped ``stamp_ns`` [ns]: returned at once when its estimate (or a
        newer one) is there, else held (replacing a held one) and None returned."""
        if self.estimate_ns >= stamp_ns:
            return item
        self._held = (stamp_ns, item)
        self._since = self._clock()
        return None

    def estimate(self, stamp_ns: int) -> T | None:
        """An estimate stamped ``stamp_ns`` [ns] arrived: the held joint state it answers
        (released), else None."""
        self.estimate_ns = max(self.estimate_ns, stamp_ns)
        held = self._held
        if held is not None and held[0] <= self.estimate_ns:
            self._held = None
            return held[1]
        return None

    def reset(self) -> None:
        """Forget the newest estimate and the held joint state (the clock went back)."""
        self.estimate_ns = -1
        self._held = None

    def expired(self, timeout: float) -> T | None:
        """The held joint state once it has waited more than ``timeout`` [s] of wall time
        (released: it is answered without its estimate), else None."""
        held = self._held
        if held is not None and self._clock() - self._since > timeout:
            self._held = None
            return held[1]
        return None
