"""Evaluation data of the motion benchmark: sequences rendered from the simulator's
eye cameras with MuJoCo ground truth, and the synthetic homography sequences."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.baselines import SyntheticSequence
from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.eye_kinematics import project_point
from icub_sim_bridge.harness.sequence_generator import SequenceGenerator, SequenceSpec


def test_rendered_sequence_ground_truth():
    """Frames are 320x240 RGB from both eyes; during the lead-in the target is hidden (empty
    masks, NaN position); then its mask is where the pinhole model projects its centre, and a
    40 cm/s parallel motion moves it by about 343 * 0.4 / 0.47 / 30 = 9.7 px per frame."""
    gen = SequenceGenerator()
    try:
        spec = SequenceSpec(speed=0.4, direction="parallel", n_frames=5, lead_in=2, seed=0,
                            amplitude=0.2)
        frames = list(gen.frames(spec))
        cam = gen.camera
    finally:
        gen.close()
    assert spec.name == "parallel_40cm_still"
    for f in frames:
        assert f.left.shape == f.right.shape == (240, 320, 3) and f.left.dtype == np.uint8
    for f in frames[:2]:
        assert not f.left_mask.any() and np.isnan(f.target_position).all()
    cents = []
    for f in frames[2:]:
        for mask, T in ((f.left_mask, f.T_root_left), (f.right_mask, f.T_root_right)):
            assert mask.sum() > 1500
            c = np.argwhere(mask).mean(axis=0)[::-1]
            assert np.hypot(*(c - project_point(T, f.target_position, cam))) < 1.5
        cents.append(np.argwhere(f.left_mask).mean(axis=0)[::-1])
    step = np.linalg.norm(np.diff(cents, axis=0), axis=1)
    assert np.allclose(step, 9.7, atol=1.5), step


def test_frame_at_poses_the_robot_from_joint_states():
    """frame_at renders the robot at given joints (a simulation's joint states, eyes as tilt,
    version, vergence) and the ball where asked: posed with a sequence frame's own joints and
    target, it reproduces that frame; turning the neck yaw moves the camera."""
    gen = SequenceGenerator(right_camera=False)
    try:
        spec = SequenceSpec(speed=0.4, direction="parallel", head_rate=20.0, n_frames=3,
                            seed=3)
        f = list(gen.frames(spec))[-1]
        g = gen.frame_at(f.joints, f.target_position, index=7)
        turned = gen.frame_at({**f.joints, "neck_yaw": f.joints["neck_yaw"] + 0.1}, None)
    finally:
        gen.close()
    assert g.index == 7
    np.testing.assert_array_equal(g.left, f.left)
    np.testing.assert_array_equal(g.left_mask, f.left_mask)
    np.testing.assert_allclose(g.T_root_left, f.T_root_left, atol=1e-12)
    assert not turned.left_mask.any() and np.isnan(turned.target_position).all()
    assert np.linalg.norm(turned.T_root_left[:3, 2] - f.T_root_left[:3, 2]) > 0.05


def test_sequence_spec_validation():
    """Unknown directions or head axes and negative values are rejected by name."""
    with pytest.raises(UnknownName, match="direction"):
        SequenceSpec(direction="sideways")
    with pytest.raises(UnknownName, match="head axis"):
        SequenceSpec(head_axis="roll")
    with pytest.raises(InvalidInput):
        SequenceSpec(speed=-1.0)
    assert SequenceSpec(direction="none", head_rate=40, head_axis="pitch").name == \
        "static_pitch40"


def test_synthetic_sequence_is_deterministic_and_masks_the_patch():
    """The synthetic sequence is reproducible and its mask is the patch (60 x 60 px on the
    canvas, seen at unit scale by the unrotated camera)."""
    a = SyntheticSequence(patch_size=60, patch_velocity=(30.0, 0.0)).frame(3)
    b = SyntheticSequence(patch_size=60, patch_velocity=(30.0, 0.0)).frame(3)
    assert np.array_equal(a.image, b.image)
    assert abs(int(a.mask.sum()) - 3600) < 200
    c = np.argwhere(a.mask).mean(axis=0)[::-1]
    assert np.hypot(*(c - np.array(a.object_center))) < 1.0
