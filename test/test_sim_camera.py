"""The eye cameras see the table objects where the pinhole model (EyeKinematics + intrinsics)
projects them, in both eyes; the threaded renderer delivers frames stamped with sim time."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from icub_pmp.kinematics import IcubModel
from icub_pmp.kinematics.eye_kinematics import project_point
from icub_sim_bridge import CameraRenderer, SimConfig, Simulator

LOOK_DOWN = {"neck_pitch": -0.55, "eyes_tilt": -0.35, "eyes_vergence": 0.05,
             "l_shoulder_roll": 0.2, "r_shoulder_roll": 0.2}


@pytest.fixture(scope="module")
def scene():
    sim = Simulator(SimConfig())
    sim.reset(q=LOOK_DOWN)
    sim.set_object_pose("box", [-0.36, -0.05, -0.05])
    sim.set_object_pose("cylinder", [-0.40, 0.12, -0.03])
    sim.step(5)
    cams = CameraRenderer(sim.model, sim.built.camera, threaded=False)
    images = cams.render(sim.data)
    cams.close()
    return sim, images


def _mask_bbox(img: np.ndarray, rgb: tuple[int, int, int]) -> tuple[float, float, float, float]:
    """Pixel-edge bounding box (u_min, u_max, v_min, v_max) of the pixels close to the
    object's hue (lit red or blue)."""
    r, g, b = (img[..., k].astype(int) for k in range(3))
    if rgb == (1, 0, 0):
        m = (r > 80) & (r > 2 * g + 20) & (r > 2 * b + 20)
    else:
        m = (b > 80) & (b > 2 * r + 20) & (b > g + 30)
    vs, us = np.nonzero(m)
    assert us.size > 50, "object not visible"
    return us.min(), us.max() + 1.0, vs.min(), vs.max() + 1.0


def _projected_bbox(T_cam: np.ndarray, points: np.ndarray, sim: Simulator):
    uv = np.array([project_point(T_cam, p, sim.built.camera) for p in points])
    return uv[:, 0].min(), uv[:, 0].max(), uv[:, 1].min(), uv[:, 1].max()


def _box_corners(sim: Simulator) -> np.ndarray:
    pose = sim.object_pose("box")
    h = np.array(sim.config.box_size) / 2
    return np.array([pose.position + h * [sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1)
                     for sz in (-1, 1)])


def _cylinder_rim(sim: Simulator) -> np.ndarray:
    pose = sim.object_pose("cylinder")
    r, h = sim.config.cylinder_radius, sim.config.cylinder_height / 2
    a = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    ring = np.stack([r * np.cos(a), r * np.sin(a), np.zeros_like(a)], axis=1)
    return np.concatenate([pose.position + ring + [0, 0, h], pose.position + ring - [0, 0, h]])


@pytest.mark.parametrize("side", ["left", "right"])
@pytest.mark.parametrize("obj", ["box", "cylinder"])
def test_object_at_projected_pixels(scene, side, obj):
    """The red box and the blue cylinder appear in each eye image exactly where their 3D
    outline projects (EyeKinematics pose, fx = fy = 343.12, cx = 160, cy = 120): the image
    bounding box of the object's pixels matches the projected one within 2 px."""
    sim, images = scene
    pin_model = IcubModel()
    q = sim.joint_state().position[sim.indices(pin_model.joint_names)]
    T_head = pin_model.frame_pose(q, "head").homogeneous
    tilt, version, vergence = sim.joint_state().position[
        sim.indices(["eyes_tilt", "eyes_version", "eyes_vergence"])]
    T_cam = sim.built.eye_kinematics.T_root_camera(T_head, side, tilt, version, vergence)
    pts = _box_corners(sim) if obj == "box" else _cylinder_rim(sim)
    expected = _projected_bbox(T_cam, pts, sim)
    img = images[side]
    assert img.shape == (240, 320, 3) and img.dtype == np.uint8
    assert 0 < expected[0] and expected[1] < 320 and 0 < expected[2] and expected[3] < 240
    got = _mask_bbox(img, (1, 0, 0) if obj == "box" else (0, 0, 1))
    np.testing.assert_allclose(got, expected, atol=2.0)


def test_stereo_disparity(scene):
    """The same object lies further right in the left image than in the right one (positive
    disparity for a point in front of both eyes)."""
    _, images = scene
    ul = np.mean(_mask_bbox(images["left"], (1, 0, 0))[:2])
    ur = np.mean(_mask_bbox(images["right"], (1, 0, 0))[:2])
    assert ul > ur + 5


def test_threaded_renderer_delivers_stamped_frames():
    """The worker renders each requested snapshot once, stamped with the snapshot's sim time,
    and equal to an unthreaded render of the same state."""
    sim = Simulator(SimConfig())
    sim.reset(q=LOOK_DOWN)
    got: list[tuple[float, dict]] = []
    done = threading.Event()

    def on_frame(t, images):
        got.append((t, images))
        if len(got) == 3:
            done.set()

    cams = CameraRenderer(sim.model, sim.built.camera, threaded=True, on_frame=on_frame)
    stamps = []
    for _ in range(3):
        sim.step(33)
        stamps.append(sim.time)
        cams.request(sim.data)
    assert done.wait(30.0)
    cams.close()
    assert [t for t, _ in got] == pytest.approx(stamps)
    ref = CameraRenderer(sim.model, sim.built.camera, threaded=False)
    now = ref.render(sim.data)
    ref.close()
    assert np.abs(now["left"].astype(int) - got[-1][1]["left"].astype(int)).mean() < 1.0
