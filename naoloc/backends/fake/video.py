"""ALVideoDevice of the fake robot: ray-cast frames of the textured room (NAOqi semantics:
:class:`naoloc.backends.simulated.video.SimulatedVideo`).

A frame is rendered on demand from the TRUE camera pose: the true robot pose and the
forward kinematics of the measured joints (:mod:`naoloc.robot.kinematics`, StandInit's lean and
the walk's sway included). Its timestamp is the simulated time; its view angles are
``(+hfov/2, +vfov/2, -hfov/2, -vfov/2)`` (left, top, right, bottom).
"""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from naoloc.backends.fake.render import RoomRenderer
from naoloc.backends.fake.world import FakeWorld
from naoloc.backends.simulated.camera_model import CameraModel, Motion, render_fov_for
from naoloc.backends.simulated.video import SimulatedVideo
from naoloc.constants import (
    FOV_V5,
    FOV_V6,
    RESOLUTIONS,
    kBottomCamera,
    kTopCamera,
)
from naoloc.robot.image import Frame, frame_to_naoqi, from_rgb
from naoloc.robot.kinematics import optical_from_camera


class FakeVideo(SimulatedVideo):
    """ALVideoDevice of the fake robot (NAOqi's semantics: :class:`SimulatedVideo`).

    Args:
        world: The shared robot state and clock.
        renderer: The room renderer.
    """

    def __init__(self, world: FakeWorld, renderer: RoomRenderer) -> None:
        super().__init__()
        self._world = world
        self._renderer = renderer
        realism, seed = world.cfg.world.camera_realism, world.cfg.world.sim.seed
        self._cameras = {c: CameraModel(realism, seed, c) for c in (kTopCamera, kBottomCamera)}
        self._fov_rad = FOV_V6 if world.cfg.world.model == "v6" else FOV_V5
        self._render_fov = render_fov_for(self._fov_rad, realism)  # wider through NAO's lens

    def _check_open(self) -> None:
        self._world.check_open()

    def _advance(self) -> None:
        self._world.tick()

    def _fov(self) -> tuple[float, float]:
        return self._fov_rad

    def _check_resolution(self, resolution: int) -> None:
        return None  # the ray caster renders any NAO resolution

    def _image(self, camera: int, resolution: int, colorspace: int, fps: int) -> list[Any]:
        return frame_to_naoqi(self.capture(camera, resolution, colorspace, fps))

    def capture(self, camera: int, resolution: int, colorspace: int, fps: int = 30) -> Frame:
        """Render a frame of the current view without a subscription (no time advance).

        Args:
            camera: Camera index (0 top, 1 bottom).
            resolution: NAOqi resolution id.
            colorspace: NAOqi colorspace id.
            fps: Frame rate the camera runs at (auto exposure adapts per camera frame).
        """
        w = self._world
        width, height = RESOLUTIONS[resolution]
        cam = optical_from_camera(w.camera_in_room(camera))  # joints' kinematics, with sway
        hfov, vfov = self._render_fov
        rgb = self._renderer.render(cam, width, height, hfov, vfov)
        light = w.cfg.world.sim.light
        if light != 1.0:  # the room's light scale, as the MuJoCo lights take it
            rgb = cv2.convertScaleAbs(rgb, alpha=light)
        rgb = self._cameras[camera].process(
            rgb, time_s=w.time_s, fps=fps, hfov=hfov, vfov=vfov, motion=self._motion(cam)
        )
        pixels = from_rgb(rgb, colorspace)
        nominal_h, nominal_v = self._fov_rad
        angles = (nominal_h / 2, nominal_v / 2, -nominal_h / 2, -nominal_v / 2)
        return Frame(pixels, colorspace, w.time_s, camera, angles)

    def _motion(self, cam_in_room: np.ndarray) -> Motion:
        """The camera's velocity in its optical frame: the body's walk plus the head's joints."""
        w = self._world
        rates = []
        for name in ("HeadYaw", "HeadPitch"):
            cmd, target = w.joint_cmd[name], w.joint_target[name]
            rates.append(
                0.0 if cmd == target else float(np.copysign(w.joint_speed[name], target - cmd))
            )
        vx, vy, wz = w.velocity
        heading = w.true_pose.theta
        yaw = heading + w.head_angles()[0]
        c, s = np.cos(heading), np.sin(heading)
        omega_room = np.array(
            [-np.sin(yaw) * rates[1], np.cos(yaw) * rates[1], wz + rates[0]]
        )  # pitch turns about the head's left (y) axis, yaw and the walk about z
        v_room = np.array([c * vx - s * vy, s * vx + c * vy, 0.0])
        rot = cam_in_room[:3, :3].T
        om, v = rot @ omega_room, rot @ v_room
        return Motion(
            (float(om[0]), float(om[1]), float(om[2])), (float(v[0]), float(v[1]), float(v[2]))
        )
