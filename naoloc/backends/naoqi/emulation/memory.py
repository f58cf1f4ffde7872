"""ALMemory of a served NAOqi: a key-value store, events, standard keys and joint keys."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any, Final

from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.constants import JOINT_NAMES
from naoloc.errors import RobotError

STATIC_KEYS: Final[dict[str, Any]] = {
    "robotHasFallen": 0,
    "robotIsFalling": 0,
    "ALMotion/RobotIsFalling": False,
    "ALMotion/MoveFailed": [],
    "FrontTactilTouched": 0.0,
    "MiddleTactilTouched": 0.0,
    "RearTactilTouched": 0.0,
    "HandLeftBackTouched": 0.0,
    "HandRightBackTouched": 0.0,
    "LeftBumperPressed": 0.0,
    "RightBumperPressed": 0.0,
    "ChestButtonPressed": 0.0,
    "WordRecognized": [],
    "LastWordRecognized": [],
    "SpeechDetected": 0,
    "ALTextToSpeech/TextDone": 1,
    "ALTextToSpeech/TextStarted": 0,
    "ALTextToSpeech/CurrentSentence": "",
    "Device/SubDeviceList/Battery/Charge/Sensor/Value": 1.0,
    "Device/SubDeviceList/Platform/ILS/Sensor/Value": 0.0,
    "RobotConfig/Body/Type": "nao",
}
_SENSOR = "Device/SubDeviceList/{}/Position/Sensor/Value"
_ACTUATOR = "Device/SubDeviceList/{}/Position/Actuator/Value"
_STIFFNESS = "Device/SubDeviceList/{}/Hardness/Actuator/Value"


class MemoryFront:
    """ALMemory: a key-value store, events, and live joint keys.

    Joint keys (``Device/SubDeviceList/<Joint>/Position/Sensor/Value``, ``.../Actuator/Value``,
    ``.../Hardness/Actuator/Value``) are read from the robot at each call. Events raised
    with ``raiseEvent`` or ``insertData`` reach every subscriber through ``emit``.

    Args:
        ctx: The host's context.
        joints: ``joints(names, use_sensors)`` -> angles (rad), from the motion front.
        stiffness: ``stiffness(names)`` -> stiffness in [0, 1].
    """

    def __init__(
        self,
        ctx: FrontContext,
        joints: Callable[[list[str], bool], list[float]],
        stiffness: Callable[[list[str]], list[float]],
    ) -> None:
        self._ctx = ctx
        self._lock = threading.Lock()
        self._data: dict[str, Any] = dict(STATIC_KEYS)
        self._events: set[str] = {"robotHasFallen", "ALMotion/MoveFailed", "WordRecognized"}
        self._joints = joints
        self._stiffness = stiffness
        self._listeners: list[Callable[[str, Any], None]] = []
        self._providers: list[tuple[tuple[str, ...], Callable[[str], Any]]] = []

    def add_provider(self, keys: tuple[str, ...], read: Callable[[str], Any]) -> None:
        """Serve ``keys`` live: ``read(key)`` answers getData (sensors of other fronts)."""
        self._providers.append((tuple(keys), read))

    def add_listener(self, listener: Callable[[str, Any], None]) -> None:
        """Call ``listener(key, value)`` on every event and data change."""
        self._listeners.append(listener)

    def _emit(self, key: str, value: Any) -> None:
        for listener in list(self._listeners):
            listener(key, value)

    def _live(self, key: str) -> tuple[bool, Any]:
        for keys, read in self._providers:
            if key in keys:
                return True, read(key)
        for template, kind in ((_SENSOR, "sensor"), (_ACTUATOR, "actuator"), (_STIFFNESS, "stiff")):
            prefix, _, suffix = template.partition("{}")
            if key.startswith(prefix) and key.endswith(suffix):
                joint = key[len(prefix) : len(key) - len(suffix)]
                if joint in JOINT_NAMES:
                    if kind == "stiff":
                        return True, float(self._stiffness([joint])[0])
                    return True, float(self._joints([joint], kind == "sensor")[0])
        return False, None

    def getData(self, key: Any, *deprecated: Any) -> Any:
        """The value of a key.

        Raises:
            RobotError: A key nobody inserted (as NAOqi raises).
        """
        if not isinstance(key, str):
            raise RobotError(f"a key is a string, got {key!r}")
        live, value = self._live(key)
        if live:
            return value
        with self._lock:
            if key not in self._data:
                raise RobotError(f"key {key!r} does not exist")
            return self._data[key]

    def getListData(self, keyList: Any) -> list[Any]:
        """Values of several keys (None for missing ones)."""
        out = []
        for key in list(keyList):
            try:
                out.append(self.getData(key))
            except RobotError:
                out.append(None)
        return out

    def insertData(self, key: Any, value: Any) -> None:
        """Store a value (subscribers of the key are told)."""
        if not isinstance(key, str) or not key:
            raise RobotError(f"a key is a non-empty string, got {key!r}")
        with self._lock:
            self._data[key] = value
        self._emit(key, value)

    def insertListData(self, list_: Any) -> None:
        """Store ``[[key, value], ...]``."""
        for item in list(list_):
            if not isinstance(item, list | tuple) or len(item) < 2:
                raise RobotError(f"insertListData takes [[key, value], ...], got {item!r}")
            self.insertData(item[0], item[1])

    def removeData(self, key: Any) -> None:
        """Forget a key."""
        with self._lock:
            self._data.pop(str(key), None)

    def raiseEvent(self, name: Any, value: Any) -> None:
        """Store ``value`` under ``name`` and tell every subscriber."""
        if not isinstance(name, str) or not name:
            raise RobotError(f"an event name is a non-empty string, got {name!r}")
        with self._lock:
            self._events.add(name)
        self.insertData(name, value)

    def raiseMicroEvent(self, name: Any, value: Any) -> None:
        """As raiseEvent."""
        self.raiseEvent(name, value)

    def declareEvent(self, eventName: Any) -> None:
        """Declare an event name."""
        with self._lock:
            self._events.add(str(eventName))
            self._data.setdefault(str(eventName), None)

    def getEventList(self) -> list[str]:
        """Declared event names."""
        with self._lock:
            return sorted(self._events)

    def getDataList(self, filter_: Any) -> list[str]:
        """Keys that contain ``filter`` (joint keys included)."""
        return [k for k in self.getDataListName() if str(filter_) in k]

    def getDataListName(self) -> list[str]:
        """Every key."""
        live = [t.format(j) for j in JOINT_NAMES for t in (_SENSOR, _ACTUATOR, _STIFFNESS)]
        live += [k for keys, _ in self._providers for k in keys]
        with self._lock:
            return sorted(set(self._data) | set(live))

    def getDataOnChange(self, key: Any, deprecatedParameter: Any) -> Any:
        """The key's value now (changes are delivered through subscriber signals)."""
        return self.getData(key)

    def subscriber(self, eventName: Any) -> Any:
        """Signals need an object-capable transport: libqi serves them (see libqi_transport)."""
        raise RobotError("subscriber signals are served over libqi; on this transport poll getData")

    def subscribeToEvent(self, name: Any, callbackModule: Any, callbackMethod: Any) -> None:
        """NAOqi 1 callbacks into a client module are not supported over this server."""
        raise RobotError(
            "subscribeToEvent needs a NAOqi 1 module; use ALMemory.subscriber(name).signal"
        )

    def unsubscribeToEvent(self, name: Any, callbackModule: Any) -> None:
        """See subscribeToEvent."""
        raise RobotError("unsubscribeToEvent: use the subscriber's signal.disconnect(link)")
