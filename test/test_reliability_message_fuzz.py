"""The message fuzzer's strategies (icub_pmp.testing.message_fuzz), checked without DDS: they
are derived from the types, cover every field, and draw the bad cases issue 22 lists."""

from __future__ import annotations

import math

from hypothesis import given
from sensor_msgs.msg import Image, JointState
from trajectory_msgs.msg import JointTrajectory

from icub_interfaces.action import FollowJointTrajectory
from icub_interfaces.srv import Reach
from icub_pmp.testing.interface_fuzzer import fuzz_settings
from icub_pmp.testing.message_fuzz import (
    FuzzVocabulary,
    goal_strategy,
    message_strategy,
    out_of_order_stamps,
    request_strategy,
)

VOCAB = FuzzVocabulary.icub()
#: draws per claim (derandomised: the same draws on every run). A Reach request or a
#: FollowJointTrajectory goal costs about 50 ms to draw; every field of both already varies
#: within 5 draws, trajectories show both bad cases within 5, so 20 and 30 keep a margin of 4x
#: and more. JointStates need about 100 draws before both far stamps turn up: they keep 150.
#: (bench/reliability.py draws the DDS cases at full scale.)
N_GOALS = 20
N_TRAJECTORIES = 30


def _draw(strategy, n: int = 150) -> list:
    out: list = []

    @fuzz_settings(n)
    @given(strategy)
    def collect(m) -> None:
        out.append(m)

    collect()
    return out


def test_joint_states_cover_the_bad_cases():
    """Drawn JointStates hold NaN and inf, wrong-length and empty arrays, unknown and
    duplicated names, and also well-formed messages (lengths equal to the names)."""
    msgs = _draw(message_strategy(JointState, VOCAB))
    floats = [x for m in msgs for x in m.position]
    assert any(math.isnan(x) for x in floats) and any(math.isinf(x) for x in floats)
    assert any(len(m.position) != len(m.name) for m in msgs)
    assert any(len(m.position) == 0 and m.name for m in msgs)
    known = set(VOCAB.joint_names)
    assert any(set(m.name) - known for m in msgs)
    assert any(len(set(m.name)) < len(m.name) for m in msgs)
    assert any(m.name and set(m.name) <= known and len(m.position) == len(m.name)
               and all(math.isfinite(x) for x in m.position) for m in msgs)
    stamps = {m.header.stamp.sec for m in msgs}
    assert 2**31 - 1 in stamps and -1 in stamps  # the far future, before the epoch


def test_requests_and_goals_are_derived_from_the_types():
    """A service request and an action goal: every field of the type varies over the draws
    (a field added to the interface is fuzzed without a change here)."""
    for strategy, cls in ((request_strategy(Reach, VOCAB), Reach.Request),
                          (goal_strategy(FollowJointTrajectory, VOCAB),
                           FollowJointTrajectory.Goal)):
        msgs = _draw(strategy, N_GOALS)
        assert all(isinstance(m, cls) for m in msgs)
        for field in cls.get_fields_and_field_types():
            assert len({repr(getattr(m, field)) for m in msgs}) > 1, f"{cls.__name__}.{field}"


def test_trajectories_have_negative_durations_and_mismatched_points():
    """JointTrajectory points: negative times from start, and points whose position count
    differs from the joint names."""
    msgs = _draw(message_strategy(JointTrajectory, VOCAB), N_TRAJECTORIES)
    pts = [(m, p) for m in msgs for p in m.points]
    assert any(p.time_from_start.sec < 0 for _, p in pts)
    assert any(len(p.positions) != len(m.joint_names) for m, p in pts)


def test_images_with_inconsistent_sizes():
    """Images whose data does not match step x height, and ones whose data does."""
    msgs = _draw(message_strategy(Image, VOCAB))
    assert any(len(m.data) != m.step * m.height for m in msgs)
    assert any(len(m.data) == m.step * m.height > 0 for m in msgs)


def test_out_of_order_stamps():
    """The stamps are a permutation of the sorted ones except one repeat, not increasing."""
    ts = out_of_order_stamps(6, 10.0, 0.001)
    assert any(b < a for a, b in zip(ts, ts[1:]))
    assert ts[-1] == ts[0]


def test_fuzz_tally_totals_problems_and_reasons():
    """The tally sums per interface, lists only the interfaces with a crash, hang or unclear
    rejection, and groups rejection messages that differ only in their numbers."""
    from icub_pmp.testing.fuzz_tally import FuzzTally

    tally = FuzzTally()
    a = tally.get("/a", "service", "node_a")
    a.cases = 5
    a.reject("tau: expected a finite duration >= 0 s, got -1.0")
    a.reject("tau: expected a finite duration >= 0 s, got -2.0")
    b = tally.get("/b", "topic", "node_b")
    b.cases, b.hangs = 3, 1
    b.note("no answer")
    assert tally.total("cases") == 8 and tally.total("rejected") == 2
    assert [p.split(" ")[0] for p in tally.problems()] == ["/b"]
    assert a.reasons.most_common(1)[0][1] == 2
    assert "/a" in tally.table() and "/b" in tally.table()
