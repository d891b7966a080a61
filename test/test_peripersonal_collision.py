"""The imagined collision check of two arm reaches (Bhat and Mohan 2018, "Coupled interaction
between internal models") on the iCub URDF, and its geometry (segments, capsules)."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.peripersonal import (
    CollisionCheckConfig,
    ImaginedCollisionCheck,
    LinkHull,
    fit_capsule,
    fit_capsules,
    segment_distance,
)
from icub_pmp.peripersonal.segment_distance import segment_distance as _sd

CROSSING = {"left": [-0.28, 0.05, 0.05], "right": [-0.28, -0.05, 0.05]}  # hands swap sides
MIRRORED = {"left": [-0.28, -0.15, 0.05], "right": [-0.28, 0.15, 0.05]}  # each on its side


def brute_segment_distance(p0, p1, q0, q1, n=801):
    s = np.linspace(0, 1, n)[:, None]
    P, Q = p0 + s * (p1 - p0), q0 + s * (q1 - q0)
    return np.min(np.linalg.norm(P[:, None] - Q[None], axis=2))


def test_segment_distance_matches_brute_force():
    """Closest distance of two segments (general, parallel, point-like) equals a dense
    search, also broadcast over a batch."""
    rng = np.random.default_rng(0)
    cases = []
    for k in range(60):
        p0, p1, q0, q1 = rng.normal(size=(4, 3))
        if k % 5 == 0:
            p1 = p0.copy()
        if k % 7 == 0:
            q1 = q0.copy()
        if k % 11 == 0:
            q1 = q0 + 2.0 * (p1 - p0)
        cases.append((p0, p1, q0, q1))
        d = segment_distance(p0, p1, q0, q1)
        assert d == pytest.approx(brute_segment_distance(p0, p1, q0, q1), abs=5e-3)
        assert d <= brute_segment_distance(p0, p1, q0, q1) + 1e-12
    batch = np.array(cases)
    np.testing.assert_allclose(_sd(batch[:, 0], batch[:, 1], batch[:, 2], batch[:, 3]),
                               [segment_distance(*c) for c in cases])


def test_capsules_bound_the_points():
    """A fitted capsule contains every point; splitting a flat plate into slabs gives
    smaller total volume than one capsule, and still contains every point."""
    rng = np.random.default_rng(1)
    stick = rng.normal(size=(300, 3)) * [0.08, 0.01, 0.01]
    c = fit_capsule("stick", stick)
    assert np.all(segment_distance(c.a, c.b, stick, stick) <= c.radius + 1e-12)
    assert np.linalg.norm(c.b - c.a) > 0.1 and c.radius < 0.05
    plate = rng.uniform([-0.08, -0.06, -0.01], [0.08, 0.06, 0.01], size=(2000, 3))
    caps = fit_capsules("plate", plate, max_pieces=4)
    assert len(caps) > 1
    assert sum(k.volume for k in caps) < fit_capsule("plate", plate).volume
    inside = np.zeros(len(plate), dtype=bool)
    for k in caps:
        inside |= segment_distance(k.a, k.b, plate, plate) <= k.radius + 1e-12
    assert inside.all()


def _box(half: tuple[float, float, float]) -> np.ndarray:
    return np.array([[sx * half[0], sy * half[1], sz * half[2]] for sx in (-1, 1)
                     for sy in (-1, 1) for sz in (-1, 1)])


def _rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_link_hull_distance_of_two_boxes():
    """Two boxes of half size 5 x 3 x 2 cm, the second 14 cm further along x and turned
    about z: the sampled hull distance equals the true gap (face to face: 4 cm; turned by
    90 deg: 14 - 5 - 3 = 6 cm) within the sampling spacing, and a bound below it gives inf."""
    a = LinkHull("a", _box((0.05, 0.03, 0.02)), spacing=0.005)
    b = LinkHull("b", _box((0.05, 0.03, 0.02)), spacing=0.005)
    eye, p0, p1 = np.eye(3), np.zeros(3), np.array([0.14, 0.0, 0.0])
    assert a.distance(eye, p0, b, eye, p1) == pytest.approx(0.04, abs=0.003)
    assert a.distance(eye, p0, b, _rot_z(np.pi / 2), p1) == pytest.approx(0.06, abs=0.003)
    assert a.distance(_rot_z(0.3), p0, b, eye, p0) < 0.003  # overlapping: surfaces cross
    assert a.distance(eye, p0, b, eye, p1, bound=0.03) == np.inf
    assert len(a.points) > 8 and np.abs(a.points).max(axis=0) == pytest.approx(
        [0.05, 0.03, 0.02])


@pytest.fixture(scope="module")
def check():
    return ImaginedCollisionCheck()


def test_capsules_cover_the_arm_links(check):
    """Every link that collides in the simulator has a hull and capsules in both arms, of
    about the same total volume on both sides (the arms are mirror images), and the capsules
    contain their hull."""
    volume = {}
    for arm, p in (("left", "l_"), ("right", "r_")):
        names = set(check.body.capsule_names(arm))
        assert names == {p + n for n in check.config.capsule_links}
        assert check.body.link_names(arm) == tuple(p + n for n in check.config.capsule_links)
        for i, hull in enumerate(check.body.hulls[arm]):
            inside = np.zeros(len(hull.points), dtype=bool)
            for c in np.flatnonzero(check.body.capsule_links(arm) == i):
                cap = check.body.capsules[arm][c]
                inside |= segment_distance(cap.a, cap.b, hull.points, hull.points) <= \
                    cap.radius + 1e-9
            assert inside.all(), hull.frame
        assert np.all(check.body.radii(arm) > 0.01) and np.all(check.body.radii(arm) < 0.08)
        volume[arm] = sum(c.volume for c in check.body.capsules[arm])
    assert volume["left"] == pytest.approx(volume["right"], rel=0.15)


def test_crossing_reaches_collide_and_are_serialised(check):
    """Each hand reaching across to the other side: the imagined motions meet (distal test
    and capsules), mid-way rather than at the start; the plan is serialised and every step
    of the serial schedule is imagined clear (the waiting arm out of the way)."""
    pair = check.plan_pair(CROSSING)
    v = pair.verdict
    assert v.collides and v.distal_hit and v.body_hit
    assert v.min_clearance < check.config.margin
    assert 0.0 < v.time_of_closest_approach <= check.config.reach_tau
    assert all(p.success for p in pair.plans.values())
    s = pair.schedule
    assert s.mode == "serial" and s.safe
    reaches = [st for st in s.steps if st.action == "reach"]
    assert [st.arm for st in reaches] == ["left", "right"]
    assert reaches[1].start >= reaches[0].end  # one after the other
    assert s.duration == pytest.approx(s.steps[-1].end)
    for st in s.steps:
        assert not st.clearance.collides
        assert st.positions.shape == (len(st.t), 7) and st.joint_names[0].startswith(st.arm[0])
    # the waiting arm went to the safe posture before the other one crossed its space
    parks = [st for st in s.steps if st.action == "park"]
    assert parks and parks[0].end <= reaches[1].start
    np.testing.assert_allclose(parks[0].positions[-1], check.safe_posture(parks[0].arm))


def test_mirrored_reaches_run_in_parallel(check):
    """Each hand on its own side: no collision, both reaches start together."""
    pair = check.plan_pair(MIRRORED)
    v = pair.verdict
    assert not v.collides and not v.distal_hit and not v.body_hit
    assert v.min_clearance > 0.05 and v.min_distal_distance > 0.2
    s = pair.schedule
    assert s.mode == "parallel" and s.safe and len(s.steps) == 2
    assert all(st.start == 0.0 and st.action == "reach" for st in s.steps)
    assert s.duration == pytest.approx(check.config.reach_tau)


def test_serial_order_follows_first(check):
    """The arm named first reaches first when the pair must be serialised."""
    s = check.plan_pair(CROSSING, first="right").schedule
    assert [st.arm for st in s.steps if st.action == "reach"] == ["right", "left"]


def test_threshold_decides(check):
    """The verdict follows the thresholds: with the body test off and a distal threshold of
    0, even crossing reaches are 'clear'; a huge distal threshold flags mirrored ones."""
    loose = ImaginedCollisionCheck(CollisionCheckConfig(distal_threshold=0.0, body_check=False),
                                   check.planner, check.body)
    assert not loose.plan_pair(CROSSING).verdict.collides
    strict = ImaginedCollisionCheck(CollisionCheckConfig(distal_threshold=0.5), check.planner,
                                    check.body)
    v = strict.plan_pair(MIRRORED).verdict
    assert v.collides and v.distal_hit and not v.body_hit


def test_bad_pairs_are_refused(check):
    """Missing arm, unknown arm, NaN target, unknown first arm: clear errors."""
    with pytest.raises(InvalidInput, match=r"missing \['right'\]"):
        check.plan_pair({"left": [-0.3, 0.0, 0.0]})
    with pytest.raises(UnknownName, match="unknown arm 'middle'"):
        check.plan_pair({**CROSSING, "middle": [0.0, 0.0, 0.0]})
    with pytest.raises(InvalidInput, match=r"targets\['left'\]"):
        check.plan_pair({"left": [np.nan, 0.0, 0.0], "right": [-0.3, 0.1, 0.0]})
    with pytest.raises(UnknownName, match="arm 'up'"):
        check.plan_pair(CROSSING, first="up")
    with pytest.raises(UnknownName, match="posture"):
        ImaginedCollisionCheck(CollisionCheckConfig(safe_posture="nowhere"), check.planner,
                               check.body)
