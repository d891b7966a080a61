"""CommandWatchdog: when the simulator holds the robot because its controller stopped
answering, and when it hands the robot back.

The iCub's joint boards stop a joint whose set-point stream stops; the simulator does the
same: without effort commands it never keeps applying the last torques (with a dead
controller they would drive the arms into their limits). It puts every joint on its own hold
(:meth:`icub_sim_bridge.Simulator.hold`: joint PD plus gravity compensation at the posture it
had) when

- lockstep: the answer to a published state did not come within ``lockstep_timeout`` of wall
  time (:meth:`missed_answer`);
- free run: no command came for ``command_timeout`` of wall time (:meth:`check`), once a
  first command has come (before it every joint is on the hold anyway);

and hands the joints back to the commanded torques with the next command (:meth:`resume`).
Wall time, not simulated time: a simulator that waits for its controller does not advance.
"""

from __future__ import annotations

import time
from typing import Callable

__all__ = ["CommandWatchdog"]


class CommandWatchdog:
    """Hold / resume decisions on missing effort commands (module doc).

    Args:
        clock: wall clock [s] (default ``time.monotonic``).
    """

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._clock = clock
        self.last_command: float | None = None  # wall time of the last accepted command [s]
        self.holding = False
        self.reason = ""
        self.holds = 0  # how many times the robot was put on hold

    def command(self) -> None:
        """An effort command was accepted now (any thread)."""
        self.last_command = self._clock()

    def command_age(self) -> float:
        """Wall time since the last accepted command [s] (-1 before the first)."""
        return -1.0 if self.last_command is None else self._clock() - self.last_command

    def restart(self) -> None:
        """The simulation resumes after a pause: the controller could not answer while it
        stood, so the command age starts again from now."""
        if self.last_command is not None:
            self.last_command = self._clock()

    def missed_answer(self, sim_time: float, timeout: float) -> str | None:
        """Lockstep: the state of ``sim_time`` [s] got no answer within ``timeout`` [s] of
        wall time. Returns the reason when this starts a hold (hold the robot and say so),
        None when already holding."""
        if self.last_command is None:
            return self._hold(f"no controller has answered yet: no /effort_command for the "
                              f"state of t = {sim_time:.3f} s within {timeout:g} s "
                              "(lockstep_timeout)")
        return self._hold(f"no /effort_command stamped t = {sim_time:.3f} s within "
                          f"{timeout:g} s (lockstep_timeout)")

    def check(self, timeout: float) -> str | None:
        """Free run: the reason when no command came for ``timeout`` [s] of wall time and
        this starts a hold, else None."""
        if self.holding or self.last_command is None:
            return None
        age = self._clock() - self.last_command
        if age <= timeout:
            return None
        return self._hold(f"no /effort_command for {age:.2f} s of wall time "
                          f"(command_timeout {timeout:g} s)")

    def resume(self) -> bool:
        """A command arrived and was applied: True when this ends a hold (say so)."""
        if not self.holding:
            return False
        self.holding = False
        self.reason = ""
        return True

    def _hold(self, reason: str) -> str | None:
        if self.holding:
            return None
        self.holding = True
        self.reason = reason
        self.holds += 1
        return reason
