"""ALVideoDevice on the MuJoCo simulation: rendering and the NAOqi image array.

Subscriptions and NAOqi's rules are
:class:`naoloc.backends.simulated.video.SimulatedVideo`'s. One ``mujoco.Renderer`` per
image size, created on first use and reused; frames are rendered into preallocated
buffers. Rendering happens only in ``getImageRemote``, which advances simulated time by one
ALMotion cycle and then renders the scene at that time (the timestamp in slots [4], [5]).
The pipeline is render -> camera model -> colorspace: ``naoloc.backends.simulated.
camera_model`` (one per camera, shared with the fake backend) applies
``world.camera_realism`` (by default a NAO's camera: lens, auto exposure, white balance,
noise, YUV422, motion blur from the camera's velocity in the physics).
"""

from __future__ import annotations

import contextlib
import math
from typing import Any

import numpy as np

from naoloc.backends.mujoco.gl import import_mujoco
from naoloc.backends.mujoco.sim import CAMERA_NAMES, Simulation
from naoloc.backends.simulated.camera_model import CameraModel, Motion
from naoloc.backends.simulated.video import SimulatedVideo
from naoloc.constants import (
    RESOLUTION_NAMES,
    RESOLUTIONS,
    k4VGA,
    kBottomCamera,
    kTopCamera,
)
from naoloc.errors import RenderError, RobotError
from naoloc.robot.image import from_rgb

# mujoco reads MUJOCO_GL when first imported: import_mujoco chooses the platform first.
mujoco: Any = import_mujoco()

MAX_SIZE = RESOLUTIONS[k4VGA]  # the offscreen buffer of the room model (1280 x 960)
HIDDEN_GROUPS = (2, 3, 4, 5)  # head shell, (unused), collision shapes, removed posters
RENDER_PACKAGES = (
    "apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri (or libosmesa6), and set "
    "MUJOCO_GL=egl (or osmesa) before mujoco is first imported"
)


class MujocoVideo(SimulatedVideo):
    """ALVideoDevice of the simulated NAO (NAOqi's semantics: :class:`SimulatedVideo`)."""

    def __init__(self, sim: Simulation) -> None:
        """Render the simulation's cameras."""
        super().__init__()
        self._sim = sim
        self._renderers: dict[tuple[int, int], Any] = {}
        self._buffers: dict[tuple[int, int], np.ndarray] = {}
        self._option = mujoco.MjvOption()
        for g in HIDDEN_GROUPS:
            self._option.geomgroup[g] = 0
        realism, seed = sim.cfg.world.camera_realism, sim.cfg.world.sim.seed
        self._cameras = {c: CameraModel(realism, seed, c) for c in (kTopCamera, kBottomCamera)}
        self._velocity = np.zeros(6)

    def _check_open(self) -> None:
        return None  # the simulation refuses calls by itself once closed

    def _advance(self) -> None:
        self._sim.cycle()

    def _fov(self) -> tuple[float, float]:
        return self._sim.fov

    def _check_resolution(self, resolution: int) -> None:
        w, h = RESOLUTIONS[resolution]
        if w > MAX_SIZE[0] or h > MAX_SIZE[1]:
            raise RobotError(
                f"resolution {RESOLUTION_NAMES[resolution]} is not supported by the simulator "
                "(k4VGA at most)"
            )

    # ------------------------------------------------------------------ images
    def _renderer(self, width: int, height: int) -> tuple[Any, np.ndarray]:
        key = (width, height)
        renderer = self._renderers.get(key)
        if renderer is None:
            try:
                renderer = mujoco.Renderer(self._sim.model, height, width)
            except Exception as err:  # GL errors come as many different types
                why = str(err).strip().splitlines()[0] if str(err).strip() else ""
                raise RenderError(
                    f"headless rendering failed ({type(err).__name__}: {why}); {RENDER_PACKAGES}"
                ) from None
            self._renderers[key] = renderer
            self._buffers[key] = np.empty((height, width, 3), np.uint8)
        return renderer, self._buffers[key]

    def render_rgb(self, camera: int, width: int, height: int) -> np.ndarray:
        """Render a camera now, without advancing time; ``(h, w, 3)`` uint8 RGB (reused buffer)."""
        renderer, buf = self._renderer(width, height)
        self._sim.prepare_render()
        renderer.update_scene(
            self._sim.data, camera=CAMERA_NAMES[camera], scene_option=self._option
        )
        renderer.render(out=buf)
        return buf

    def _camera_motion(self, camera: int) -> Motion:
        """The camera's angular and linear velocity now, in its optical frame."""
        sim = self._sim
        cam = int(mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_CAMERA, CAMERA_NAMES[camera]))
        mujoco.mj_objectVelocity(
            sim.model, sim.data, mujoco.mjtObj.mjOBJ_CAMERA, cam, self._velocity, 1
        )
        w, v = self._velocity[:3], self._velocity[3:]
        # MuJoCo's camera frame: x right, y up, looking along -z; optical: y down, z forward.
        return Motion(
            (float(w[0]), -float(w[1]), -float(w[2])), (float(v[0]), -float(v[1]), -float(v[2]))
        )

    def _image(self, camera: int, resolution: int, colorspace: int, fps: int) -> list[Any]:
        """Render a camera now and return the NAOqi image array (stamped with sim time)."""
        width, height = RESOLUTIONS[resolution]
        stamp = self._sim.sim_time()
        hfov, vfov = self._sim.render_fov
        rgb = self._cameras[camera].process(
            self.render_rgb(camera, width, height),
            time_s=stamp, fps=fps, hfov=hfov, vfov=vfov, motion=self._camera_motion(camera),
            radiance=self._sim.radiance,
        )  # fmt: skip
        pixels = from_rgb(rgb, colorspace)
        sec = math.floor(stamp)
        usec = min(999_999, round((stamp - sec) * 1e6))
        return [
            width, height, int(pixels.shape[2]) if pixels.ndim == 3 else 1, colorspace,
            sec, usec, pixels.tobytes(), camera,
            *self._angles(),
        ]  # fmt: skip

    def _angles(self) -> tuple[float, float, float, float]:
        """(left, top, right, bottom) of the nominal field of view, rad."""
        hfov, vfov = self._sim.fov
        return (hfov / 2, vfov / 2, -hfov / 2, -vfov / 2)

    def close(self) -> None:
        """Free every renderer (GL contexts); safe to call twice."""
        for renderer in self._renderers.values():
            with contextlib.suppress(Exception):  # best effort at shutdown
                renderer.close()
        self._renderers.clear()
        self._buffers.clear()
