"""The companion services of a served NAOqi: ALMemory, speech, LEDs, touch, life, system.

What a script reads and writes is kept and answered with NAOqi's types; what needs a
body naoloc does not simulate says so once in the server's log: no audio (speech is
timed and logged, recognition never hears a word), LEDs change state but nothing
lights, touch sensors and bumpers are never touched, the battery stays full.
"""

from __future__ import annotations

import re
import threading
from collections.abc import Callable
from typing import Any, Final

from naoloc.constants import JOINT_NAMES
from naoloc.errors import RobotError
from naoloc.naoqi import rules
from naoloc.naoqi.context import FrontContext

LANGUAGES: Final = ("English", "French", "German", "Spanish", "Italian", "Japanese", "Chinese")
SECONDS_PER_WORD: Final = 0.4  # about 150 words a minute, NAO's default speech rate
TOUCH_SENSORS: Final = (
    "Head/Touch/Front", "Head/Touch/Middle", "Head/Touch/Rear",
    "LHand/Touch/Back", "LHand/Touch/Left", "LHand/Touch/Right",
    "RHand/Touch/Back", "RHand/Touch/Left", "RHand/Touch/Right",
    "LFoot/Bumper/Left", "LFoot/Bumper/Right", "RFoot/Bumper/Left", "RFoot/Bumper/Right",
    "ChestBoard/Button",
)  # fmt: skip
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

    def add_listener(self, listener: Callable[[str, Any], None]) -> None:
        """Call ``listener(key, value)`` on every event and data change."""
        self._listeners.append(listener)

    def _emit(self, key: str, value: Any) -> None:
        for listener in list(self._listeners):
            listener(key, value)

    def _live(self, key: str) -> tuple[bool, Any]:
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


class TextToSpeechFront:
    """ALTextToSpeech: ``say`` blocks for a plausible speaking time and logs the text.

    Args:
        ctx: The host's context.
        memory: ALMemory, for the TextStarted / TextDone / CurrentSentence keys.
    """

    def __init__(self, ctx: FrontContext, memory: MemoryFront) -> None:
        self._ctx = ctx
        self._memory = memory
        self._language = "English"
        self._volume = 1.0
        self._params: dict[str, float] = {
            "speed": 100.0,
            "pitchShift": 1.0,
            "doubleVoice": 0.0,
            "volume": 100.0,
        }
        self._stop = threading.Event()

    @staticmethod
    def speaking_time_s(text: str) -> float:
        """Seconds NAO takes to say ``text`` at its default rate (tags removed)."""
        words = re.sub(r"\\\\[a-z]+=?\d*\\\\|\^\w+\([^)]*\)", " ", text).split()
        return 0.3 + SECONDS_PER_WORD * len(words)

    def say(self, stringToSay: Any, *language: Any) -> None:
        """Say a text (logged); blocking for about 0.4 s a word."""
        if not isinstance(stringToSay, str):
            raise RobotError(f"say takes a string, got {stringToSay!r}")
        if language:
            self._check_language(language[0])
        self._ctx.log(f"naoloc serve: ALTextToSpeech.say: {stringToSay!r} (no audio is simulated)")
        self._stop.clear()
        self._memory.insertData("ALTextToSpeech/CurrentSentence", stringToSay)
        self._memory.insertData("ALTextToSpeech/TextStarted", 1)
        self._memory.insertData("ALTextToSpeech/TextDone", 0)
        speed = self._params["speed"] / 100.0
        self._ctx.sleep_sim(self.speaking_time_s(stringToSay) / max(0.5, speed), self._stop)
        self._memory.insertData("ALTextToSpeech/TextStarted", 0)
        self._memory.insertData("ALTextToSpeech/TextDone", 1)

    def stopAll(self) -> None:
        """Interrupt what is being said."""
        self._stop.set()

    def _check_language(self, language: Any) -> str:
        if language not in LANGUAGES:
            raise RobotError(
                f"language {language!r} is not installed; available: {', '.join(LANGUAGES)}"
            )
        return str(language)

    def setLanguage(self, language: Any) -> None:
        """Choose an installed language."""
        self._language = self._check_language(language)

    def getLanguage(self) -> str:
        """The current language."""
        return self._language

    def getAvailableLanguages(self) -> list[str]:
        """Installed languages."""
        return list(LANGUAGES)

    def getSupportedLanguages(self) -> list[str]:
        """As getAvailableLanguages."""
        return list(LANGUAGES)

    def setVolume(self, volume: Any) -> None:
        """Speech volume in [0, 1]."""
        v = rules.finite(volume, "volume")
        if not 0.0 <= v <= 1.0:
            raise RobotError(f"volume must be in [0, 1], got {volume}")
        self._volume = v

    def getVolume(self) -> float:
        """Speech volume in [0, 1]."""
        return self._volume

    def setParameter(self, parameter: Any, value: Any) -> None:
        """speed (50-400 %), pitchShift (1.0-4.0), doubleVoice..., volume."""
        if parameter not in self._params:
            raise RobotError(
                f"unknown speech parameter {parameter!r}; valid: {sorted(self._params)}"
            )
        self._params[str(parameter)] = rules.finite(value, str(parameter))

    def getParameter(self, parameter: Any) -> float:
        """A speech parameter."""
        if parameter not in self._params:
            raise RobotError(
                f"unknown speech parameter {parameter!r}; valid: {sorted(self._params)}"
            )
        return self._params[str(parameter)]

    def getAvailableVoices(self) -> list[str]:
        """Voices (one per language here)."""
        return [f"naoloc_{lang.lower()}" for lang in LANGUAGES]

    def setVoice(self, pVoiceID: Any) -> None:
        """Choose a voice."""
        if pVoiceID not in self.getAvailableVoices():
            raise RobotError(f"unknown voice {pVoiceID!r}")

    def sayToFile(self, pStringToSay: Any, pFileName: Any) -> None:
        """Not simulated (no audio)."""
        raise RobotError("sayToFile is not simulated: naoloc has no speech synthesiser")


class AnimatedSpeechFront:
    """ALAnimatedSpeech: says the text without its ^tags; gestures are not simulated."""

    def __init__(self, ctx: FrontContext, tts: TextToSpeechFront) -> None:
        self._ctx = ctx
        self._tts = tts
        self._mode = 1

    def say(self, text: Any, *configuration: Any) -> None:
        """Say ``text`` (blocking); ``^start(...)`` style tags are dropped."""
        if not isinstance(text, str):
            raise RobotError(f"say takes a string, got {text!r}")
        self._ctx.not_simulated("ALAnimatedSpeech gestures")
        self._tts.say(re.sub(r"\^\w+\([^)]*\)", "", text))

    def setBodyLanguageMode(self, bodyLanguageMode: Any) -> None:
        """0 disabled, 1 random, 2 contextual."""
        if bodyLanguageMode not in (0, 1, 2):
            raise RobotError(f"body language mode must be 0, 1 or 2, got {bodyLanguageMode!r}")
        self._mode = int(bodyLanguageMode)

    def getBodyLanguageMode(self) -> int:
        """The body language mode."""
        return self._mode

    def setBodyLanguageModeFromStr(self, stringBodyLanguageMode: Any) -> None:
        """ "disabled", "random" or "contextual"."""
        modes = {"disabled": 0, "random": 1, "contextual": 2}
        if stringBodyLanguageMode not in modes:
            raise RobotError(f"mode must be one of {sorted(modes)}, got {stringBodyLanguageMode!r}")
        self._mode = modes[stringBodyLanguageMode]

    def getBodyLanguageModeToStr(self) -> str:
        """The body language mode's name."""
        return ("disabled", "random", "contextual")[self._mode]


LED_GROUPS: Final[dict[str, tuple[str, ...]]] = {
    "FaceLeds": ("LeftFaceLeds", "RightFaceLeds"),
    "EarLeds": ("LeftEarLeds", "RightEarLeds"),
    "FeetLeds": ("LeftFootLeds", "RightFootLeds"),
    "ChestLeds": ("ChestLeds",),
    "BrainLeds": ("BrainLeds",),
    "AllLeds": (
        "LeftFaceLeds", "RightFaceLeds", "LeftEarLeds", "RightEarLeds",
        "LeftFootLeds", "RightFootLeds", "ChestLeds", "BrainLeds",
    ),
}  # fmt: skip
COLOURS: Final[dict[str, int]] = {
    "white": 0xFFFFFF, "red": 0xFF0000, "green": 0x00FF00, "blue": 0x0000FF,
    "yellow": 0xFFFF00, "magenta": 0xFF00FF, "cyan": 0x00FFFF,
}  # fmt: skip


_FADE_USAGE: Final = (
    "fadeRGB takes (name, rgb, duration), (name, colour, duration) or (name, r, g, b, duration)"
)


class LedsFront:
    """ALLeds: LED groups keep a colour and an intensity; fades block for their duration."""

    def __init__(self, ctx: FrontContext) -> None:
        self._ctx = ctx
        self._groups: dict[str, tuple[str, ...]] = dict(LED_GROUPS)
        leaves = {leaf for members in LED_GROUPS.values() for leaf in members}
        self._groups.update({leaf: (leaf,) for leaf in leaves})
        self._rgb = dict.fromkeys(leaves, 0xFFFFFF)
        self._intensity = dict.fromkeys(leaves, 1.0)

    def _leaves(self, name: Any) -> tuple[str, ...]:
        members = self._groups.get(name) if isinstance(name, str) else None
        if members is None:
            raise RobotError(
                f"unknown LED or group {name!r}; groups: {', '.join(sorted(LED_GROUPS))}"
            )
        return members

    def _wait(self, duration: Any) -> None:
        seconds = rules.finite(duration, "duration")
        if seconds < 0:
            raise RobotError(f"duration must be >= 0 s, got {duration}")
        self._ctx.sleep_sim(seconds)

    def on(self, name: Any) -> None:
        """Full intensity."""
        for leaf in self._leaves(name):
            self._intensity[leaf] = 1.0

    def off(self, name: Any) -> None:
        """Zero intensity."""
        for leaf in self._leaves(name):
            self._intensity[leaf] = 0.0

    def setIntensity(self, name: Any, intensity: Any) -> None:
        """Intensity in [0, 1] at once."""
        value = rules.finite(intensity, "intensity")
        for leaf in self._leaves(name):
            self._intensity[leaf] = min(1.0, max(0.0, value))

    def getIntensity(self, name: Any) -> float:
        """Intensity of an LED or group (the first member's)."""
        return self._intensity[self._leaves(name)[0]]

    def fade(self, name: Any, intensity: Any, duration: Any) -> None:
        """Reach an intensity in ``duration`` s; blocking."""
        leaves = self._leaves(name)
        value = rules.finite(intensity, "intensity")
        self._wait(duration)
        for leaf in leaves:
            self._intensity[leaf] = min(1.0, max(0.0, value))

    def fadeRGB(self, name: Any, *args: Any) -> None:
        """Reach a colour in ``duration`` s; blocking.

        Forms: ``(name, 0xRRGGBB, duration)``, ``(name, colourName, duration)``,
        ``(name, red, green, blue, duration)`` with components in [0, 1].
        """
        leaves = self._leaves(name)
        if len(args) == 2 and isinstance(args[0], str):
            if args[0] not in COLOURS:
                raise RobotError(f"unknown colour {args[0]!r}; known: {', '.join(COLOURS)}")
            rgb = COLOURS[args[0]]
        elif len(args) == 2:
            rgb = int(rules.finite(args[0], "rgb")) & 0xFFFFFF
        elif len(args) == 4:
            parts = [min(1.0, max(0.0, rules.finite(v, "colour"))) for v in args[:3]]
            rgb = (
                (round(parts[0] * 255) << 16) | (round(parts[1] * 255) << 8) | round(parts[2] * 255)
            )
        else:
            raise RobotError(_FADE_USAGE)
        self._wait(args[-1])
        for leaf in leaves:
            self._rgb[leaf] = rgb
            self._intensity[leaf] = 1.0

    def fadeListRGB(self, name: Any, rgbList: Any, timeList: Any) -> None:
        """A sequence of colours at key times (s); blocking for the last time."""
        leaves = self._leaves(name)
        times = [rules.finite(t, "time") for t in list(timeList)]
        colours = [int(rules.finite(c, "rgb")) for c in list(rgbList)]
        if len(times) != len(colours):
            raise RobotError("fadeListRGB: as many colours as times")
        now = 0.0
        for t, c in zip(times, colours, strict=True):
            self._ctx.sleep_sim(max(0.0, t - now))
            now = max(now, t)
            for leaf in leaves:
                self._rgb[leaf] = c

    def getRGB(self, name: Any) -> int:
        """Colour ``0xRRGGBB`` of an LED or group (the first member's)."""
        return self._rgb[self._leaves(name)[0]]

    def rasta(self, duration: Any) -> None:
        """Coloured eyes for ``duration`` s; blocking."""
        self._wait(duration)

    def randomEyes(self, duration: Any) -> None:
        """Random eye colours for ``duration`` s; blocking."""
        self._wait(duration)

    def rotateEyes(self, rgb: Any, timeForRotation: Any, totalDuration: Any) -> None:
        """Rotating eye colour for ``totalDuration`` s; blocking."""
        rules.finite(timeForRotation, "timeForRotation")
        self._wait(totalDuration)
        for leaf in ("LeftFaceLeds", "RightFaceLeds"):
            self._rgb[leaf] = int(rules.finite(rgb, "rgb")) & 0xFFFFFF

    def reset(self, name: Any) -> None:
        """White, full intensity."""
        for leaf in self._leaves(name):
            self._rgb[leaf], self._intensity[leaf] = 0xFFFFFF, 1.0

    def listGroups(self) -> list[str]:
        """Group names."""
        return sorted(LED_GROUPS)

    def listGroup(self, groupName: Any) -> list[str]:
        """Members of a group."""
        return list(self._leaves(groupName))

    def listLEDs(self) -> list[str]:
        """Every LED (as groups of LEDs)."""
        return sorted(self._rgb)

    def createGroup(self, groupName: Any, ledNames: Any) -> None:
        """A new group of existing LEDs or groups."""
        if not isinstance(groupName, str) or not groupName:
            raise RobotError(f"a group name is a non-empty string, got {groupName!r}")
        members: list[str] = []
        for name in list(ledNames):
            members.extend(self._leaves(name))
        self._groups[groupName] = tuple(members)


class SimpleState:
    """Stores NAOqi state a script sets and reads, for the services that need no body."""

    def __init__(self, ctx: FrontContext, name: str, state: str, states: tuple[str, ...]) -> None:
        self._ctx = ctx
        self._name = name
        self._state = state
        self._states = states
        self._flags: dict[str, bool] = {}
        self._modes: dict[str, str] = {}


class AutonomousLifeFront(SimpleState):
    """ALAutonomousLife: the state is kept; no autonomous behaviour is simulated."""

    def __init__(self, ctx: FrontContext) -> None:
        super().__init__(
            ctx,
            "ALAutonomousLife",
            "solitary",
            ("solitary", "interactive", "disabled", "safeguard"),
        )

    def getState(self) -> str:
        """ "solitary", "interactive", "disabled" or "safeguard"."""
        return self._state

    def setState(self, state: Any) -> None:
        """Change the state (no autonomous behaviour is simulated)."""
        if state not in self._states:
            raise RobotError(f"state must be one of {', '.join(self._states)}, got {state!r}")
        self._ctx.not_simulated("ALAutonomousLife behaviours")
        self._state = str(state)

    def setAutonomousAbilityEnabled(self, autonomousAbility: Any, enabled: Any) -> None:
        """Store an ability flag."""
        self._flags[str(autonomousAbility)] = bool(enabled)

    def getAutonomousAbilityEnabled(self, autonomousAbility: Any) -> bool:
        """An ability flag (True unless disabled)."""
        return self._flags.get(str(autonomousAbility), True)

    def getAutonomousAbilitiesStatus(self) -> list[list[Any]]:
        """``[[name, enabled, running], ...]``."""
        return [[k, v, False] for k, v in sorted(self._flags.items())]


class BasicAwarenessFront(SimpleState):
    """ALBasicAwareness: flags and modes are kept; nothing is tracked."""

    def __init__(self, ctx: FrontContext) -> None:
        super().__init__(ctx, "ALBasicAwareness", "running", ("running", "stopped"))
        self._modes = {"engagement": "Unengaged", "tracking": "Head"}
        self._enabled = True
        self._paused = False

    def startAwareness(self) -> None:
        """Start (nothing is tracked in the simulator)."""
        self._ctx.not_simulated("ALBasicAwareness tracking")
        self._enabled = True

    def stopAwareness(self) -> None:
        """Stop."""
        self._enabled = False

    def setEnabled(self, enabled: Any) -> None:
        """Start or stop."""
        self._enabled = bool(enabled)

    def isEnabled(self) -> bool:
        """True while enabled."""
        return self._enabled

    def isAwarenessRunning(self) -> bool:
        """True while enabled and not paused."""
        return self._enabled and not self._paused

    def isRunning(self) -> bool:
        """As isAwarenessRunning (NAOqi 2.5+)."""
        return self.isAwarenessRunning()

    def pauseAwareness(self) -> None:
        """Pause."""
        self._paused = True

    def resumeAwareness(self) -> None:
        """Resume."""
        self._paused = False

    def setEngagementMode(self, modeName: Any) -> None:
        """ "Unengaged", "FullyEngaged" or "SemiEngaged"."""
        if modeName not in ("Unengaged", "FullyEngaged", "SemiEngaged"):
            raise RobotError(f"unknown engagement mode {modeName!r}")
        self._modes["engagement"] = str(modeName)

    def getEngagementMode(self) -> str:
        """The engagement mode."""
        return self._modes["engagement"]

    def setTrackingMode(self, modeName: Any) -> None:
        """ "Head", "BodyRotation", "WholeBody" or "MoveContextually"."""
        if modeName not in ("Head", "BodyRotation", "WholeBody", "MoveContextually"):
            raise RobotError(f"unknown tracking mode {modeName!r}")
        self._modes["tracking"] = str(modeName)

    def getTrackingMode(self) -> str:
        """The tracking mode."""
        return self._modes["tracking"]

    def setStimulusDetectionEnabled(self, stimulusName: Any, isEnabled: Any) -> None:
        """Store a stimulus flag."""
        self._flags[str(stimulusName)] = bool(isEnabled)

    def isStimulusDetectionEnabled(self, stimulusName: Any) -> bool:
        """A stimulus flag (True unless disabled)."""
        return self._flags.get(str(stimulusName), True)


class TouchFront:
    """ALTouch: the sensors exist and are never touched."""

    def getSensorList(self) -> list[str]:
        """Touch sensor and bumper names."""
        return list(TOUCH_SENSORS)

    def getStatus(self) -> list[list[Any]]:
        """``[[sensor, touched, []], ...]``: nothing is ever touched in the simulator."""
        return [[name, False, []] for name in TOUCH_SENSORS]


class BatteryFront:
    """ALBattery: the simulated battery stays full."""

    def getBatteryCharge(self) -> int:
        """Charge in percent (100: the simulated battery never drains)."""
        return 100

    def getBatteryCapacity(self) -> int:
        """Capacity in percent of a new battery."""
        return 100


class SystemFront:
    """ALSystem: the robot's name and NAOqi version; no system administration."""

    def __init__(self, robot_name: str = "nao") -> None:
        self._name = robot_name

    def robotName(self) -> str:
        """The robot's name."""
        return self._name

    def setRobotName(self, name: Any) -> bool:
        """Rename the robot; True."""
        if not isinstance(name, str) or not name:
            raise RobotError(f"a robot name is a non-empty string, got {name!r}")
        self._name = name
        return True

    def systemVersion(self) -> str:
        """The NAOqi version naoloc mirrors."""
        return rules.NAOQI_VERSION

    def robotIcon(self) -> str:
        """No icon."""
        return ""

    def timezone(self) -> str:
        """The robot's time zone."""
        return "UTC"

    def shutdown(self) -> bool:
        """Refused: stop the server instead."""
        raise RobotError("shutdown is not simulated: stop `naoloc serve` with Ctrl-C")

    def reboot(self) -> bool:
        """Refused: restart the server instead."""
        raise RobotError("reboot is not simulated: restart `naoloc serve`")


class SpeechRecognitionFront:
    """ALSpeechRecognition: a subscriber API that never hears anything (no audio)."""

    def __init__(self, ctx: FrontContext) -> None:
        self._ctx = ctx
        self._language = "English"
        self._vocabulary: list[str] = []
        self._subscribers: list[str] = []
        self._params: dict[str, float] = {"Sensitivity": 0.5, "NbHypotheses": 1.0}
        self._paused = False

    def setLanguage(self, language: Any) -> None:
        """Choose a language."""
        if language not in LANGUAGES:
            raise RobotError(
                f"language {language!r} is not installed; available: {', '.join(LANGUAGES)}"
            )
        self._language = str(language)

    def getLanguage(self) -> str:
        """The language."""
        return self._language

    def getAvailableLanguages(self) -> list[str]:
        """Installed languages."""
        return list(LANGUAGES)

    def setVocabulary(self, vocabulary: Any, enableWordSpotting: Any) -> None:
        """The words to listen for."""
        words = list(vocabulary)
        if not all(isinstance(w, str) for w in words):
            raise RobotError("vocabulary must be a list of strings")
        self._vocabulary = words

    def setWordListAsVocabulary(self, vocabulary: Any) -> None:
        """Deprecated form of setVocabulary."""
        self.setVocabulary(vocabulary, False)

    def subscribe(self, name: Any) -> None:
        """Start listening (WordRecognized never changes: no audio is simulated)."""
        self._ctx.not_simulated("ALSpeechRecognition (no audio: nothing is ever recognised)")
        self._subscribers.append(str(name))

    def unsubscribe(self, name: Any) -> None:
        """Stop listening."""
        if str(name) not in self._subscribers:
            raise RobotError(f"{name!r} is not subscribed to ALSpeechRecognition")
        self._subscribers.remove(str(name))

    def getSubscribersInfo(self) -> list[list[Any]]:
        """``[[name, period, precision], ...]``."""
        return [[n, 500, 1.0] for n in self._subscribers]

    def pause(self, isPaused: Any) -> None:
        """Pause or resume."""
        self._paused = bool(isPaused)

    def setAudioExpression(self, setOrNot: Any) -> None:
        """Beep flag (stored)."""

    def setVisualExpression(self, setOrNot: Any) -> None:
        """Eye LED flag (stored)."""

    def setParameter(self, parameter: Any, value: Any) -> None:
        """A recognition parameter."""
        self._params[str(parameter)] = rules.finite(value, str(parameter))

    def getParameter(self, parameter: Any) -> float:
        """A recognition parameter."""
        if parameter not in self._params:
            raise RobotError(f"unknown parameter {parameter!r}; valid: {sorted(self._params)}")
        return self._params[str(parameter)]
