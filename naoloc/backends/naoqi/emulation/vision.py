"""ALFaceDetection, ALTracker and ALLandMarkDetection of a served NAOqi: stand-ins.

The simulated rooms have no people and carry no NAOmarks, so these services never see
anything, as a NAO in an empty room would not: they take NAOqi's calls, keep their
settings, and write what NAOqi writes when nothing is seen (``FaceDetected`` and
``LandmarkDetected`` are ``[]``; ALTracker's target is lost). Their events are never
raised. ``ALTracker.lookAt`` is real: it turns the head toward a point.
"""

from __future__ import annotations

import math
import threading
from typing import Any, Final

from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.constants import FRAME_ROBOT, FRAME_TORSO, FRAME_WORLD
from naoloc.errors import RobotError

TRACKER_MODES: Final = ("Head", "WholeBody", "Move")
TARGETS: Final = ("RedBall", "Face", "LandMark", "LandMarks", "People", "Sound")
HEAD_YAW_LIMIT: Final = 2.0857
HEAD_PITCH_LIMITS: Final = (-0.672, 0.5149)


class _Extractor:
    """ALExtractor's subscribe/unsubscribe bookkeeping, with its ALMemory output key."""

    def __init__(self, ctx: FrontContext, memory: Any, name: str, key: str) -> None:
        self._ctx, self._memory, self._name, self._key = ctx, memory, name, key
        self._lock = threading.Lock()
        self._subscribers: dict[str, int] = {}
        memory.insertData(key, [])

    def subscribe(self, name: Any, *period_precision: Any) -> None:
        """Start detecting for ``name`` (period ms and precision are stored)."""
        if not isinstance(name, str) or not name:
            raise RobotError(f"a subscriber name is a non-empty string, got {name!r}")
        self._ctx.not_simulated(f"{self._name} (no {self._what()} in the simulated rooms)")
        with self._lock:
            self._subscribers[name] = int(period_precision[0]) if period_precision else 500
        self._memory.insertData(self._key, [])

    def unsubscribe(self, name: Any) -> None:
        """Stop ``name``'s subscription."""
        with self._lock:
            if self._subscribers.pop(str(name), None) is None:
                raise RobotError(f"{self._name} has no subscriber {name!r}")

    def getSubscribersInfo(self) -> list[list[Any]]:
        """``[[name, period ms, precision], ...]``."""
        with self._lock:
            return [[n, p, 1.0] for n, p in self._subscribers.items()]

    def updatePeriod(self, name: Any, period: Any) -> None:
        """Change a subscriber's period (ms)."""
        with self._lock:
            if str(name) not in self._subscribers:
                raise RobotError(f"{self._name} has no subscriber {name!r}")
            self._subscribers[str(name)] = int(period)

    def getCurrentPeriod(self) -> int:
        """The fastest subscriber's period, ms."""
        with self._lock:
            return min(self._subscribers.values(), default=500)

    def getOutputNames(self) -> list[str]:
        """The ALMemory key it writes."""
        return [self._key]

    def _what(self) -> str:
        return "faces" if "Face" in self._name else "NAOmarks"


class FaceDetectionFront(_Extractor):
    """ALFaceDetection: never detects a face (``FaceDetected`` stays ``[]``)."""

    def __init__(self, ctx: FrontContext, memory: Any) -> None:
        super().__init__(ctx, memory, "ALFaceDetection", "FaceDetected")
        self._tracking = False
        self._recognition = True

    def setTrackingEnabled(self, enabled: Any) -> None:
        """Whether the head follows a detected face (stored)."""
        self._tracking = bool(enabled)

    def isTrackingEnabled(self) -> bool:
        """The tracking flag."""
        return self._tracking

    def setRecognitionEnabled(self, enabled: Any) -> None:
        """Whether detected faces are recognised (stored)."""
        self._recognition = bool(enabled)

    def isRecognitionEnabled(self) -> bool:
        """The recognition flag."""
        return self._recognition

    def learnFace(self, name: Any) -> bool:
        """False: no face is in view to learn."""
        return False

    def reLearnFace(self, name: Any) -> bool:
        """False: no face is in view."""
        return False

    def forgetPerson(self, name: Any) -> bool:
        """False: nobody was learned."""
        return False

    def clearDatabase(self) -> bool:
        """True (the database is empty)."""
        return True

    def getLearnedFacesList(self) -> list[str]:
        """``[]``."""
        return []


class LandMarkDetectionFront(_Extractor):
    """ALLandMarkDetection: the rooms carry no NAOmarks (``LandmarkDetected`` stays ``[]``)."""

    def __init__(self, ctx: FrontContext, memory: Any) -> None:
        super().__init__(ctx, memory, "ALLandMarkDetection", "LandmarkDetected")


class TrackerFront:
    """ALTracker: targets are registered but never found; ``lookAt`` turns the head.

    Args:
        ctx: The host's context.
        motion: The served ALMotion front.
    """

    def __init__(self, ctx: FrontContext, motion: Any) -> None:
        self._ctx, self._motion = ctx, motion
        self._targets: dict[str, Any] = {}
        self._active = ""
        self._mode = "Head"
        self._max_distance = 2.0

    def registerTarget(self, target: Any, param: Any) -> None:
        """Register a target kind ("Face", "RedBall", "LandMark"...) with its parameter."""
        if target not in TARGETS:
            raise RobotError(f"unknown target {target!r}; valid: {', '.join(TARGETS)}")
        self._targets[str(target)] = param

    def unregisterTarget(self, target: Any) -> None:
        """Forget a target kind."""
        self._targets.pop(str(target), None)

    def unregisterAllTargets(self) -> None:
        """Forget every target."""
        self._targets.clear()

    def getRegisteredTargets(self) -> list[str]:
        """The registered target kinds."""
        return list(self._targets)

    def getSupportedTargets(self) -> list[str]:
        """Every target kind."""
        return list(TARGETS)

    def track(self, target: Any) -> None:
        """Start tracking a registered target (it is never found here)."""
        if target not in self._targets:
            raise RobotError(f"target {target!r} is not registered; registerTarget first")
        self._ctx.not_simulated("ALTracker tracking (no faces, balls or marks in the rooms)")
        self._active = str(target)

    def trackEvent(self, eventName: Any) -> None:
        """Track what an event reports (never raised here)."""
        self._active = str(eventName)

    def stopTracker(self) -> None:
        """Stop tracking."""
        self._active = ""

    def isActive(self) -> bool:
        """True while a track was asked for."""
        return bool(self._active)

    def getActiveTarget(self) -> str:
        """The tracked target ("" when none)."""
        return self._active

    def isNewTargetDetected(self) -> bool:
        """False: nothing is ever detected."""
        return False

    def isTargetLost(self) -> bool:
        """True: the target is never in view."""
        return True

    def getTargetPosition(self, *frame: Any) -> list[float]:
        """``[]``: no target position is known."""
        return []

    def setMode(self, mode: Any) -> None:
        """ "Head", "WholeBody" or "Move"."""
        if mode not in TRACKER_MODES:
            raise RobotError(f"unknown mode {mode!r}; valid: {', '.join(TRACKER_MODES)}")
        self._mode = str(mode)

    def getMode(self) -> str:
        """The tracking mode."""
        return self._mode

    def setMaximumDistanceDetection(self, distance: Any) -> None:
        """Farthest target distance (m, stored)."""
        self._max_distance = float(distance)

    def getMaximumDistanceDetection(self) -> float:
        """Farthest target distance, m."""
        return self._max_distance

    def lookAt(self, position: Any, frame: Any, fractionMaxSpeed: Any, useWholeBody: Any) -> None:
        """Turn the head toward ``[x, y, z]`` (m) in FRAME_TORSO, FRAME_WORLD or FRAME_ROBOT."""
        try:
            x, y, z = (float(v) for v in position)
        except (TypeError, ValueError):
            raise RobotError(f"position must be [x, y, z], got {position!r}") from None
        if frame not in (FRAME_TORSO, FRAME_WORLD, FRAME_ROBOT):
            raise RobotError(f"frame must be 0 (torso), 1 (world) or 2 (robot), got {frame!r}")
        head = self._motion.getPosition("Head", int(frame), True)
        dx, dy, dz = x - head[0], y - head[1], z - head[2]
        yaw = math.atan2(dy, dx)
        if frame == FRAME_WORLD:  # the head turns relative to the robot's heading
            yaw -= float(self._motion.getRobotPosition(True)[2])
        yaw = math.atan2(math.sin(yaw), math.cos(yaw))
        yaw = max(-HEAD_YAW_LIMIT, min(HEAD_YAW_LIMIT, yaw))
        pitch = -math.atan2(dz, math.hypot(dx, dy))
        pitch = max(HEAD_PITCH_LIMITS[0], min(HEAD_PITCH_LIMITS[1], pitch))
        self._motion.angleInterpolationWithSpeed(
            ["HeadYaw", "HeadPitch"], [yaw, pitch], fractionMaxSpeed
        )

    def pointAt(self, effector: Any, position: Any, frame: Any, fractionMaxSpeed: Any) -> None:
        """Not simulated (no arm inverse kinematics): accepted, the arm does not move."""
        self._ctx.not_simulated("ALTracker.pointAt (arm inverse kinematics)")
