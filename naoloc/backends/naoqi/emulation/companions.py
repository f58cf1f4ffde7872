"""The companion services of a served NAOqi: ALMemory, speech, LEDs, touch, life, system.

What a script reads and writes is kept and answered with NAOqi's types; what needs a
body naoloc does not simulate says so once in the server's log: no audio (speech is
timed and logged, recognition never hears a word), LEDs change state but nothing
lights, touch sensors and bumpers are never touched, the battery stays full.
"""

from __future__ import annotations

from typing import Any, Final

from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.backends.naoqi.emulation.memory import STATIC_KEYS, MemoryFront
from naoloc.backends.naoqi.emulation.speech import (
    LANGUAGES,
    AnimatedSpeechFront,
    SpeechRecognitionFront,
    TextToSpeechFront,
)
from naoloc.errors import RobotError
from naoloc.robot import rules

__all__ = [
    "LANGUAGES", "STATIC_KEYS", "AnimatedSpeechFront", "AutonomousLifeFront",
    "BasicAwarenessFront", "BatteryFront", "LedsFront", "MemoryFront",
    "SpeechRecognitionFront", "SystemFront", "TextToSpeechFront", "TouchFront",
]  # fmt: skip

TOUCH_SENSORS: Final = (
    "Head/Touch/Front", "Head/Touch/Middle", "Head/Touch/Rear",
    "LHand/Touch/Back", "LHand/Touch/Left", "LHand/Touch/Right",
    "RHand/Touch/Back", "RHand/Touch/Left", "RHand/Touch/Right",
    "LFoot/Bumper/Left", "LFoot/Bumper/Right", "RFoot/Bumper/Left", "RFoot/Bumper/Right",
    "ChestBoard/Button",
)  # fmt: skip


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
