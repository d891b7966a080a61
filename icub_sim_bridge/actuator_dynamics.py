"""ActuatorDynamics: the commanded torque reaches the joint late and smoothed.

A delay of ``delay_steps`` physics steps (the command of step k is applied at step
k + delay_steps) followed by an optional first-order torque bandwidth ``bandwidth_hz``
(exact discretisation at ``dt``). With 0 and 0 the command passes unchanged.
"""

from __future__ import annotations

import collections
import math

import numpy as np

__all__ = ["ActuatorDynamics"]


class ActuatorDynamics:
    """Delay + first-order lag of an (n,) torque command (module doc)."""

    def __init__(self, n: int, delay_steps: int, bandwidth_hz: float, dt: float):
        self.n = n
        self.delay_steps = int(delay_steps)
        self.alpha = 1.0 - math.exp(-2.0 * math.pi * bandwidth_hz * dt) if bandwidth_hz > 0 \
            else 1.0
        self._queue: collections.deque[np.ndarray] = collections.deque()
        self._out = np.zeros(n)
        self.reset(np.zeros(n))

    def reset(self, tau: np.ndarray) -> None:
        """Start from a steady torque ``tau`` (n,) [N m] (after a hold or a reset)."""
        self._queue.clear()
        for _ in range(self.delay_steps):
            self._queue.append(np.array(tau, dtype=float))
        self._out = np.array(tau, dtype=float)

    def apply(self, tau_cmd: np.ndarray) -> np.ndarray:
        """Push this step's command (n,), return the torque applied this step (n,)."""
        self._queue.append(np.array(tau_cmd, dtype=float))
        delayed = self._queue.popleft()
        self._out += self.alpha * (delayed - self._out)
        return self._out.copy()
