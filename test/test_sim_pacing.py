"""The simulator's pacing (StepPacer) and lockstep protocol (LockstepGate), without ROS."""

from __future__ import annotations

import threading

import pytest

from icub_pmp.errors import InvalidInput
from icub_sim_bridge.lockstep_gate import LockstepGate
from icub_sim_bridge.step_pacer import StepPacer


def test_pacer_keeps_sim_time_at_the_real_time_factor(fake_clock):
    """At factor 0.5, 10 ms of simulated time take 20 ms of wall time: after a step done
    instantly the pacer asks to wait the rest (minus the early wake-up)."""
    clock = fake_clock
    pacer = StepPacer(clock)
    assert pacer.wait_time(0.0, 0.5) == 0.0  # first call anchors
    assert pacer.wait_time(0.010, 0.5) == pytest.approx(0.020 - 0.001)
    clock.t += 0.015
    assert pacer.wait_time(0.010, 0.5) == pytest.approx(0.005 - 0.001)
    clock.t += 0.0195  # now ahead by less than min_wait: no wait
    assert pacer.wait_time(0.0175, 0.5) == 0.0


def test_pacer_never_waits_as_fast_as_possible_and_reanchors_on_a_new_factor(fake_clock):
    clock = fake_clock
    pacer = StepPacer(clock)
    assert pacer.wait_time(5.0, 0.0) == 0.0
    pacer.wait_time(5.0, 1.0)
    n = pacer.restarts
    assert pacer.wait_time(5.0, 2.0) == 0.0 and pacer.restarts == n + 1
    assert pacer.wait_time(5.1, 2.0) == pytest.approx(0.05 - 0.001)


def test_pacer_does_not_catch_up_after_a_stall(fake_clock):
    """Far behind (the machine stalled 1 s), the pacer re-anchors: the next steps are paced
    from there, not run unpaced until the lost second is made up."""
    clock = fake_clock
    pacer = StepPacer(clock)
    pacer.wait_time(0.0, 1.0)
    clock.t += 1.0
    assert pacer.wait_time(0.001, 1.0) == 0.0  # 0.999 s behind: re-anchored
    assert pacer.wait_time(0.011, 1.0) == pytest.approx(0.010 - 0.001)


def test_pacer_rejects_negative_settings():
    with pytest.raises(InvalidInput, match="max_lag"):
        StepPacer(max_lag=-1.0)


def test_gate_is_released_only_by_the_answer_to_the_expected_state():
    gate = LockstepGate()
    gate.expect(2_000_000)
    assert not gate.answer(1_000_000)  # a late answer to the previous state
    assert not gate.wait(0.01) and gate.timeouts == 1
    assert gate.answer(2_000_000)
    assert gate.wait(0.0) and gate.timeouts == 1


def test_gate_forgets_an_answer_that_came_after_its_timeout():
    """The answer to t arriving after the step gave up on it must not release the wait for
    the next state t + 1 ms."""
    gate = LockstepGate()
    gate.expect(1_000_000)
    assert not gate.wait(0.0)
    gate.answer(1_000_000)  # late, while the loop steps on
    gate.expect(2_000_000)
    assert not gate.wait(0.0)


def test_gate_wait_returns_when_another_thread_answers():
    gate = LockstepGate()
    gate.expect(5)
    timer = threading.Timer(0.05, gate.answer, args=(5,))
    timer.start()
    try:
        assert gate.wait(10.0)
    finally:
        timer.cancel()
    assert gate.expected_ns == 5
