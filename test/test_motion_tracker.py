"""TargetTracker: the largest blob is the target, followed smoothly over time."""

from __future__ import annotations

import numpy as np

from icub_pmp.baselines import SyntheticSequence, textured_image
from icub_pmp.vision import (
    MotionBlob,
    MotionBlobs,
    MotionSegmenter,
    MotionSegmenterConfig,
    TargetTracker,
)


def _blobs(*centroids_sizes: tuple[float, float, int]) -> MotionBlobs:
    blobs = tuple(
        MotionBlob(centroid=(u, v), size=n, area=36 * n, bbox=(0, 0, 1, 1), mean_flow=(0.0, 0.0))
        for u, v, n in sorted(centroids_sizes, key=lambda b: -b[2])
    )
    z = np.zeros((2, 2))
    return MotionBlobs(0, blobs, np.zeros((240, 320), np.uint8), z > 0, z > 0,
                       np.zeros((2, 2, 2)), z)


def test_target_follows_largest_moving_object_not_distractor():
    """A 70 px patch crossing the image at 3 px/frame and a 30 px distractor moving at
    5 px/frame: the target stays within 8 px of the large patch in every frame."""
    seq = SyntheticSequence(patch_size=70, patch_velocity=(90.0, 0.0), patch_start=(-60, -25))
    small = textured_image(30, 30, 5)
    seg, tr = MotionSegmenter(), TargetTracker()
    errors = []
    for k in range(25):
        f = seq.frame(k)
        img = f.image.copy()
        x, y = 60 + 5 * k, 172
        img[y : y + 30, x : x + 30] = small[:, :, None]
        t = tr.update(seg.process(img))
        if k >= 2:
            assert t.valid
            errors.append(np.hypot(t.position[0] - f.object_center[0],
                                   t.position[1] - f.object_center[1]))
    assert max(errors) < 8.0, errors


def test_target_is_smoothed():
    """Each update moves the target by target_alpha of the way to the new centroid."""
    tr = TargetTracker(MotionSegmenterConfig(target_alpha=0.5))
    tr.update(_blobs((100.0, 100.0, 20)))
    t = tr.update(_blobs((110.0, 100.0, 20)))
    assert t.position == (105.0, 100.0) and t.age == 1 and t.missing_frames == 0


def test_target_held_then_dropped():
    """Without blobs the target is held target_hold_frames frames, then invalid."""
    tr = TargetTracker(MotionSegmenterConfig(target_hold_frames=3))
    tr.update(_blobs((50.0, 60.0, 15)))
    states = [tr.update(_blobs()) for _ in range(5)]
    assert [s.valid for s in states] == [True, True, True, False, False]
    assert states[2].missing_frames == 3 and states[2].position == (50.0, 60.0)
    assert np.isnan(states[3].position[0])


def test_distant_blob_needs_persistence_to_take_over():
    """A new largest blob far from the target takes over only after target_switch_frames
    consecutive frames near the same place; a one-frame jump is ignored."""
    tr = TargetTracker(MotionSegmenterConfig(target_switch_frames=3, target_max_jump=30.0))
    tr.update(_blobs((50.0, 50.0, 20)))
    t = tr.update(_blobs((200.0, 50.0, 40), (52.0, 50.0, 12)))
    assert t.position == (50.0, 50.0) and t.missing_frames == 1
    t = tr.update(_blobs((51.0, 50.0, 20)))
    assert t.position[0] == 50.5
    for _ in range(2):
        t = tr.update(_blobs((200.0, 50.0, 40)))
        assert t.position[0] == 50.5
    t = tr.update(_blobs((201.0, 50.0, 40)))
    assert t.position == (201.0, 50.0) and t.age == 0
