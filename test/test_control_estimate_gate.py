"""EstimateGate: the impedance controller's lockstep wait for the joint-torque estimate."""

from __future__ import annotations

from icub_pmp.control import EstimateGate

MS = 1_000_000  # [ns]


def test_a_joint_state_with_its_estimate_there_goes_at_once():
    gate = EstimateGate()
    assert gate.estimate(5 * MS) is None  # nothing held
    assert gate.offer(5 * MS, "js5") == "js5"
    assert gate.offer(4 * MS, "js4") == "js4"  # a newer estimate answers an older state
    assert not gate.holding


def test_a_joint_state_waits_for_the_estimate_of_its_stamp():
    gate = EstimateGate()
    gate.estimate(1 * MS)
    assert gate.offer(2 * MS, "js2") is None and gate.holding
    assert gate.estimate(1 * MS) is None  # an older estimate does not release it
    assert gate.estimate(2 * MS) == "js2"
    assert not gate.holding and gate.estimate(3 * MS) is None


def test_the_newest_joint_state_replaces_a_held_one():
    gate = EstimateGate()
    gate.offer(1 * MS, "js1")
    gate.offer(2 * MS, "js2")
    assert gate.estimate(3 * MS) == "js2"


def test_a_held_joint_state_is_released_after_the_wall_time_timeout(fake_clock):
    """Simulated time stands still while the simulator waits: only wall time can release."""
    gate = EstimateGate(fake_clock)
    gate.offer(7 * MS, "js7")
    fake_clock.t += 0.05
    assert gate.expired(0.1) is None and gate.holding
    fake_clock.t += 0.06
    assert gate.expired(0.1) == "js7"
    assert not gate.holding and gate.expired(0.1) is None


def test_after_reset_a_joint_state_waits_for_its_own_estimate_again():
    """The clock went back (a restarted simulator): the old newest estimate (198 s) no longer
    answers the new joint states, which wait for the estimates of their own stamps."""
    gate = EstimateGate()
    gate.estimate(198_000 * MS)
    assert gate.offer(1 * MS, "js1") == "js1"  # without reset: passed at once, unanswered
    gate.reset()
    assert gate.offer(2 * MS, "js2") is None and gate.holding
    assert gate.estimate(2 * MS) == "js2"
