"""CommandWatchdog: the simulator's decision to hold the robot when its controller stops
answering, and to hand it back when commands return (wall time, fake clock)."""

from __future__ import annotations

from icub_sim_bridge.command_watchdog import CommandWatchdog


def test_lockstep_missed_answer_holds_once_and_a_command_resumes(fake_clock):
    """The first missed answer starts a hold and says why; further misses do not repeat it;
    the next applied command ends the hold (once)."""
    w = CommandWatchdog(fake_clock)
    assert "no controller has answered yet" in w.missed_answer(0.0, 0.5)
    w.command()
    assert w.resume()
    reason = w.missed_answer(12.345, 0.5)
    assert w.holding and reason == w.reason
    assert "stamped t = 12.345 s within 0.5 s" in reason and "lockstep_timeout" in reason
    assert w.missed_answer(12.346, 0.5) is None and w.holds == 2
    w.command()
    assert w.resume() and not w.holding and w.reason == ""
    assert not w.resume()


def test_free_run_holds_after_command_timeout_of_wall_time(fake_clock):
    """Free run: nothing before the first command (every joint is held anyway); then a hold
    once no command came for longer than the timeout, and not before."""
    w = CommandWatchdog(fake_clock)
    fake_clock.t += 10.0
    assert w.check(0.5) is None and w.command_age() == -1.0
    w.command()
    fake_clock.t += 0.4
    assert w.check(0.5) is None
    fake_clock.t += 0.2
    reason = w.check(0.5)
    assert reason is not None and "0.60 s of wall time" in reason and w.holding
    assert w.check(0.5) is None  # said once
    assert abs(w.command_age() - 0.6) < 1e-9


def test_restart_after_a_pause_does_not_count_the_pause(fake_clock):
    """A paused simulation gets no commands; resuming starts the command age again."""
    w = CommandWatchdog(fake_clock)
    w.command()
    fake_clock.t += 30.0  # paused
    w.restart()
    fake_clock.t += 0.1
    assert w.check(0.5) is None and not w.holding
