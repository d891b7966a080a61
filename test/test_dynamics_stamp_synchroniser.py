"""StampSynchroniser: the wrench estimator's pairing of joint states and FT wrenches by stamp."""

from __future__ import annotations

import pytest

from icub_pmp.dynamics.stamp_synchroniser import StampSynchroniser
from icub_pmp.errors import InvalidInput

MS = 1_000_000  # [ns]


def _sync(buffer: int = 64) -> StampSynchroniser[str]:
    return StampSynchroniser(["left", "right"], buffer)


def test_a_sample_completes_when_all_items_of_its_stamp_arrived_in_any_order():
    s = _sync()
    s.add("right", 1 * MS, "r1")
    assert s.match(1 * MS) is None
    s.add_primary(1 * MS, "js1")
    assert s.match(1 * MS) is None
    s.add("left", 1 * MS, "l1")
    sample = s.match(1 * MS)
    assert sample.stamp_ns == 1 * MS and sample.primary == "js1"
    assert sample.secondary == {"left": "l1", "right": "r1"}
    assert s.match(1 * MS) is None  # consumed


def test_completing_a_sample_drops_every_older_item():
    """Never back in time: after the sample of t = 3 ms, the incomplete 2 ms is gone."""
    s = _sync()
    for t in (2, 3):
        s.add_primary(t * MS, f"js{t}")
        s.add("left", t * MS, f"l{t}")
    s.add("right", 3 * MS, "r3")
    assert s.match(3 * MS).primary == "js3"
    s.add("right", 2 * MS, "r2")  # the late partner of the dropped sample
    assert s.match(2 * MS) is None


def test_buffers_keep_only_the_newest_items():
    s = _sync(buffer=2)
    for t in (1, 2, 3):
        s.add_primary(t * MS, f"js{t}")
        s.add("left", t * MS, f"l{t}")
        s.add("right", t * MS, f"r{t}")
    assert s.match(1 * MS) is None  # pushed out
    assert s.match(2 * MS).primary == "js2"


def test_after_a_jump_back_the_buffers_keep_the_new_stamps():
    """The earliest received go first, not the smallest stamps: items of a restarted clock
    (t = 1, 2 ms after t = 198 s) stay buffered and complete their samples."""
    s = _sync(buffer=2)
    s.add("left", 198_000 * MS, "old")
    s.add("left", 198_001 * MS, "old")
    for t in (1, 2):
        s.add("left", t * MS, f"l{t}")
        s.add("right", t * MS, f"r{t}")
    s.add_primary(2 * MS, "js2")
    assert s.match(2 * MS).secondary == {"left": "l2", "right": "r2"}


def test_latest_pairs_with_the_newest_items_unless_stale():
    s = _sync()
    with pytest.raises(InvalidInput, match="no left item"):
        s.latest(5 * MS, 0.1)
    s.add("left", 1 * MS, "l1")
    s.add("left", 4 * MS, "l4")
    s.add("right", 3 * MS, "r3")
    assert s.latest(5 * MS, 0.1) == {"left": "l4", "right": "r3"}
    with pytest.raises(InvalidInput, match="right is stale"):
        s.latest(104 * MS, 0.1005)  # left: 100 ms old, right: 101 ms


def test_release_refuses_duplicates_and_steps_back_until_reset():
    s = _sync()
    assert s.release(5 * MS)
    assert not s.release(5 * MS) and not s.release(4 * MS)
    assert s.release(6 * MS)
    s.add_primary(7 * MS, "js7")
    s.reset()  # e.g. the clock jumped back
    assert not s.has_primary(7 * MS)
    assert s.release(1 * MS)


def test_bad_arguments_are_named():
    with pytest.raises(InvalidInput, match="keys"):
        StampSynchroniser([])
    with pytest.raises(InvalidInput, match="buffer"):
        StampSynchroniser(["left"], 0)
    with pytest.raises(InvalidInput, match="unknown stream 'head'"):
        _sync().add("head", 1, "x")
