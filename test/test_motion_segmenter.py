"""MotionSegmenter: the eq. 13 LK-failure test, filters, blobs, bad input.

Synthetic images (no simulator): a textured canvas seen through a rotating pinhole camera
(homographies) with a textured patch moving on it.
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from icub_pmp.baselines import SyntheticSequence, textured_image
from icub_pmp.config import config_dir
from icub_pmp.errors import ConfigError, InvalidInput
from icub_pmp.vision import MotionSegmenter, MotionSegmenterConfig


def _run(seq: SyntheticSequence, n: int, config: MotionSegmenterConfig | None = None):
    seg = MotionSegmenter(config)
    out = []
    for k in range(n):
        f = seq.frame(k)
        out.append((f, seg.process(f.image)))
    return seg, out


def test_translating_patch_is_found():
    """A textured patch translating at 4 px/frame over a textured background (still camera)
    gives one blob per frame whose centroid is within 6 px of the patch centre, and a mask
    that covers most of the patch."""
    seq = SyntheticSequence(patch_size=60, patch_velocity=(120.0, 0.0), patch_start=(-40, 0))
    _, out = _run(seq, 20)
    for f, r in out[2:]:
        assert r.has_motion
        assert len(r.blobs) == 1
        err = np.hypot(*(np.array(r.largest.centroid) - f.object_center))
        assert err < 6.0, (r.frame_index, err)
        m = r.mask > 0
        assert (m & f.mask).sum() > 0.7 * f.mask.sum()
        assert (m & ~f.mask).sum() < 0.6 * f.mask.sum()


def test_rotating_patch_is_found():
    """A patch spinning in place (120 deg/s, no translation) is found: local rotation makes
    LK fail (Sect. 5, 'Rotations')."""
    seq = SyntheticSequence(patch_size=70, patch_spin=120.0)
    _, out = _run(seq, 12)
    for f, r in out[2:]:
        assert r.has_motion
        assert np.hypot(*(np.array(r.largest.centroid) - f.object_center)) < 4.0


def test_patch_found_while_camera_rotates():
    """With the camera panning at 20 deg/s, a patch moving at 3 px/frame is still found near
    its centre in every frame (the pyramid absorbs the ego-motion)."""
    seq = SyntheticSequence(
        yaw_rate=20.0, patch_size=60, patch_velocity=(0.0, 90.0), patch_start=(0, -40)
    )
    _, out = _run(seq, 20)
    for f, r in out[1:]:
        assert r.has_motion
        assert np.hypot(*(np.array(r.largest.centroid) - f.object_center)) < 10.0


@pytest.mark.parametrize("yaw,pitch", [(40.0, 0.0), (40.0, 20.0), (0.0, 40.0)])
def test_static_scene_with_camera_rotation_gives_no_blob(yaw, pitch):
    """A static textured scene seen by a camera rotating at up to 40 deg/s (pure rotation,
    sensor noise 1 grey level) never produces a blob."""
    seq = SyntheticSequence(yaw_rate=yaw, pitch_rate=pitch)
    _, out = _run(seq, 30)
    assert not any(r.has_motion for _, r in out)
    assert max(int(r.failures.sum()) for _, r in out) < 10


def test_first_frame_has_no_motion_and_fixed_grid():
    """The first frame has no flow and no blob; the grid is motionCUT's 41 x 31 nodes with
    6 px spacing over the central 75 % of a 320x240 image."""
    seg = MotionSegmenter()
    r = seg.process(textured_image(240, 320, 0))
    assert r.frame_index == 0 and not r.has_motion
    assert seg.grid_shape == (31, 41)
    assert seg.nodes.shape == (31 * 41, 2)
    assert tuple(seg.nodes[0]) == (40.0, 30.0) and tuple(seg.nodes[-1]) == (280.0, 210.0)
    with pytest.raises(IndexError):
        _ = r.largest


def test_discrepancy_is_eq13():
    """``discrepancy`` equals sum_q (I_t(p+q) - I_t+1(p+v+q))^2 / |W| computed directly, is 0
    for the true integer flow of a shifted image and large for a wrong one."""
    img = textured_image(240, 320, 3)
    shifted = np.roll(img, (2, 3), axis=(0, 1))  # content moves by v = (+3, +2)
    seg = MotionSegmenter()
    seg.process(img)
    n = seg.nodes.shape[0]
    v_true = np.tile(np.array([3.0, 2.0], np.float32), (n, 1))
    assert np.abs(seg.discrepancy(shifted, v_true)).max() == 0.0
    rng = np.random.default_rng(0)
    v = rng.integers(-4, 5, size=(n, 2)).astype(np.float32)
    got = seg.discrepancy(shifted, v)
    h = seg.config.win_size // 2
    for i in rng.choice(n, 20, replace=False):
        x, y = seg.nodes[i].astype(int)
        a = img[y - h : y + h + 1, x - h : x + h + 1].astype(float)
        dx, dy = v[i].astype(int)
        b = shifted[y + dy - h : y + dy + h + 1, x + dx - h : x + dx + h + 1].astype(float)
        assert got[i] == pytest.approx(((a - b) ** 2).sum() / (2 * h + 1) ** 2, rel=1e-5)
    wrong = seg.discrepancy(shifted, np.zeros((n, 2), np.float32))
    assert np.median(wrong) > 10 * seg.config.theta_m


def test_isolated_failures_are_filtered_and_persistence_holds():
    """A single failing node is dropped by the neighbour filter; a 5x5 failure block is kept
    and stays ON for exactly frames_persistence frames after it stops failing."""
    seg = MotionSegmenter(MotionSegmenterConfig(grow_by_flow=False, blob_min_size=0))
    rows, cols = seg.grid_shape
    lone = np.zeros((rows, cols), bool)
    lone[5, 5] = True
    assert not seg._neighbour_filter(lone).any()
    block = np.zeros((rows, cols), bool)
    block[10:15, 10:15] = True
    kept = seg._neighbour_filter(block)
    assert kept[11:14, 11:14].all() and kept[10:15, 10:15].sum() >= 21
    p = seg.config.frames_persistence
    ttl = np.zeros((rows, cols), np.int32)
    on = []
    for k in range(p + 2):
        k_nodes = kept if k == 0 else np.zeros_like(kept)
        ttl = np.where(k_nodes, p, np.maximum(ttl - 1, 0))
        on.append(bool((ttl > 0)[12, 12]))
    assert on == [True] * p + [False] * 2


def test_blobs_sorted_by_size_with_stats():
    """Two patches of different sizes give two blobs, the larger first, with bbox containing
    the centroid and area = size * grid_step^2."""
    big = SyntheticSequence(patch_size=70, patch_velocity=(90.0, 0.0), patch_start=(-60, 0))
    frames = [big.frame(k) for k in range(6)]
    small_tex = textured_image(36, 36, 99)
    seg = MotionSegmenter()
    r = None
    for k, f in enumerate(frames):
        img = f.image.copy()
        x = 230 + 4 * k
        img[150:186, x : x + 36] = small_tex[:, :, None]
        r = seg.process(img)
    assert len(r.blobs) == 2
    assert r.blobs[0].size > r.blobs[1].size
    for b in r.blobs:
        u0, v0, u1, v1 = b.bbox
        assert u0 <= b.centroid[0] <= u1 and v0 <= b.centroid[1] <= v1
        assert b.area == b.size * 36
    assert r.blobs[1].centroid[0] > 200


@pytest.mark.parametrize(
    "bad,match",
    [
        (np.zeros((240, 320), np.float32), "dtype uint8"),
        (np.zeros((120, 160, 3), np.uint8), "expected 320x240"),
        (np.zeros((240, 320, 4), np.uint8), "shape"),
        ([[0, 1], [2, 3]], "numpy array"),
    ],
)
def test_bad_images_are_rejected_and_state_kept(bad, match):
    """Wrong dtype, size, channels or type raise InvalidInput naming the problem; the
    segmenter's state is unchanged (the next good frame is frame 1)."""
    seg = MotionSegmenter()
    seg.process(textured_image(240, 320, 0))
    with pytest.raises(InvalidInput, match=match):
        seg.process(bad)
    r = seg.process(textured_image(240, 320, 0))
    assert r.frame_index == 1 and not r.has_motion


def test_results_are_read_only():
    """MotionBlobs arrays are read-only copies."""
    seg = MotionSegmenter()
    r = seg.process(textured_image(240, 320, 0))
    with pytest.raises(ValueError):
        r.mask[0, 0] = 1


def test_shipped_values_are_motioncuts():
    """config/motion_segmenter.yaml holds motionCUT's grid,
    neighbour, persistence and blob-size defaults, the 11 px window and 3 pyramid levels."""
    c = MotionSegmenterConfig.from_yaml(config_dir() / "motion_segmenter.yaml", "motion_segmenter")
    assert (c.grid_step, c.win_size, c.pyramid_levels) == (6, 11, 3)
    assert (c.adj_nodes_thres, c.frames_persistence, c.blob_min_size) == (4, 3, 10)
    assert c == MotionSegmenterConfig()


@pytest.mark.parametrize(
    "field,value",
    [
        ("win_size", 14),
        ("grid_step", 0),
        ("theta_m", 0.0),
        ("adj_nodes_thres", 9),
        ("frames_persistence", 0),
        ("cover_x_ratio", 1.5),
        ("target_alpha", 0.0),
        ("flow_tol", -1.0),
        ("accum_decay", 1.0),
        ("accum_clip", 0.0),
        ("accum_tol", -1.0),
        ("loom_tol", 0.0),
        ("refine_window", 4),
        ("refine_match", 0.0),
    ],
)
def test_config_rejects_out_of_range(field, value):
    """Each out-of-range parameter raises ConfigError naming the field."""
    with pytest.raises(ConfigError, match=field):
        dataclasses.replace(MotionSegmenterConfig(), **{field: value})


def test_config_rejects_windows_outside_image():
    """A grid whose windows leave the image (full cover) is rejected."""
    with pytest.raises(ConfigError, match="leave the"):
        MotionSegmenterConfig(cover_x_ratio=1.0)


def test_grey_and_rgb_inputs_agree():
    """An RGB frame and its grey conversion give the same result."""
    seq = SyntheticSequence(patch_size=60, patch_velocity=(120.0, 0.0))
    a, b = MotionSegmenter(), MotionSegmenter()
    for k in range(4):
        img = seq.frame(k).image
        ra = a.process(img)
        rb = b.process(cv2.cvtColor(img, cv2.COLOR_RGB2GRAY))
    assert np.array_equal(ra.mask, rb.mask)
