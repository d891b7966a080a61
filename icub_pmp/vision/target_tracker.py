"""TargetTracker: follow the largest motion blob smoothly over time (motionCUT's target).

Sect. 5 of the force-control paper: "the tracker is instructed to follow the largest blob";
small distractor blobs do not interfere. The target centroid is smoothed exponentially; a
largest blob far from the current target must persist a few frames before it takes over, and
the target is held for a few frames after its blob disappears.
"""

from __future__ import annotations

import dataclasses
import math

from icub_pmp.vision.motion_blobs import MotionBlobs
from icub_pmp.vision.motion_segmenter_config import MotionSegmenterConfig

__all__ = ["TargetTracker", "TrackedTarget"]


@dataclasses.dataclass(frozen=True)
class TrackedTarget:
    """The tracked image target after one frame.

    Attributes:
        valid: a target exists (seen now or within the hold time).
        position: smoothed centroid (u, v) [px]; (nan, nan) when not valid.
        size: node count of the blob last associated with the target (0 when not valid).
        missing_frames: frames since the target's blob was last seen (0 = seen now).
        age: frames since the target was acquired.
    """

    valid: bool
    position: tuple[float, float]
    size: int
    missing_frames: int
    age: int


_NONE = TrackedTarget(False, (math.nan, math.nan), 0, 0, 0)


class TargetTracker:
    """Smoothly follow the largest blob (parameters from :class:`MotionSegmenterConfig`)."""

    def __init__(self, config: MotionSegmenterConfig | None = None):
        self.config = config or MotionSegmenterConfig()
        self.reset()

    def reset(self) -> None:
        """Drop the target."""
        self._target = _NONE
        self._candidate: tuple[float, float] | None = None
        self._candidate_frames = 0

    @property
    def target(self) -> TrackedTarget:
        """The current target."""
        return self._target

    def update(self, blobs: MotionBlobs) -> TrackedTarget:
        """Associate this frame's largest blob with the target and return the new target."""
        c = self.config
        t = self._target
        if not blobs.has_motion:
            self._candidate, self._candidate_frames = None, 0
            if t.valid and t.missing_frames < c.target_hold_frames:
                self._target = dataclasses.replace(
                    t, missing_frames=t.missing_frames + 1, age=t.age + 1
                )
            else:
                self._target = _NONE
            return self._target
        blob = blobs.largest
        u, v = blob.centroid
        if not t.valid:
            self._target = TrackedTarget(True, (u, v), blob.size, 0, 0)
            return self._target
        du, dv = u - t.position[0], v - t.position[1]
        if math.hypot(du, dv) <= c.target_max_jump:
            a = c.target_alpha
            pos = (t.position[0] + a * du, t.position[1] + a * dv)
            self._candidate, self._candidate_frames = None, 0
            self._target = TrackedTarget(True, pos, blob.size, 0, t.age + 1)
            return self._target
        # a distant largest blob: switch only if it persists near the same place
        if self._candidate is not None and math.hypot(
            u - self._candidate[0], v - self._candidate[1]
        ) <= c.target_max_jump:
            self._candidate_frames += 1
        else:
            self._candidate_frames = 1
        self._candidate = (u, v)
        if self._candidate_frames >= c.target_switch_frames:
            self._candidate, self._candidate_frames = None, 0
            self._target = TrackedTarget(True, (u, v), blob.size, 0, 0)
        elif t.missing_frames < c.target_hold_frames:
            self._target = dataclasses.replace(
                t, missing_frames=t.missing_frames + 1, age=t.age + 1
            )
        else:
            self._target = _NONE
        return self._target
