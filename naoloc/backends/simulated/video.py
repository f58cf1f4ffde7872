"""ALVideoDevice's call surface for the simulated robots, written once.

:class:`SimulatedVideo` is the ALVideoDevice of the fake and the MuJoCo robot, in process
and behind ``naoloc serve`` (whose front runs every call on the robot thread,
:mod:`naoloc.backends.naoqi.emulation.video`). It keeps NAOqi's subscriber bookkeeping:
argument rules (:mod:`naoloc.robot.rules`), unique handles (``name``, then ``name_1``...),
the subscriber limit, the deprecated ``subscribe`` on the active camera, frame rates 1-30
(rendered at the nearest rate the simulated camera runs at: 5, 10, 15 or 30), per-
subscriber resolution, colorspace and rate, and per-camera parameters (brightness,
exposure...: stored and read back, but the simulated image does not change). A backend
subclasses it and supplies the pictures only (the ``_`` methods a subclass implements).

Time: every call that touches the camera advances simulated time by one 20 ms ALMotion
cycle (``getImageRemote`` before it renders, so the picture is of that time).
"""

from __future__ import annotations

import abc
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final

from naoloc.constants import kBottomCamera, kTopCamera
from naoloc.errors import HandleError, RobotError
from naoloc.robot import rules

# ALVideoDevice camera parameter ids -> default values (NAOqi's kCamera*ID; unconfirmed
# defaults are those NAOqi 2.x reports on a V5 top camera).
CAMERA_PARAMETERS: Final[dict[int, int]] = {
    0: 55,  # kCameraBrightnessID
    1: 32,  # kCameraContrastID
    2: 128,  # kCameraSaturationID
    3: 0,  # kCameraHueID
    6: 32,  # kCameraGainID
    7: 0,  # kCameraHFlipID
    8: 0,  # kCameraVFlipID
    11: 1,  # kCameraAutoExpositionID
    12: 1,  # kCameraAutoWhiteBalanceID
    14: 1,  # kCameraResolutionID
    15: 30,  # kCameraFrameRateID
    17: 512,  # kCameraExposureID
    22: 0,  # kCameraSelectID
    24: 2,  # kCameraSharpnessID
    33: 6500,  # kCameraWhiteBalanceID
    34: 0,  # kCameraBacklightCompensationID
}
_SELECT = 22  # kCameraSelectID: the camera's own index


@dataclass
class Subscription:
    """One camera subscriber.

    Attributes:
        camera: Camera index (0 top, 1 bottom).
        resolution: NAOqi resolution id.
        colorspace: NAOqi colorspace id.
        fps: Frame rate asked for (1-30).
    """

    camera: int
    resolution: int
    colorspace: int
    fps: int


def _defaults(camera: int) -> dict[int, int]:
    return {**CAMERA_PARAMETERS, _SELECT: camera}


class SimulatedVideo(abc.ABC):
    """ALVideoDevice of a simulated NAO (see the module docstring); subclasses render.

    Attributes:
        on_not_simulated: Called once per kind of call that is accepted but not simulated
            (camera parameters), with what it is; ``naoloc serve`` logs it.
    """

    def __init__(self) -> None:
        self._subs: dict[str, Subscription] = {}
        self._active = kTopCamera
        self._params = {c: _defaults(c) for c in (kTopCamera, kBottomCamera)}
        self.on_not_simulated: Callable[[str], None] = lambda what: None

    # ------------------------------------------------------------------ the camera
    @abc.abstractmethod
    def _check_open(self) -> None:
        """Raise RobotError when the robot was closed."""

    @abc.abstractmethod
    def _advance(self) -> None:
        """Advance simulated time by one ALMotion cycle."""

    @abc.abstractmethod
    def _fov(self) -> tuple[float, float]:
        """The cameras' nominal (horizontal, vertical) field of view, rad."""

    @abc.abstractmethod
    def _check_resolution(self, resolution: int) -> None:
        """Raise RobotError for a resolution the simulator cannot render."""

    @abc.abstractmethod
    def _image(self, camera: int, resolution: int, colorspace: int, fps: int) -> list[Any]:
        """The 12-item NAOqi image array of a camera now (no time advance)."""

    # ------------------------------------------------------------------ subscribers
    def _sub(self, nameId: Any) -> Subscription:
        self._check_open()
        sub = self._subs.get(nameId) if isinstance(nameId, str) else None
        if sub is None:
            raise HandleError(f"no camera subscriber named {nameId!r}")
        return sub

    def subscribeCamera(
        self, name: Any, cameraIndex: Any, resolution: Any, colorSpace: Any, fps: Any
    ) -> str:
        """Subscribe; returns ``name``, or ``name_<n>`` when ``name`` is already taken.

        Raises:
            RobotError: Unknown camera, resolution or colorspace, a resolution the simulator
                cannot render, fps outside 1-30, or too many subscribers.
        """
        self._check_open()
        if not isinstance(name, str) or not name:
            raise RobotError(f"subscriber name must be a non-empty string, got {name!r}")
        camera = rules.camera_index(cameraIndex)
        res, cs, rate = rules.subscription(resolution, colorSpace, fps)
        self._check_resolution(res)
        if len(self._subs) >= rules.MAX_SUBSCRIBERS:
            raise RobotError(
                f"too many camera subscribers ({rules.MAX_SUBSCRIBERS}); unsubscribe some"
            )
        handle, n = name, 0
        while handle in self._subs:
            n += 1
            handle = f"{name}_{n}"
        self._subs[handle] = Subscription(camera, res, cs, rate)
        self._advance()
        return handle

    def subscribe(self, name: Any, resolution: Any, colorSpace: Any, fps: Any) -> str:
        """Deprecated NAOqi 1 form: subscribe to the active camera."""
        return self.subscribeCamera(name, self._active, resolution, colorSpace, fps)

    def unsubscribe(self, nameId: Any) -> bool:
        """Drop a subscriber; True when it existed."""
        self._check_open()
        existed = isinstance(nameId, str) and self._subs.pop(nameId, None) is not None
        self._advance()
        return existed

    def getSubscribers(self) -> list[str]:
        """Handles of every subscriber."""
        self._check_open()
        return list(self._subs)

    # ------------------------------------------------------------------ images
    def getImageRemote(self, nameId: Any) -> list[Any]:
        """Advance one cycle and take the picture: the 12-item NAOqi image array
        (``[width, height, layers, colorspace, sec, usec, bytes, camera, left, top, right,
        bottom]``, angles in radians; see ``naoloc.robot.image.Frame``).

        Raises:
            HandleError: Unknown or unsubscribed handle.
        """
        sub = self._sub(nameId)
        self._advance()
        return self._image(sub.camera, sub.resolution, sub.colorspace, rules.backend_fps(sub.fps))

    def getImageLocal(self, nameId: Any) -> Any:
        """Not available to a remote client (as on NAOqi)."""
        raise RobotError("getImageLocal only works inside NAOqi's process; use getImageRemote")

    def releaseImage(self, nameId: Any) -> bool:
        """Give the image back (nothing to do for remote images); True."""
        self._sub(nameId)
        self._advance()
        return True

    # ------------------------------------------------------------------ cameras
    def setActiveCamera(self, cameraIndex: Any) -> bool:
        """Select the camera of ``subscribe``; False for an index NAO does not have."""
        self._check_open()
        self._advance()
        try:
            self._active = rules.camera_index(cameraIndex)
        except RobotError:
            return False
        return True

    def getActiveCamera(self) -> int:
        """The active camera's index."""
        self._advance()
        return self._active

    def getHorizontalFOV(self, cameraIndex: Any) -> float:
        """Horizontal field of view, rad (V5 or V6 head by ``world.model``)."""
        rules.camera_index(cameraIndex)
        self._advance()
        return float(self._fov()[0])

    def getVerticalFOV(self, cameraIndex: Any) -> float:
        """Vertical field of view, rad."""
        rules.camera_index(cameraIndex)
        self._advance()
        return float(self._fov()[1])

    def getCameraName(self, cameraIndex: Any) -> str:
        """ "CameraTop" or "CameraBottom"."""
        return ("CameraTop", "CameraBottom")[rules.camera_index(cameraIndex)]

    def isCameraOpen(self, cameraIndex: Any) -> bool:
        """Both simulated cameras are always open."""
        rules.camera_index(cameraIndex)
        return True

    # ------------------------------------------------------------------ a subscriber's settings
    def getResolution(self, nameId: Any) -> int:
        """Resolution id of a subscriber."""
        sub = self._sub(nameId)
        self._advance()
        return sub.resolution

    def getColorSpace(self, nameId: Any) -> int:
        """Colorspace id of a subscriber."""
        sub = self._sub(nameId)
        self._advance()
        return sub.colorspace

    def getFrameRate(self, nameId: Any) -> int:
        """Frame rate asked for (1-30)."""
        sub = self._sub(nameId)
        self._advance()
        return sub.fps

    def getCameraIndex(self, nameId: Any) -> int:
        """Camera of a subscriber."""
        sub = self._sub(nameId)
        self._advance()
        return sub.camera

    def setFrameRate(self, nameId: Any, frameRate: Any) -> bool:
        """Change a subscriber's frame rate (1-30); True."""
        sub = self._sub(nameId)
        _, _, sub.fps = rules.subscription(sub.resolution, sub.colorspace, frameRate)
        return True

    def setResolution(self, nameId: Any, resolution: Any) -> bool:
        """Change a subscriber's resolution; True."""
        sub = self._sub(nameId)
        res, _, _ = rules.subscription(resolution, sub.colorspace, sub.fps)
        self._check_resolution(res)
        sub.resolution = res
        return True

    def setColorSpace(self, nameId: Any, colorSpace: Any) -> bool:
        """Change a subscriber's colorspace; True."""
        sub = self._sub(nameId)
        _, sub.colorspace, _ = rules.subscription(sub.resolution, colorSpace, sub.fps)
        return True

    # ------------------------------------------------------------------ camera parameters
    def _param(self, parameter: Any) -> int:
        if (
            isinstance(parameter, bool)
            or not isinstance(parameter, int)
            or parameter not in CAMERA_PARAMETERS
        ):
            raise RobotError(
                f"unknown camera parameter id {parameter!r}; known: {sorted(CAMERA_PARAMETERS)}"
            )
        return int(parameter)

    def setParameter(self, cameraIndex: Any, parameter: Any, value: Any) -> bool:
        """Store a camera parameter (the simulated image ignores it); True."""
        camera = rules.camera_index(cameraIndex)
        if isinstance(value, bool) or not isinstance(value, int):
            raise RobotError(f"a camera parameter value is an int, got {value!r}")
        self.on_not_simulated("ALVideoDevice camera parameters (brightness, exposure...)")
        self._params[camera][self._param(parameter)] = int(value)
        return True

    def getParameter(self, cameraIndex: Any, parameter: Any) -> int:
        """A camera parameter's value (set, or NAOqi's default)."""
        return self._params[rules.camera_index(cameraIndex)][self._param(parameter)]

    def setCameraParameter(self, nameId: Any, parameter: Any, value: Any) -> bool:
        """setParameter on a subscriber's camera."""
        return self.setParameter(self._sub(nameId).camera, parameter, value)

    def getCameraParameter(self, nameId: Any, parameter: Any) -> int:
        """getParameter on a subscriber's camera."""
        return self.getParameter(self._sub(nameId).camera, parameter)

    def setAllParametersToDefaultValue(self, cameraIndex: Any) -> bool:
        """Reset a camera's parameters; True."""
        camera = rules.camera_index(cameraIndex)
        self._params[camera] = _defaults(camera)
        return True
