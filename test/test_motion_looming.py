"""Looming detector (an addition to motionCUT): accumulated ego-motion residuals whose
components expand or contract mark objects approaching or receding; uniform drifts (motion
parallax) do not. Synthetic images: a textured canvas seen by a rotating camera, a textured
patch growing in place (an object approaching along the optical axis)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from icub_pmp.baselines import SyntheticSequence
from icub_pmp.vision import LoomingDetector, MotionSegmenter, MotionSegmenterConfig
from icub_pmp.vision.looming_detector import expansion


def _grid(rows: int = 21, cols: int = 31, step: int = 6):
    gy, gx = np.mgrid[0:rows, 0:cols]
    nodes = np.stack([20 + gx * step, 20 + gy * step], -1).reshape(-1, 2).astype(np.float32)
    return nodes, (rows, cols), step


def _detector(**kw) -> LoomingDetector:
    nodes, shape, step = _grid()
    args = dict(decay=0.9, clip=1.0, tol=1.0, loom_tol=0.5, min_nodes=10)
    args.update(kw)
    return LoomingDetector(nodes, shape, step, **args)


def _mask_scores(seq: SyntheticSequence, n: int, **config) -> tuple[float, float]:
    """Pixel (precision, recall) of the segmenter's masks over frames 3..n-1 of ``seq``."""
    seg = MotionSegmenter(dataclasses.replace(MotionSegmenterConfig(), **config))
    tp = fp = fn = 0
    for k in range(n):
        f = seq.frame(k)
        m = seg.process(f.image).mask > 0
        if k >= 3:
            tp += int((m & f.mask).sum())
            fp += int((m & ~f.mask).sum())
            fn += int((~m & f.mask).sum())
    return tp / max(tp + fp, 1), tp / max(tp + fn, 1)


def _disc(det: LoomingDetector, centre=(110.0, 80.0), radius=30.0) -> np.ndarray:
    d = det.nodes - np.array(centre, np.float32)
    return (np.hypot(d[:, 0], d[:, 1]) < radius).reshape(det.grid_shape)


def test_expansion_known_answer():
    """expansion() returns |a| * rms radius of R = t + a d + w perp(d), whatever t and w."""
    rng = np.random.default_rng(0)
    p = rng.uniform(0, 50, (40, 2))
    d = p - p.mean(axis=0)
    perp = np.stack([-d[:, 1], d[:, 0]], 1)
    res = np.array([0.7, -0.3]) + 0.05 * d + 0.02 * perp
    rho = np.sqrt((d**2).sum(1).mean())
    assert expansion(p, res) == pytest.approx(0.05 * rho, rel=1e-9)
    assert expansion(p, -0.05 * d) == pytest.approx(0.05 * rho, rel=1e-9)
    assert expansion(p, np.tile([1.5, 0.5], (40, 1))) == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("rate", [0.012, -0.012])
def test_expanding_residual_field_is_reported(rate):
    """Nodes inside a disc whose flow diverges from the ego-motion by ``rate * (p - c)`` per
    frame (0.36 px/frame at the rim of a 30 px disc: approaching, or receding) are reported
    once the accumulated residual reaches the tolerance, and only inside the disc (or the
    grid step its tracks have spread over)."""
    det = _detector()
    rows, cols = det.grid_shape
    disc = _disc(det)
    ego = np.zeros((rows, cols, 2), np.float32)
    d = (det.nodes - np.array([110.0, 80.0], np.float32)).reshape(rows, cols, 2)
    flow = np.where(disc[:, :, None], rate * d, 0.0).astype(np.float32)
    hits = [det.update(flow, ego, np.ones((rows, cols), bool)) for _ in range(12)]
    assert not hits[0].any()
    assert hits[-1].sum() > 10
    assert not (hits[-1] & ~_disc(det, radius=36.0)).any()


def test_uniform_drift_is_parallax_not_looming():
    """A disc drifting uniformly against the ego-motion by 0.3 px/frame (motion parallax of
    an object off the background plane) accumulates far above the tolerance but is not
    reported: it does not expand."""
    det = _detector()
    rows, cols = det.grid_shape
    disc = _disc(det)
    ego = np.zeros((rows, cols, 2), np.float32)
    flow = np.where(disc[:, :, None], np.float32([0.3, 0.0]), 0.0).astype(np.float32)
    for _ in range(30):
        out = det.update(flow, ego, np.ones((rows, cols), bool))
        assert not out.any()
    assert np.linalg.norm(det.accumulated, axis=1).max() > 2.0


def test_accumulation_follows_tracks_and_restarts():
    """The accumulated residual moves with the tracks (a node's sum lands where its track
    lands), unreliable nodes carry nothing, and a frame without ego-motion restarts it."""
    det = _detector(min_nodes=0)
    rows, cols = det.grid_shape
    ego = np.zeros((rows, cols, 2), np.float32)
    flow = np.zeros((rows, cols, 2), np.float32)
    flow[10, 10] = (6.0, 0.0)  # one node moves one grid step right: residual 6 clipped to 1
    ok = np.ones((rows, cols), bool)
    ok[10, 11] = False  # its own track is lost: only the moving node's track lands there
    det.update(flow, ego, ok)
    acc = np.linalg.norm(det.accumulated, axis=1).reshape(rows, cols)
    assert acc[10, 11] == pytest.approx(1.0)
    assert acc[10, 10] == 0.0
    det.update(np.zeros_like(flow), ego, ok)
    assert np.abs(det.accumulated).max() == 0.0
    flow[10, 10] = (0.5, 0.0)
    det.update(flow, ego, np.ones((rows, cols), bool))
    assert np.abs(det.accumulated).max() > 0
    det.update(flow, None, np.ones((rows, cols), bool))
    assert np.abs(det.accumulated).max() == 0.0


def test_approaching_object_found_while_camera_rotates():
    """A 60 px textured patch growing by 25 %/s in place (an object approaching along the
    optical axis: its rim moves 0.25 px/frame) while the camera pans at 20 deg/s: with the
    looming detector a blob centred on the patch (within 8 px) is found in most frames after
    the first 15; motionCUT's eq. 13 test alone finds it in few frames."""
    seq = SyntheticSequence(yaw_rate=20.0, patch_size=60, patch_scale_rate=0.25)
    found = {}
    for decay in (0.9, 0.0):
        seg = MotionSegmenter(dataclasses.replace(MotionSegmenterConfig(), accum_decay=decay))
        hits = 0
        for k in range(40):
            f = seq.frame(k)
            r = seg.process(f.image)
            if k >= 15 and r.has_motion:
                err = np.hypot(*(np.array(r.largest.centroid) - f.object_center))
                hits += err < 8.0
        found[decay] = hits
    assert found[0.9] >= 20, found
    assert found[0.0] <= 8, found


@pytest.mark.parametrize("yaw,pitch", [(20.0, 0.0), (40.0, 20.0)])
def test_static_rotation_gives_no_looming_blob(yaw, pitch):
    """A static textured scene under camera rotation produces no looming candidates that
    expand, and no blob, over 45 frames (the accumulation has reached steady state)."""
    seq = SyntheticSequence(yaw_rate=yaw, pitch_rate=pitch)
    seg = MotionSegmenter()
    for k in range(45):
        assert not seg.process(seq.frame(k).image).has_motion


def test_mask_follows_the_object_under_rotation():
    """With the camera panning at 40 deg/s (8 px/frame) the mask, shifted by the object's
    motion to the current frame, covers the translating patch better than the cells left at
    the grid positions of the previous frame (motionCUT)."""
    seq = SyntheticSequence(yaw_rate=40.0, patch_size=60, patch_velocity=(0.0, 90.0),
                            patch_start=(0, -40))
    cover = {shift: _mask_scores(seq, 20, mask_to_current=shift)[0] for shift in (True, False)}
    assert cover[True] > cover[False] + 0.03, cover


@pytest.mark.parametrize("velocity,yaw", [(600.0, 0.0), (-500.0, 0.0), (150.0, 20.0)])
def test_pixel_refinement_trims_the_mask(velocity, yaw):
    """A patch crossing the view at 20 or 17 px/frame (still camera) or 5 px/frame (camera
    panning at 20 deg/s): deciding per pixel which motion, the object's or the background's,
    explains it raises the mask's precision by at least 0.05 over the blob's cells and keeps
    its recall above 0.8."""
    seq = SyntheticSequence(yaw_rate=yaw, patch_size=60, patch_velocity=(velocity, 0.0),
                            patch_start=(-np.sign(velocity) * 120.0, 0.0))
    scores = {on: _mask_scores(seq, 14, mask_refine=on) for on in (True, False)}
    assert scores[True][0] > scores[False][0] + 0.05, scores
    assert scores[True][1] > 0.8, scores
