"""Speech of a served NAOqi: ALTextToSpeech, ALAnimatedSpeech, ALSpeechRecognition.

No audio is simulated: ``say`` blocks for about 0.4 s a word and logs the text;
recognition is a subscriber API that never hears a word.
"""

from __future__ import annotations

import re
import threading
from typing import Any, Final

from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.backends.naoqi.emulation.memory import MemoryFront
from naoloc.errors import RobotError
from naoloc.robot import rules

LANGUAGES: Final = ("English", "French", "German", "Spanish", "Italian", "Japanese", "Chinese")
SECONDS_PER_WORD: Final = 0.4  # about 150 words a minute, NAO's default speech rate


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
