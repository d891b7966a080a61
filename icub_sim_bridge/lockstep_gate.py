"""LockstepGate: the simulator's side of the lockstep protocol with the controller.

After publishing the state stamped t, the simulator's next step waits for an effort command
stamped exactly t (the controller's answer to that state), at most ``timeout`` of wall time;
a command with another stamp (an answer to an earlier state) does not release it. Thread-safe:
commands arrive on the executor thread, the physics loop waits.
"""

from __future__ import annotations

import threading

__all__ = ["LockstepGate"]


class LockstepGate:
    """Wait for the answer to the last published state (module doc)."""

    def __init__(self) -> None:
        self._expected_ns = 0
        self._answered = threading.Event()
        self.timeouts = 0

    @property
    def expected_ns(self) -> int:
        """The stamp [ns] of the state waiting for its answer."""
        return self._expected_ns

    def expect(self, stamp_ns: int) -> None:
        """A state stamped ``stamp_ns`` [ns] is about to be published: wait for its answer
        (an answer to an earlier state that arrives late no longer counts)."""
        self._expected_ns = int(stamp_ns)
        self._answered.clear()

    def answer(self, stamp_ns: int) -> bool:
        """A command stamped ``stamp_ns`` [ns] arrived (valid or not: either way the state was
        answered); True when it releases the waiting step."""
        if stamp_ns == self._expected_ns:
            self._answered.set()
            return True
        return False

    def wait(self, timeout: float) -> bool:
        """Wait up to ``timeout`` s (wall) for the answer; False (and counted) on timeout."""
        ok = self._answered.wait(timeout)
        self._answered.clear()
        if not ok:
            self.timeouts += 1
        return ok
