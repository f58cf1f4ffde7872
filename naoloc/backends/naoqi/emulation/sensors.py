"""ALSonar and the inertial unit of a served NAOqi, from the simulator's ground truth.

**ALSonar.** A NAO has two chest sonars looking 25 degrees to each side, each with a
cone of +-30 degrees. While at least one client is subscribed (``ALSonar.subscribe``,
as on a NAO, where the values only refresh then) every :data:`SONAR_PERIOD_S` the
nearest wall or furniture inside each cone is found by casting rays in the room
(``SimControl.is_free``, the simulator's own collision model, from the robot's true
pose), written to ``Device/SubDeviceList/US/{Left,Right}/Sensor/Value`` (m) and, on
crossing :data:`DETECTION_M`, raised as ``SonarLeftDetected`` / ``SonarRightDetected``
and ``SonarLeftNothingDetected`` / ``SonarRightNothingDetected``. Nothing within
:data:`SONAR_RANGE_M` reads as that range. The rays are 2D: an obstacle at any height is
seen (a real sonar misses thin or high ones).

**Inertial unit.** ``Device/SubDeviceList/InertialSensor/<K>/Sensor/Value`` for
AngleX/Y/Z (rad, the torso's roll, pitch and yaw from ALMotion's torso pose in
FRAME_WORLD), GyrX/Y/Z (rad/s, the change of those angles between reads) and
AccX/Y/Z (m/s^2: gravity in the torso frame, ``AccZ`` about -9.81 upright, as a NAO
reports; the body's own acceleration is not added).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any, Final

from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.errors import RobotError

SONAR_PERIOD_S: Final = 0.1  # NAOqi's default sonar refresh
SONAR_RANGE_M: Final = 5.0  # reading when nothing is in range
SONAR_MIN_M: Final = 0.25  # nearer than this the sonar cannot measure; it reads this
DETECTION_M: Final = 0.5  # SonarXDetected under this distance
SONAR_YAW: Final = math.radians(25.0)  # each sonar's axis from the robot's x axis
SONAR_HALF_CONE: Final = math.radians(30.0)
SONAR_OFFSET_M: Final = 0.05  # sonar ahead of the robot's origin
_RAYS: Final = 5  # per cone
_STEP_M: Final = 0.05  # ray marching step (then refined by bisection)
SONAR_KEYS: Final = {
    "Left": "Device/SubDeviceList/US/Left/Sensor/Value",
    "Right": "Device/SubDeviceList/US/Right/Sensor/Value",
}
INERTIAL_KEYS: Final = tuple(
    f"Device/SubDeviceList/InertialSensor/{k}/Sensor/Value"
    for k in ("AngleX", "AngleY", "AngleZ", "GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ")
)
GRAVITY: Final = 9.81


def sonar_distance(
    is_free: Callable[[float, float, float], bool],
    pose: tuple[float, float, float],
    yaw: float,
) -> float:
    """Distance (m) to the nearest obstacle in a sonar's cone, or :data:`SONAR_RANGE_M`.

    Args:
        is_free: ``is_free(x, y, clearance)`` of the room (room frame, m).
        pose: The robot's true ``(x, y, theta)`` (room frame).
        yaw: The sonar's axis relative to the robot's x axis (rad).
    """
    x, y, theta = pose
    ox, oy = x + SONAR_OFFSET_M * math.cos(theta), y + SONAR_OFFSET_M * math.sin(theta)
    best = SONAR_RANGE_M
    for k in range(_RAYS):
        angle = theta + yaw + SONAR_HALF_CONE * (2.0 * k / (_RAYS - 1) - 1.0)
        c, s = math.cos(angle), math.sin(angle)
        d = _STEP_M
        while d < best:
            if not is_free(ox + d * c, oy + d * s, 0.005):
                lo, hi = d - _STEP_M, d  # refine to a few millimetres
                for _ in range(4):
                    mid = 0.5 * (lo + hi)
                    lo, hi = (mid, hi) if is_free(ox + mid * c, oy + mid * s, 0.005) else (lo, mid)
                best = hi
                break
            d += _STEP_M
    return max(SONAR_MIN_M, best) if best < SONAR_RANGE_M else SONAR_RANGE_M


class SonarFront:
    """ALSonar: subscribe / unsubscribe (ALExtractor's API); values in ALMemory.

    Args:
        ctx: The host's context.
        sim: The robot's SimControl (true pose, ``is_free``).
        memory: The served ALMemory (``insertData``, ``raiseEvent``).
    """

    def __init__(self, ctx: FrontContext, sim: Any, memory: Any) -> None:
        self._ctx, self._sim, self._memory = ctx, sim, memory
        self._lock = threading.Lock()
        self._subscribers: dict[str, int] = {}
        self._period_ms = int(SONAR_PERIOD_S * 1000)
        self._near = {"Left": False, "Right": False}
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        for key in SONAR_KEYS.values():
            memory.insertData(key, SONAR_RANGE_M)

    def subscribe(self, name: Any, *period_precision: Any) -> None:
        """Start the sonars for ``name`` (optionally with a period in ms and a precision)."""
        if not isinstance(name, str) or not name:
            raise RobotError(f"a subscriber name is a non-empty string, got {name!r}")
        with self._lock:
            self._subscribers[name] = int(period_precision[0]) if period_precision else 100
            start = self._thread is None
            if start:
                self._stop.clear()
                self._thread = threading.Thread(target=self._run, name="naoloc-sonar", daemon=True)
        if start and self._thread is not None:
            self._thread.start()

    def unsubscribe(self, name: Any) -> None:
        """Stop ``name``'s subscription (the sonars stop with the last one)."""
        with self._lock:
            if self._subscribers.pop(str(name), None) is None:
                raise RobotError(f"ALSonar has no subscriber {name!r}")
            last = not self._subscribers
        if last:
            self.close()

    def getSubscribersInfo(self) -> list[list[Any]]:
        """``[[name, period ms, precision], ...]``."""
        with self._lock:
            return [[n, p, 1.0] for n, p in self._subscribers.items()]

    def getCurrentPeriod(self) -> int:
        """The refresh period, ms."""
        return self._period_ms

    def getCurrentPrecision(self) -> float:
        """The precision (always 1)."""
        return 1.0

    def getMyPeriod(self, name: Any) -> int:
        """A subscriber's period, ms."""
        with self._lock:
            return self._subscribers.get(str(name), self._period_ms)

    def getOutputNames(self) -> list[str]:
        """The ALMemory keys the sonars write."""
        return list(SONAR_KEYS.values())

    def getEventList(self) -> list[str]:
        """The events ALSonar raises."""
        return [f"Sonar{s}{w}Detected" for s in ("Left", "Right") for w in ("", "Nothing")]

    def measure(self) -> dict[str, float]:
        """One reading of both sonars (m), written to ALMemory with its events."""
        pose = tuple(float(v) for v in self._ctx.run(self._sim.true_pose))
        out = {}
        for side, sign in (("Left", 1.0), ("Right", -1.0)):
            d = float(self._ctx.run(sonar_distance, self._sim.is_free, pose, sign * SONAR_YAW))
            out[side] = d
            self._memory.insertData(SONAR_KEYS[side], d)
            near = d < DETECTION_M
            if near != self._near[side]:
                self._near[side] = near
                event = f"Sonar{side}Detected" if near else f"Sonar{side}NothingDetected"
                self._memory.raiseEvent(event, d)
        return out

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self.measure()
            except Exception as err:  # the robot closed: stop quietly
                self._ctx.log(f"naoloc serve: ALSonar stopped: {err}")
                return
            wall_floor = 0.05 * self._ctx.speed  # at most 20 readings per wall second
            self._ctx.sleep_sim(max(SONAR_PERIOD_S, wall_floor), self._stop)

    def close(self) -> None:
        """Stop the sonar thread."""
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=2.0)


class InertialUnit:
    """The inertial ALMemory keys, read from the torso's pose at each getData.

    Args:
        torso: ``torso()`` -> ``[x, y, z, wx, wy, wz]`` of the torso in FRAME_WORLD.
        speed: Simulated seconds per wall second (gyro rates are per simulated second).
    """

    def __init__(self, torso: Callable[[], list[float]], speed: float = 1.0) -> None:
        self._torso = torso
        self._speed = speed
        self._lock = threading.Lock()
        self._last: tuple[float, float, float, float] | None = None

    def read(self, key: str) -> float:
        """The value of one inertial key."""
        name = key.split("/")[3]
        _, _, _, wx, wy, wz = (float(v) for v in self._torso())
        now = time.monotonic()
        with self._lock:
            last, self._last = self._last, (now, wx, wy, wz)
        if name.startswith("Angle"):
            return {"AngleX": wx, "AngleY": wy, "AngleZ": wz}[name]
        if name.startswith("Gyr"):
            if last is None or now - last[0] > 1.0 or now <= last[0]:
                return 0.0
            dt = (now - last[0]) * self._speed
            index = {"GyrX": 1, "GyrY": 2, "GyrZ": 3}[name]
            delta = (wx, wy, wz)[index - 1] - last[index]
            return math.atan2(math.sin(delta), math.cos(delta)) / dt
        cx, sx, cy, sy = math.cos(wx), math.sin(wx), math.cos(wy), math.sin(wy)
        # gravity (0, 0, -g) seen from the torso: R^T g with R = Rz(wz) Ry(wy) Rx(wx)
        return {"AccX": GRAVITY * sy, "AccY": -GRAVITY * cy * sx, "AccZ": -GRAVITY * cy * cx}[name]
