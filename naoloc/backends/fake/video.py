"""ALVideoDevice of the fake robot: ray-cast frames of the textured room.

A frame is rendered on demand from the TRUE camera pose: the true robot pose and the
forward kinematics of the measured joints (:mod:`naoloc.robot.kinematics`, StandInit's lean and
the walk's sway included). Its timestamp is the simulated time; its view angles are
``(+hfov/2, +vfov/2, -hfov/2, -vfov/2)`` (left, top, right, bottom).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from naoloc.backends.fake.render import RoomRenderer
from naoloc.backends.fake.world import FakeWorld
from naoloc.backends.simulated.camera_model import CameraModel, Motion, render_fov_for
from naoloc.constants import (
    FOV_V5,
    FOV_V6,
    RESOLUTIONS,
    kBottomCamera,
    kTopCamera,
)
from naoloc.errors import HandleError, RobotError
from naoloc.robot import rules
from naoloc.robot.image import Frame, frame_to_naoqi, from_rgb
from naoloc.robot.kinematics import optical_from_camera

MAX_SUBSCRIBERS = rules.MAX_SUBSCRIBERS


@dataclass
class Subscription:
    """One camera subscriber.

    Attributes:
        camera: Camera index (0 top, 1 bottom).
        resolution: NAOqi resolution id.
        colorspace: NAOqi colorspace id.
        fps: Frame rate asked for (5, 10, 15 or 30).
    """

    camera: int
    resolution: int
    colorspace: int
    fps: int


def _check_camera(index: int) -> int:
    return rules.camera_index(index)


class FakeVideo:
    """ALVideoDevice of the fake robot.

    Args:
        world: The shared robot state and clock.
        renderer: The room renderer.
    """

    def __init__(self, world: FakeWorld, renderer: RoomRenderer) -> None:
        self._world = world
        self._renderer = renderer
        realism, seed = world.cfg.world.camera_realism, world.cfg.world.sim.seed
        self._cameras = {c: CameraModel(realism, seed, c) for c in (kTopCamera, kBottomCamera)}
        self._fov = FOV_V6 if world.cfg.world.model == "v6" else FOV_V5
        self._render_fov = render_fov_for(self._fov, realism)  # wider through NAO's lens
        self._subs: dict[str, Subscription] = {}
        self._active = kTopCamera

    def _sub(self, nameId: str) -> Subscription:
        self._world.check_open()
        sub = self._subs.get(str(nameId))
        if sub is None:
            raise HandleError(f"unknown or unsubscribed camera handle {nameId!r}")
        return sub

    def subscribeCamera(
        self, name: str, cameraIndex: int, resolution: int, colorSpace: int, fps: int
    ) -> str:
        """Subscribe; returns ``name``, or ``name_<n>`` when ``name`` is already taken.

        Raises:
            RobotError: Unknown camera, resolution, colorspace or fps.
        """
        w = self._world
        w.check_open()
        camera = rules.camera_index(cameraIndex)
        resolution, colorspace, fps = rules.subscription(resolution, colorSpace, fps)
        if len(self._subs) >= MAX_SUBSCRIBERS:
            raise RobotError(f"too many camera subscribers ({MAX_SUBSCRIBERS}); unsubscribe some")
        handle, n = str(name), 0
        while handle in self._subs:
            n += 1
            handle = f"{name}_{n}"
        self._subs[handle] = Subscription(camera, int(resolution), colorspace, int(fps))
        w.tick()
        return handle

    def unsubscribe(self, nameId: str) -> bool:
        """Drop a subscription; True when it existed."""
        w = self._world
        w.check_open()
        existed = self._subs.pop(str(nameId), None) is not None
        w.tick()
        return existed

    def getImageRemote(self, nameId: str) -> list[Any]:
        """Render the current view: the 12-item NAOqi image array (bytes in slot 6).

        Raises:
            HandleError: Unknown or unsubscribed handle.
        """
        sub = self._sub(nameId)
        self._world.tick()
        return frame_to_naoqi(self.capture(sub.camera, sub.resolution, sub.colorspace, sub.fps))

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
        nominal_h, nominal_v = self._fov
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

    def releaseImage(self, nameId: str) -> bool:
        """No-op for remote images (checks the handle); True."""
        self._sub(nameId)
        self._world.tick()
        return True

    def setActiveCamera(self, cameraIndex: int) -> bool:
        """Select the active camera; True on success, False for a camera NAO does not have."""
        self._world.check_open()
        self._world.tick()
        try:
            self._active = rules.camera_index(cameraIndex)
        except RobotError:
            return False
        return True

    def getActiveCamera(self) -> int:
        """Index of the active camera."""
        self._world.tick()
        return self._active

    def getHorizontalFOV(self, cameraIndex: int) -> float:
        """Horizontal field of view in radians (V5 or V6 head by ``world.model``)."""
        self._world.tick()
        _check_camera(cameraIndex)
        return float(self._fov[0])

    def getVerticalFOV(self, cameraIndex: int) -> float:
        """Vertical field of view in radians."""
        self._world.tick()
        _check_camera(cameraIndex)
        return float(self._fov[1])

    def getResolution(self, nameId: str) -> int:
        """Resolution id of a subscription."""
        sub = self._sub(nameId)
        self._world.tick()
        return sub.resolution

    def getColorSpace(self, nameId: str) -> int:
        """Colorspace id of a subscription."""
        sub = self._sub(nameId)
        self._world.tick()
        return sub.colorspace

    def getFrameRate(self, nameId: str) -> int:
        """Frame rate of a subscription (frames per second)."""
        sub = self._sub(nameId)
        self._world.tick()
        return sub.fps

    def getCameraIndex(self, nameId: str) -> int:
        """Camera index of a subscription."""
        sub = self._sub(nameId)
        self._world.tick()
        return sub.camera
