"""CollisionVerdict: what the imagined collision check found for two arm motions."""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["CollisionVerdict"]


class CollisionVerdict(NamedTuple):
    """Result of comparing the two arms along their (imagined) motions.

    Attributes:
        collides: a collision is predicted (distal or body test).
        distal_hit: the paper's test: a wrist/hand point of one arm came within
            ``distal_threshold`` of one of the other arm.
        body_hit: a link hull of one arm came within ``margin`` of one of the other arm.
        min_distal_distance: smallest wrist/hand point distance [m].
        min_clearance: smallest distance between the two arms' link hulls [m] (to the
            hull sampling; when larger than ``margin + broad_phase``, a lower bound from the
            capsules, which can be negative); +inf without the body test.
        time_of_closest_approach: when ``min_clearance`` (or, without the body test,
            ``min_distal_distance``) occurred [s] from the start of the motions.
        closest_links: the two links (left, right) at the closest approach (the distal frames
            without the body test).
    """

    collides: bool
    distal_hit: bool
    body_hit: bool
    min_distal_distance: float
    min_clearance: float
    time_of_closest_approach: float
    closest_links: tuple[str, str]
