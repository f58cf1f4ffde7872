"""ALVideoDevice in front of a simulated camera: subscribers, parameters, the image array.

The front keeps NAOqi's subscriber bookkeeping (unique handles, the subscriber limit,
the deprecated ``subscribe`` on the active camera, frame rates 1-30, per-camera
parameters); the backend renders. Camera parameters (brightness, exposure...) are
stored and read back but do not change the simulated image.
"""

from __future__ import annotations

import contextlib
import threading
import time
from dataclasses import dataclass
from typing import Any, Final

from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.constants import kTopCamera
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


@dataclass
class Subscriber:
    """One subscriber: its backend handle, what the client asked for, and whose it is.

    ``orphaned`` is when its owner left (time.monotonic), None while the owner is
    connected; a client that names the handle adopts it (a reconnecting client).
    """

    backend_handle: str
    camera: int
    resolution: int
    colorspace: int
    fps: int
    owner: str = ""
    orphaned: float | None = None


class VideoFront:
    """ALVideoDevice with NAOqi's rules in front of a backend's ``video``.

    Args:
        backend: The backend's ALVideoDevice (fake or MuJoCo).
        ctx: The host's context.
    """

    def __init__(self, backend: Any, ctx: FrontContext) -> None:
        self._b = backend
        self._ctx = ctx
        self._lock = threading.Lock()
        self._subs: dict[str, Subscriber] = {}
        self._active = kTopCamera
        self._params: dict[int, dict[int, int]] = {
            0: dict(CAMERA_PARAMETERS),
            1: dict(CAMERA_PARAMETERS),
        }
        self._params[1][22] = 1

    def _run(self, method: str, *args: Any) -> Any:
        return self._ctx.run(getattr(self._b, method), *args)

    def _sub(self, nameId: Any) -> Subscriber:
        caller = self._ctx.caller
        with self._lock:
            sub = self._subs.get(nameId) if isinstance(nameId, str) else None
            if sub is not None and sub.orphaned is not None and caller:
                sub.owner, sub.orphaned = caller, None  # adopted (e.g. a reconnected client)
        if sub is None:
            raise HandleError(f"no camera subscriber named {nameId!r}")
        return sub

    def orphan(self, caller: str) -> int:
        """``caller`` left: its subscribers are released after a grace (see release_orphans)."""
        now = time.monotonic()
        with self._lock:
            subs = [s for s in self._subs.values() if s.owner == caller and s.orphaned is None]
            for sub in subs:
                sub.orphaned = now
        return len(subs)

    def release_orphans(self, older_than_s: float = 0.0) -> int:
        """Unsubscribe subscribers whose owner left more than ``older_than_s`` ago."""
        now = time.monotonic()
        with self._lock:
            gone = [
                (h, s) for h, s in self._subs.items()
                if s.orphaned is not None and now - s.orphaned >= older_than_s
            ]  # fmt: skip
            for handle, _ in gone:
                del self._subs[handle]
        for _, sub in gone:
            with contextlib.suppress(RobotError):
                self._run("unsubscribe", sub.backend_handle)
        return len(gone)

    def subscribeCamera(
        self, name: Any, cameraIndex: Any, resolution: Any, colorSpace: Any, fps: Any
    ) -> str:
        """Subscribe; returns ``name`` or ``name_<n>`` when taken.

        Raises:
            RobotError: Unknown camera, resolution or colorspace, fps outside 1-30, or
                too many subscribers.
        """
        if not isinstance(name, str) or not name:
            raise RobotError(f"subscriber name must be a non-empty string, got {name!r}")
        camera = rules.camera_index(cameraIndex)
        res, cs, rate = rules.subscription(resolution, colorSpace, fps)
        with self._lock:
            full = len(self._subs) >= rules.MAX_SUBSCRIBERS
        if full:  # subscribers of clients that left make room at once
            self.release_orphans()
        with self._lock:
            if len(self._subs) >= rules.MAX_SUBSCRIBERS:
                raise RobotError(
                    f"too many camera subscribers ({rules.MAX_SUBSCRIBERS}); unsubscribe some"
                )
            handle, n = name, 0
            while handle in self._subs:
                n += 1
                handle = f"{name}_{n}"
            self._subs[handle] = Subscriber("", camera, res, cs, rate, self._ctx.caller)
        try:
            backend = self._run("subscribeCamera", handle, camera, res, cs, rules.backend_fps(rate))
        except BaseException:
            with self._lock:
                self._subs.pop(handle, None)
            raise
        with self._lock:
            self._subs[handle].backend_handle = str(backend)
        return handle

    def subscribe(self, name: Any, resolution: Any, colorSpace: Any, fps: Any) -> str:
        """Deprecated NAOqi 1 form: subscribe to the active camera."""
        return self.subscribeCamera(name, self._active, resolution, colorSpace, fps)

    def unsubscribe(self, nameId: Any) -> bool:
        """Drop a subscriber; True when it existed."""
        with self._lock:
            sub = self._subs.pop(nameId, None) if isinstance(nameId, str) else None
        if sub is None:
            return False
        self._run("unsubscribe", sub.backend_handle)
        return True

    def getSubscribers(self) -> list[str]:
        """Handles of every subscriber."""
        with self._lock:
            return list(self._subs)

    def getImageRemote(self, nameId: Any) -> list[Any]:
        """The 12-item NAOqi image array (see ``naoloc.robot.image.Frame``)."""
        sub = self._sub(nameId)
        value = list(self._run("getImageRemote", sub.backend_handle))
        value[7] = sub.camera
        return value

    def getImageLocal(self, nameId: Any) -> Any:
        """Not available to a remote client (as on NAOqi)."""
        raise RobotError("getImageLocal only works inside NAOqi's process; use getImageRemote")

    def releaseImage(self, nameId: Any) -> bool:
        """Give the image back (nothing to do for remote images); True."""
        self._sub(nameId)
        return True

    def setActiveCamera(self, cameraIndex: Any) -> bool:
        """Select the camera of ``subscribe``; False for an index NAO does not have."""
        try:
            self._active = rules.camera_index(cameraIndex)
        except RobotError:
            return False
        return True

    def getActiveCamera(self) -> int:
        """The active camera's index."""
        return self._active

    def getHorizontalFOV(self, cameraIndex: Any) -> float:
        """Horizontal field of view, rad."""
        return float(self._run("getHorizontalFOV", rules.camera_index(cameraIndex)))

    def getVerticalFOV(self, cameraIndex: Any) -> float:
        """Vertical field of view, rad."""
        return float(self._run("getVerticalFOV", rules.camera_index(cameraIndex)))

    def getResolution(self, nameId: Any) -> int:
        """Resolution id of a subscriber."""
        return self._sub(nameId).resolution

    def getColorSpace(self, nameId: Any) -> int:
        """Colorspace id of a subscriber."""
        return self._sub(nameId).colorspace

    def getFrameRate(self, nameId: Any) -> int:
        """Frame rate asked for (1-30)."""
        return self._sub(nameId).fps

    def getCameraIndex(self, nameId: Any) -> int:
        """Camera of a subscriber."""
        return self._sub(nameId).camera

    def setFrameRate(self, nameId: Any, frameRate: Any) -> bool:
        """Change a subscriber's frame rate (1-30); True."""
        sub = self._sub(nameId)
        _, _, sub.fps = rules.subscription(sub.resolution, sub.colorspace, frameRate)
        return True

    def setResolution(self, nameId: Any, resolution: Any) -> bool:
        """Change a subscriber's resolution (re-subscribes in the backend); True."""
        return self._resubscribe(nameId, resolution=resolution)

    def setColorSpace(self, nameId: Any, colorSpace: Any) -> bool:
        """Change a subscriber's colorspace; True."""
        return self._resubscribe(nameId, colorspace=colorSpace)

    def _resubscribe(self, nameId: Any, **change: Any) -> bool:
        sub = self._sub(nameId)
        res = change.get("resolution", sub.resolution)
        cs = change.get("colorspace", sub.colorspace)
        res, cs, _ = rules.subscription(res, cs, sub.fps)
        new = self._run(
            "subscribeCamera", f"{nameId}~", sub.camera, res, cs, rules.backend_fps(sub.fps)
        )
        self._run("unsubscribe", sub.backend_handle)
        sub.backend_handle, sub.resolution, sub.colorspace = str(new), res, cs
        return True

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
        self._ctx.not_simulated("ALVideoDevice camera parameters (brightness, exposure...)")
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
        self._params[camera] = dict(CAMERA_PARAMETERS)
        self._params[camera][22] = camera
        return True

    def getCameraName(self, cameraIndex: Any) -> str:
        """ "CameraTop" or "CameraBottom"."""
        return ("CameraTop", "CameraBottom")[rules.camera_index(cameraIndex)]

    def isCameraOpen(self, cameraIndex: Any) -> bool:
        """Both simulated cameras are always open."""
        rules.camera_index(cameraIndex)
        return True

    def close_all(self) -> None:
        """Drop every subscriber (at shutdown)."""
        with self._lock:
            subs, self._subs = list(self._subs.values()), {}
        for sub in subs:
            with contextlib.suppress(RobotError):
                self._run("unsubscribe", sub.backend_handle)
