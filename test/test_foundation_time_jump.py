"""TimeJumpDetector: a backward jump of a stream's clock is reported once, with both times,
and the stream goes on from the new time; forward steps, repeats and small reorderings within
the tolerance are not jumps."""

from __future__ import annotations

import pytest

from icub_pmp.errors import InvalidInput
from icub_pmp.time_jump_detector import TimeJump, TimeJumpDetector

MS = 1_000_000


def test_jump_back_reported_once_then_the_new_timeline_goes_on():
    """198.654 s -> 0.001 s is one jump (described with both times); later stamps of the new
    timeline are not jumps although they are older than the old maximum."""
    d = TimeJumpDetector()
    for k in range(3):
        assert d.observe(198_652 * MS + k * MS) is None
    jump = d.observe(1 * MS)
    assert jump == TimeJump(198_654 * MS, 1 * MS)
    assert jump.describe() == "simulated time went back from t = 198.654 s to t = 0.001 s"
    assert [d.observe(k * MS) for k in range(2, 6)] == [None] * 4
    assert d.jumps == 1 and d.newest_ns == 5 * MS


def test_repeats_and_reordering_within_the_tolerance_are_not_jumps():
    """An equal stamp is never a jump; an older one is not while within the tolerance."""
    d = TimeJumpDetector(tolerance_ns=2 * MS)
    assert d.observe(10 * MS) is None
    assert d.observe(10 * MS) is None
    assert d.observe(8 * MS) is None  # 2 ms older: tolerated
    assert d.newest_ns == 10 * MS
    assert d.observe(7 * MS) is not None
    d.reset()
    assert d.observe(1 * MS) is None and d.jumps == 1


def test_negative_tolerance_rejected():
    with pytest.raises(InvalidInput, match="tolerance_ns"):
        TimeJumpDetector(-1)
