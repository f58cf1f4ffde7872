"""Service proxies mirroring naoloc.robot's Protocols over a :class:`~.client.Link`.

Same method names, arguments, units and return values as NAOqi (camelCase on
purpose). Non-blocking calls wait at most ``robot.timeout_s``; blocking motion calls
(``moveTo``, ``goToPosture``...) at most ``robot.move_timeout_s``. Reads that can be
repeated safely are marked idempotent (retried once after a reconnect).
"""

from __future__ import annotations

from typing import Any

from naoloc.backends.naoqi.client import Link
from naoloc.backends.naoqi.signatures import MOTION, POSTURE, SIM, VIDEO
from naoloc.errors import RobotError
from naoloc.robot import Angles, Names
from naoloc.robot.image import frame_bytes


def _floats(value: Any) -> list[float]:
    return [float(v) for v in value]


class _Remote:
    def __init__(self, link: Link, timeout_s: float, move_timeout_s: float) -> None:
        self._link = link
        self._timeout = timeout_s
        self._move_timeout = move_timeout_s

    def _call(self, service: str, method: str, *args: Any, read: bool = False) -> Any:
        return self._link.call(service, method, *args, timeout_s=self._timeout, idempotent=read)

    def _block(self, service: str, method: str, *args: Any) -> Any:
        return self._link.call(service, method, *args, timeout_s=self._move_timeout)


class RemoteMotion(_Remote):
    """ALMotion over the network (see :class:`naoloc.robot.Motion`)."""

    def wakeUp(self) -> None:
        self._block(MOTION, "wakeUp")

    def rest(self) -> None:
        self._block(MOTION, "rest")

    def robotIsWakeUp(self) -> bool:
        return bool(self._call(MOTION, "robotIsWakeUp", read=True))

    def setStiffnesses(self, names: Names, stiffnesses: Angles) -> None:
        self._call(MOTION, "setStiffnesses", _plain(names), _plain(stiffnesses))

    def moveInit(self) -> None:
        self._block(MOTION, "moveInit")

    def moveTo(self, *args: Any, **kwargs: Any) -> bool:
        if kwargs:
            raise RobotError(f"moveTo takes positional arguments only, got {sorted(kwargs)}")
        if len(args) in (3, 4):
            xyz = [float(a) for a in args[:3]]
            return bool(self._block(MOTION, "moveTo", *xyz, *[_config(a) for a in args[3:]]))
        if len(args) in (1, 2):
            points = [[float(v) for v in p] for p in args[0]]
            return bool(self._block(MOTION, "moveTo", points, *[_config(a) for a in args[1:]]))
        raise RobotError(
            "moveTo takes (x, y, theta[, moveConfig]) or ([[x, y, theta], ...][, moveConfig])"
        )

    def move(self, x: float, y: float, theta: float) -> None:
        self._call(MOTION, "move", float(x), float(y), float(theta))

    def moveToward(self, x: float, y: float, theta: float) -> None:
        self._call(MOTION, "moveToward", float(x), float(y), float(theta))

    def waitUntilMoveIsFinished(self) -> None:
        self._block(MOTION, "waitUntilMoveIsFinished")

    def moveIsActive(self) -> bool:
        return bool(self._call(MOTION, "moveIsActive", read=True))

    def stopMove(self) -> None:
        self._call(MOTION, "stopMove")

    def getRobotPosition(self, useSensors: bool) -> list[float]:
        return _floats(self._call(MOTION, "getRobotPosition", bool(useSensors), read=True))

    def getNextRobotPosition(self) -> list[float]:
        return _floats(self._call(MOTION, "getNextRobotPosition", read=True))

    def getRobotVelocity(self) -> list[float]:
        return _floats(self._call(MOTION, "getRobotVelocity", read=True))

    def setAngles(self, names: Names, angles: Angles, fractionMaxSpeed: float) -> None:
        self._call(MOTION, "setAngles", _plain(names), _plain(angles), float(fractionMaxSpeed))

    def angleInterpolationWithSpeed(
        self, names: Names, targetAngles: Angles, maxSpeedFraction: float
    ) -> None:
        self._block(
            MOTION,
            "angleInterpolationWithSpeed",
            _plain(names),
            _plain(targetAngles),
            float(maxSpeedFraction),
        )

    def getAngles(self, names: Names, useSensors: bool) -> list[float]:
        return _floats(self._call(MOTION, "getAngles", _plain(names), bool(useSensors), read=True))

    def getPosition(self, name: str, frame: int, useSensorValues: bool) -> list[float]:
        args = (str(name), int(frame), bool(useSensorValues))
        return _floats(self._call(MOTION, "getPosition", *args, read=True))

    def getTransform(self, name: str, frame: int, useSensorValues: bool) -> list[float]:
        args = (str(name), int(frame), bool(useSensorValues))
        return _floats(self._call(MOTION, "getTransform", *args, read=True))


class RemoteVideo(_Remote):
    """ALVideoDevice over the network (see :class:`naoloc.robot.VideoDevice`)."""

    def subscribeCamera(
        self, name: str, cameraIndex: int, resolution: int, colorSpace: int, fps: int
    ) -> str:
        args = (str(name), int(cameraIndex), int(resolution), int(colorSpace), int(fps))
        return str(self._call(VIDEO, "subscribeCamera", *args))

    def unsubscribe(self, nameId: str) -> bool:
        return bool(self._call(VIDEO, "unsubscribe", str(nameId)))

    def getImageRemote(self, nameId: str) -> list[Any]:
        value = self._call(VIDEO, "getImageRemote", str(nameId), read=True)
        if value is None or len(value) < 12:
            raise RobotError("getImageRemote returned no image (is the camera subscribed?)")
        frame = list(value)
        frame[6] = frame_bytes(frame[6])
        return frame

    def releaseImage(self, nameId: str) -> bool:
        return bool(self._call(VIDEO, "releaseImage", str(nameId)))

    def setActiveCamera(self, cameraIndex: int) -> bool:
        return bool(self._call(VIDEO, "setActiveCamera", int(cameraIndex)))

    def getActiveCamera(self) -> int:
        return int(self._call(VIDEO, "getActiveCamera", read=True))

    def getHorizontalFOV(self, cameraIndex: int) -> float:
        return float(self._call(VIDEO, "getHorizontalFOV", int(cameraIndex), read=True))

    def getVerticalFOV(self, cameraIndex: int) -> float:
        return float(self._call(VIDEO, "getVerticalFOV", int(cameraIndex), read=True))

    def getResolution(self, nameId: str) -> int:
        return int(self._call(VIDEO, "getResolution", str(nameId), read=True))

    def getColorSpace(self, nameId: str) -> int:
        return int(self._call(VIDEO, "getColorSpace", str(nameId), read=True))


class RemotePosture(_Remote):
    """ALRobotPosture over the network (see :class:`naoloc.robot.Posture`)."""

    def goToPosture(self, postureName: str, maxSpeedFraction: float) -> bool:
        return bool(self._block(POSTURE, "goToPosture", str(postureName), float(maxSpeedFraction)))

    def getPosture(self) -> str:
        return str(self._call(POSTURE, "getPosture", read=True))

    def getPostureList(self) -> list[str]:
        return [str(p) for p in self._call(POSTURE, "getPostureList", read=True)]

    def stopMove(self) -> None:
        self._call(POSTURE, "stopMove")


class RemoteSim(_Remote):
    """The virtual NAOqi's NaolocSim service (see :class:`naoloc.robot.SimControl`)."""

    def true_pose(self) -> tuple[float, float, float]:
        x, y, theta = _floats(self._call(SIM, "true_pose", read=True))
        return (x, y, theta)

    def teleport(self, x: float, y: float, theta: float) -> None:
        self._call(SIM, "teleport", float(x), float(y), float(theta))

    def room_size(self) -> tuple[float, float]:
        sx, sy = _floats(self._call(SIM, "room_size", read=True))
        return (sx, sy)

    def is_free(self, x: float, y: float, clearance: float) -> bool:
        return bool(self._call(SIM, "is_free", float(x), float(y), float(clearance), read=True))

    def sim_time(self) -> float:
        return float(self._call(SIM, "sim_time", read=True))

    def true_camera_pose(self, camera_index: int = 0) -> list[float]:
        return _floats(self._call(SIM, "true_camera_pose", int(camera_index), read=True))


def _plain(value: Any) -> Any:
    """Names or angles as str, float or a list of them (what the wire carries)."""
    if isinstance(value, str):
        return value
    if isinstance(value, int | float):
        return float(value)
    return [v if isinstance(v, str) else float(v) for v in value]


def _config(value: Any) -> list[list[Any]]:
    """A moveConfig as ``[[name, value], ...]`` (what the wire carries)."""
    pairs = value.items() if isinstance(value, dict) else value
    return [[str(k), float(v)] for k, v in pairs]
