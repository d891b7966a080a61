"""CameraRenderer: the two eye cameras, rendered offscreen (MUJOCO_GL=egl, CPU llvmpipe).

Each frame renders a *snapshot* of the simulation state (joint positions and time), so it can
run on a worker thread while physics goes on (MuJoCo releases the GIL while rendering). The
worker owns its GL context, its ``MjData`` and its ``mujoco.Renderer``. Back-pressure keeps
the frame rate exact in simulated time: a new snapshot waits until the previous frame is done,
so no frame is dropped and each image carries the sim time of its snapshot.

Images are (height, width, 3) uint8 RGB, row 0 at the top (what ``sensor_msgs/Image`` rgb8
expects). Only geom groups 0 (upper body) and 1 (table, objects, floor) are drawn; legs,
mainstay, eyeballs and collision hulls are not (see :class:`ModelBuilder`).

    cams = CameraRenderer(model, intrinsics, threaded=True, on_frame=callback)
    cams.request(sim.data)   # at each camera period; callback(t, {"left": img, "right": img})
    cams.close()
"""

from __future__ import annotations

import threading
from typing import Callable

import mujoco
import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.eye_kinematics import EYE_SIDES, CameraIntrinsics
from icub_sim_bridge.model_builder import EYE_CAMERAS, GROUP_OBJECTS, GROUP_VISUAL

__all__ = ["CameraRenderer", "FrameCallback"]

FrameCallback = Callable[[float, dict[str, np.ndarray]], None]


class CameraRenderer:
    """Render both eye cameras from state snapshots (see module doc)."""

    def __init__(self, model: mujoco.MjModel, camera: CameraIntrinsics, threaded: bool = True,
                 on_frame: FrameCallback | None = None):
        if threaded and on_frame is None:
            raise InvalidInput("CameraRenderer: threaded rendering needs an on_frame callback")
        self.model = model
        self.camera = camera
        self.threaded = threaded
        self.on_frame = on_frame
        self.frames = 0
        self._data = mujoco.MjData(model)
        self._opt = mujoco.MjvOption()
        self._opt.geomgroup[:] = 0
        self._opt.geomgroup[GROUP_VISUAL] = 1
        self._opt.geomgroup[GROUP_OBJECTS] = 1
        self._renderer: mujoco.Renderer | None = None
        self._error: BaseException | None = None
        if threaded:
            self._idle = threading.Event()
            self._idle.set()
            self._work = threading.Event()
            self._stop = False
            self._thread = threading.Thread(target=self._run, name="camera_renderer",
                                            daemon=True)
            self._thread.start()

    # ------------------------------------------------------------------ rendering
    def _ensure_renderer(self) -> mujoco.Renderer:
        if self._renderer is None:
            self._renderer = mujoco.Renderer(self.model, self.camera.height, self.camera.width)
        return self._renderer

    def _snapshot(self, data: mujoco.MjData) -> None:
        self._data.qpos[:] = data.qpos
        self._data.time = data.time

    def _render_snapshot(self) -> dict[str, np.ndarray]:
        r = self._ensure_renderer()
        mujoco.mj_kinematics(self.model, self._data)
        mujoco.mj_camlight(self.model, self._data)
        out = {}
        for side in EYE_SIDES:
            r.update_scene(self._data, camera=EYE_CAMERAS[side], scene_option=self._opt)
            out[side] = r.render()  # a new array each call
        self.frames += 1
        return out

    def render(self, data: mujoco.MjData) -> dict[str, np.ndarray]:
        """Render both cameras now, on this thread ({'left': img, 'right': img}).
        Only for an unthreaded renderer (a GL context belongs to one thread)."""
        if self.threaded:
            raise InvalidInput("CameraRenderer.render: this renderer is threaded; use request")
        self._snapshot(data)
        return self._render_snapshot()

    def request(self, data: mujoco.MjData, timeout: float = 5.0) -> None:
        """Snapshot ``data`` and produce a frame: on the worker (waits for the previous frame
        first) or at once; ``on_frame(t, images)`` receives it."""
        if not self.threaded:
            t = float(data.time)
            images = self.render(data)
            if self.on_frame is not None:
                self.on_frame(t, images)
            return
        if self._error is not None:
            raise RuntimeError(f"camera renderer failed: {self._error}") from self._error
        if not self._idle.wait(timeout):
            raise RuntimeError(f"camera renderer: previous frame not done after {timeout} s")
        self._idle.clear()
        self._snapshot(data)
        self._work.set()

    def wait_idle(self, timeout: float = 5.0) -> bool:
        """Wait until the worker has delivered the last requested frame."""
        return self._idle.wait(timeout) if self.threaded else True

    def _run(self) -> None:
        try:
            self._ensure_renderer()
            while True:
                self._work.wait()
                self._work.clear()
                if self._stop:
                    return
                t = float(self._data.time)
                images = self._render_snapshot()
                try:
                    if self.on_frame is not None:
                        self.on_frame(t, images)
                finally:
                    self._idle.set()
        except BaseException as exc:  # reported on the next request
            self._error = exc
            self._idle.set()
        finally:
            if self._renderer is not None:
                self._renderer.close()
                self._renderer = None

    def close(self) -> None:
        """Stop the worker and free the GL context."""
        if self.threaded:
            self._stop = True
            self._work.set()
            self._thread.join(timeout=5.0)
        elif self._renderer is not None:
            self._renderer.close()
            self._renderer = None
