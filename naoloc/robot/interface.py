"""The robot interface: one Protocol per mirrored NAOqi service, and ``Robot`` bundling them.

Behaviours use only what is declared here, so the same code runs on the fake
backend, the MuJoCo simulator, a virtual NAOqi over the network and a real NAO.
Method names, arguments, units, return values and blocking behaviour mirror
NAOqi 2.x (ALMotion, ALVideoDevice, ALRobotPosture); camelCase is kept on purpose.

Simulated backends have no wall clock: time advances inside blocking calls by the
time the motion needs, and by one ALMotion cycle (20 ms) on every other call, so a
loop polling ``moveIsActive()`` makes progress exactly as it would on a robot.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

from naoloc.geometry import Pose2D

Names = str | Sequence[str]
Angles = float | Sequence[float]


@runtime_checkable
class Motion(Protocol):
    """The ALMotion subset naoloc uses. Velocities in FRAME_ROBOT; poses in FRAME_WORLD."""

    def wakeUp(self) -> None:
        """Motors on, initial posture; blocking."""
        ...

    def rest(self) -> None:
        """Safe crouch, motors off; blocking."""
        ...

    def robotIsWakeUp(self) -> bool:
        """True when the leg joints are stiff."""
        ...

    def setStiffnesses(self, names: Names, stiffnesses: Angles) -> None:
        """Set joint stiffness in [0, 1]; non-blocking."""
        ...

    def moveInit(self) -> None:
        """Take a walk-ready posture; blocking."""
        ...

    def moveTo(self, *args: Any, **kwargs: Any) -> bool:
        """``moveTo(x, y, theta)`` (m, m, rad; FRAME_ROBOT) or ``moveTo([[x, y, theta], ...])``.

        Blocks until the move ends; returns True when the target was reached.
        """
        ...

    def move(self, x: float, y: float, theta: float) -> None:
        """Walk at a velocity (m/s, m/s, rad/s; FRAME_ROBOT) until told otherwise; non-blocking."""
        ...

    def moveToward(self, x: float, y: float, theta: float) -> None:
        """Walk at a normalised velocity, each component in [-1, 1]; non-blocking."""
        ...

    def waitUntilMoveIsFinished(self) -> None:
        """Block until the current move task ends."""
        ...

    def moveIsActive(self) -> bool:
        """True while a move task runs."""
        ...

    def stopMove(self) -> None:
        """Stop walking safely."""
        ...

    def getRobotPosition(self, useSensors: bool) -> list[float]:
        """``[x, y, theta]`` in FRAME_WORLD (odometry); True = from sensors, False = commands."""
        ...

    def getNextRobotPosition(self) -> list[float]:
        """Where the current move will end, ``[x, y, theta]`` in FRAME_WORLD."""
        ...

    def getRobotVelocity(self) -> list[float]:
        """``[vx, vy, wz]`` in FRAME_ROBOT, m/s and rad/s."""
        ...

    def setAngles(self, names: Names, angles: Angles, fractionMaxSpeed: float) -> None:
        """Move joints toward angles (rad) at a fraction of max speed in (0, 1]; non-blocking."""
        ...

    def angleInterpolationWithSpeed(
        self, names: Names, targetAngles: Angles, maxSpeedFraction: float
    ) -> None:
        """Move joints to angles (rad) at a fraction of max speed; blocking."""
        ...

    def getAngles(self, names: Names, useSensors: bool) -> list[float]:
        """Joint angles in radians, in the order of the expanded names."""
        ...

    def getPosition(self, name: str, frame: int, useSensorValues: bool) -> list[float]:
        """``[x, y, z, wx, wy, wz]`` of an effector ("CameraTop", "Head", "Torso"...) in a frame.

        Frames FRAME_TORSO 0, FRAME_WORLD 1, FRAME_ROBOT 2; metres; roll-pitch-yaw radians
        (``wy > 0`` looks down).
        """
        ...

    def getTransform(self, name: str, frame: int, useSensorValues: bool) -> list[float]:
        """The effector's 4x4 transform in a frame, 16 floats row-major (metres)."""
        ...


@runtime_checkable
class VideoDevice(Protocol):
    """The ALVideoDevice subset naoloc uses."""

    def subscribeCamera(
        self, name: str, cameraIndex: int, resolution: int, colorSpace: int, fps: int
    ) -> str:
        """Subscribe and return a handle (a name unique among subscribers)."""
        ...

    def unsubscribe(self, nameId: str) -> bool:
        """Drop a subscription; True when it existed."""
        ...

    def getImageRemote(self, nameId: str) -> list[Any]:
        """The NAOqi image array (see :class:`naoloc.robot.image.Frame`)."""
        ...

    def releaseImage(self, nameId: str) -> bool:
        """Give the image buffer back (a no-op for remote images); True."""
        ...

    def setActiveCamera(self, cameraIndex: int) -> bool:
        """Select the camera used by subscribers made without an explicit index."""
        ...

    def getActiveCamera(self) -> int:
        """Index of the active camera."""
        ...

    def getHorizontalFOV(self, cameraIndex: int) -> float:
        """Horizontal field of view in radians."""
        ...

    def getVerticalFOV(self, cameraIndex: int) -> float:
        """Vertical field of view in radians."""
        ...

    def getResolution(self, nameId: str) -> int:
        """Resolution id of a subscription."""
        ...

    def getColorSpace(self, nameId: str) -> int:
        """Colorspace id of a subscription."""
        ...


@runtime_checkable
class Posture(Protocol):
    """The ALRobotPosture subset naoloc uses."""

    def goToPosture(self, postureName: str, maxSpeedFraction: float) -> bool:
        """Go to a named posture; blocking; True when reached."""
        ...

    def getPosture(self) -> str:
        """Name of the current posture, or "Unknown"."""
        ...

    def getPostureList(self) -> list[str]:
        """Names of the predefined postures."""
        ...

    def stopMove(self) -> None:
        """Stop a posture change."""
        ...


@runtime_checkable
class SimControl(Protocol):
    """What only a simulator knows: ground truth and teleport, in the room frame.

    Room frame: origin at a room corner, x and y along the walls, metres and radians.
    """

    def true_pose(self) -> tuple[float, float, float]:
        """Ground-truth ``(x, y, theta)`` of the robot (FRAME_ROBOT origin), room frame."""
        ...

    def teleport(self, x: float, y: float, theta: float) -> None:
        """Put the robot at ``(x, y, theta)`` in the room frame; odometry is not told."""
        ...

    def room_size(self) -> tuple[float, float]:
        """Inner size of the room ``(x, y)`` in metres."""
        ...

    def is_free(self, x: float, y: float, clearance: float) -> bool:
        """True when a disc of ``clearance`` m at ``(x, y)`` touches no wall or furniture."""
        ...

    def sim_time(self) -> float:
        """Simulated seconds since the backend started."""
        ...

    def true_camera_pose(self, camera_index: int = 0) -> list[float]:
        """True ``[x, y, z, wx, wy, wz]`` of a camera (NAOqi camera frame), room frame.

        Metres; angles as ALMotion.getPosition gives them (``wy > 0`` looks down).
        """
        ...


@dataclass
class Robot:
    """A robot as a bundle of NAOqi services, plus ``sim`` on simulators.

    Use it as a context manager; leaving the block stops any motion and closes
    the backend. ``close()`` is idempotent.

    Attributes:
        motion: ALMotion.
        video: ALVideoDevice.
        posture: ALRobotPosture.
        sim: Ground truth and teleport on simulators; None on a real robot.
        backend: Name of the backend ("fake", "mujoco", "naoqi").
        info: Backend facts worth logging (model, room, transport, ...).
        read: On a network robot, a read of another NAOqi service:
            ``read(service, method, *args)`` (e.g. ``("ALBattery", "getBatteryCharge")``);
            None on in-process backends.
    """

    motion: Motion
    video: VideoDevice
    posture: Posture
    sim: SimControl | None = None
    backend: str = "unknown"
    info: dict[str, Any] = field(default_factory=dict)
    read: Callable[..., Any] | None = field(default=None, repr=False)
    _closer: Callable[[], None] | None = field(default=None, repr=False)
    _closed: bool = field(default=False, repr=False)

    @property
    def closed(self) -> bool:
        """True once :meth:`close` ran."""
        return self._closed

    def close(self) -> None:
        """Stop any motion (best effort) and release the backend. Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        with contextlib.suppress(Exception):
            self.motion.stopMove()
        if self._closer is not None:
            self._closer()

    def __enter__(self) -> Robot:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def expand_joint_names(names: Names) -> list[str]:
    """Expand a joint, a chain ("Head", "LArm"...), a group ("Body", "JointActuators"...) or a list.

    Raises:
        RobotError: For a name that is neither a joint nor a chain or group.
    """
    from naoloc.robot.rules import expand_names

    return expand_names(names)


def pose_of(motion: Motion, use_sensors: bool = True) -> Pose2D:
    """``motion.getRobotPosition(use_sensors)`` as a :class:`Pose2D`."""
    return Pose2D.from_list(motion.getRobotPosition(use_sensors))
