"""ArrivalMonitor: whether a Cartesian goal arrived, judged on the measured robot.

A reach is "reached" only when the hands measured after the motion (forward kinematics of the
measured joint states, not the planner's prediction) are within ``tolerance`` of their
targets. After the trajectory's last point the monitor waits until every hand has settled (its
speed below ``settle_speed`` for ``settle_time``) or ``settle_timeout`` has passed, then
judges. Times are those of the joint states (simulated time in the simulator).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Mapping, NamedTuple

import numpy as np

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError, InvalidInput

__all__ = ["ArrivalConfig", "ArrivalMonitor", "Arrival"]


@dataclasses.dataclass(frozen=True)
class ArrivalConfig(ConfigBase):
    """How arrival is judged."""

    arrival_tolerance: float = 0.01  # largest hand-to-target distance of a reached goal [m]
    settle_speed: float = 0.005  # a hand slower than this is still [m/s]
    settle_time: float = 0.2  # every hand still this long after the end = settled [s]
    settle_timeout: float = 2.0  # judge anyway this long after the end [s]

    def validate(self) -> None:
        """Every field finite and > 0 (raises :class:`ConfigError`)."""
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if not (isinstance(v, float) and math.isfinite(v) and v > 0):
                raise ConfigError(f"{f.name}: expected a finite value > 0, got {v!r}")


class Arrival(NamedTuple):
    """The judgement: per hand the measured distance to the target [m] and the measured
    position (3,) [m]; ``reached``: every distance within the tolerance; ``settled``: the
    hands came to rest (else the settle timeout decided)."""

    errors: Mapping[str, float]
    positions: Mapping[str, np.ndarray]
    reached: bool
    settled: bool


class ArrivalMonitor:
    """Feed measured hand positions with :meth:`update`; :meth:`judge` once :meth:`settled`.

    ``targets``: hand -> (3,) target [m] (root_link); ``end``: time of the trajectory's last
    point [s] (set later with :meth:`set_end` when unknown at the start).
    """

    def __init__(self, targets: Mapping[str, np.ndarray], config: ArrivalConfig | None = None,
                 end: float = math.inf):
        if not targets:
            raise InvalidInput("arrival: no target")
        self.targets = {h: np.asarray(p, dtype=float).reshape(3) for h, p in targets.items()}
        for h, p in self.targets.items():
            if not np.all(np.isfinite(p)):
                raise InvalidInput(f"arrival: target of {h!r} is not finite: {p}")
        self.config = config or ArrivalConfig()
        self.end = float(end)
        self._t: float | None = None
        self._pos: dict[str, np.ndarray] = {}
        self._still_since: float | None = None
        self.errors: dict[str, float] = {}

    def set_end(self, end: float) -> None:
        """Time of the trajectory's last point [s]."""
        self.end = float(end)

    def update(self, t: float, positions: Mapping[str, np.ndarray]) -> dict[str, float]:
        """A measured sample at ``t`` [s]: hand -> (3,) position [m]. Returns the distances
        to the targets [m]. Samples not newer than the last one are ignored."""
        if self._t is not None and t <= self._t:
            return self.errors
        pos = {h: np.asarray(positions[h], dtype=float).reshape(3) for h in self.targets}
        if self._t is not None:
            dt = t - self._t
            speed = max(float(np.linalg.norm(pos[h] - self._pos[h])) / dt for h in pos)
            if speed < self.config.settle_speed:
                if self._still_since is None:
                    self._still_since = self._t
            else:
                self._still_since = None
        self._t, self._pos = float(t), pos
        self.errors = {h: float(np.linalg.norm(pos[h] - self.targets[h])) for h in pos}
        return self.errors

    def settled(self) -> bool:
        """True once the hands are still for ``settle_time`` after the end, or
        ``settle_timeout`` after it."""
        if self._t is None or self._t < self.end:
            return False
        if self._t >= self.end + self.config.settle_timeout:
            return True
        return (self._still_since is not None
                and self._t - max(self._still_since, self.end) >= self.config.settle_time)

    def judge(self) -> Arrival:
        """The arrival from the latest sample (raises when no sample came)."""
        if self._t is None:
            raise InvalidInput("arrival: no measured sample yet")
        still = (self._still_since is not None
                 and self._t - max(self._still_since, self.end) >= self.config.settle_time)
        reached = all(e <= self.config.arrival_tolerance for e in self.errors.values())
        return Arrival(dict(self.errors), {h: p.copy() for h, p in self._pos.items()},
                       reached, still)
