"""The served NAOqi services: method names and libqi type signatures, in one table.

The virtual NAOqi binds these signatures with ``qi.bind`` on the libqi transport (so a
real NAOqi client sees typed methods and receives image buffers as binary) and checks
incoming arguments against them on the zmq transport. Signature letters are libqi's:
``b`` bool, ``i`` int32, ``d`` double, ``s`` string, ``v`` void, ``m`` dynamic,
``r`` buffer, ``[x]`` list of x, ``(...)`` tuple. Doubles rather than NAOqi's floats
keep poses bit-exact across the network.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final

from naoloc.errors import RobotError

MOTION: Final = "ALMotion"
VIDEO: Final = "ALVideoDevice"
POSTURE: Final = "ALRobotPosture"
MEMORY: Final = "ALMemory"
TTS: Final = "ALTextToSpeech"
ANIMATED_SPEECH: Final = "ALAnimatedSpeech"
LEDS: Final = "ALLeds"
TOUCH: Final = "ALTouch"
LIFE: Final = "ALAutonomousLife"
AWARENESS: Final = "ALBasicAwareness"
BATTERY: Final = "ALBattery"
SYSTEM: Final = "ALSystem"
SPEECH_RECOGNITION: Final = "ALSpeechRecognition"
SIM: Final = "NaolocSim"
WATCHDOG: Final = "NaolocWatchdog"
SONAR: Final = "ALSonar"
NAVIGATION: Final = "ALNavigation"
ANIMATION_PLAYER: Final = "ALAnimationPlayer"
VIDEO_RECORDER: Final = "ALVideoRecorder"
FACE_DETECTION: Final = "ALFaceDetection"
TRACKER: Final = "ALTracker"
LANDMARK_DETECTION: Final = "ALLandMarkDetection"
LOCALIZATION: Final = "NaolocLocalization"

# Service name -> attribute of naoloc.robot.Robot that implements it (the robot's own
# services); the companion services are implemented by naoloc.backends.naoqi.emulation.companions.
ROBOT_ATTRIBUTE: Final[dict[str, str]] = {
    MOTION: "motion",
    VIDEO: "video",
    POSTURE: "posture",
    SIM: "sim",
}

IMAGE_SIGNATURE: Final = "(iiiiiiridddd)"  # the 12 slots of the image array; 6 is a buffer


@dataclass(frozen=True)
class Overload:
    """One callable shape of a method.

    Attributes:
        returns: libqi signature of the return value.
        params: libqi signatures of the parameters.
    """

    returns: str
    params: tuple[str, ...]


def _o(returns: str, *params: str) -> tuple[Overload, ...]:
    return (Overload(returns, params),)


def _m(returns: str, count: int) -> tuple[Overload, ...]:
    """One overload of ``count`` dynamic parameters (the service front checks them)."""
    return (Overload(returns, ("m",) * count),)


def _counts(returns: str, *counts: int) -> tuple[Overload, ...]:
    return tuple(Overload(returns, ("m",) * n) for n in counts)


# Every served service also answers these (ALModule's methods): the task model and basics.
MODULE_METHODS: Final[dict[str, tuple[Overload, ...]]] = {
    "ping": _o("b"),
    "version": _o("s"),
    "wait": _o("b", "i", "i"),
    "isRunning": _o("b", "i"),
    "stop": _o("v", "i"),
    "pCall": _counts("i", 1, 2, 3, 4, 5, 6),
    "getMethodList": _o("[s]"),
    "getBrokerName": _o("s"),
}

_SERVICES: dict[str, dict[str, tuple[Overload, ...]]] = {
    MOTION: {
        "wakeUp": _o("v"),
        "rest": _o("v"),
        "robotIsWakeUp": _o("b"),
        "setStiffnesses": _o("v", "m", "m"),
        "getStiffnesses": _o("[d]", "m"),
        "stiffnessInterpolation": _m("v", 3),
        "moveInit": _o("v"),
        "moveTo": (
            Overload("b", ("d", "d", "d")),
            Overload("b", ("d", "d", "d", "m")),
            Overload("b", ("m",)),
            Overload("b", ("m", "m")),
        ),
        "move": (Overload("v", ("d", "d", "d")), Overload("v", ("d", "d", "d", "m"))),
        "moveToward": (Overload("v", ("d", "d", "d")), Overload("v", ("d", "d", "d", "m"))),
        "waitUntilMoveIsFinished": _o("v"),
        "moveIsActive": _o("b"),
        "stopMove": _o("b"),
        "killMove": _o("v"),
        "killAll": _o("v"),
        "killTask": _o("b", "i"),
        "getTaskList": _o("m"),
        "areResourcesAvailable": _m("b", 1),
        "getRobotPosition": _o("[d]", "b"),
        "getNextRobotPosition": _o("[d]"),
        "getRobotVelocity": _o("[d]"),
        "getMoveConfig": _o("m", "s"),
        "setMoveArmsEnabled": _o("v", "b", "b"),
        "getMoveArmsEnabled": _o("b", "s"),
        "setAngles": _o("v", "m", "m", "m"),
        "changeAngles": _o("v", "m", "m", "m"),
        "angleInterpolation": _m("v", 4),
        "angleInterpolationWithSpeed": _o("v", "m", "m", "d"),
        "getAngles": _o("[d]", "m", "b"),
        "openHand": _o("v", "s"),
        "closeHand": _o("v", "s"),
        "getPosition": _o("[d]", "s", "i", "b"),
        "getTransform": _o("[d]", "s", "i", "b"),
        "transformInterpolations": _m("v", 5),
        "positionInterpolations": _m("v", 5),
        "setTransforms": _m("v", 5),
        "setPositions": _m("v", 5),
        "wbEnable": _o("v", "b"),
        "wbFootState": _o("v", "s", "s"),
        "wbEnableBalanceConstraint": _o("v", "b", "s"),
        "wbGoToBalance": _o("v", "s", "d"),
        "wbEnableEffectorControl": _o("v", "s", "b"),
        "setCollisionProtectionEnabled": _o("b", "s", "b"),
        "getCollisionProtectionEnabled": _o("b", "s"),
        "setExternalCollisionProtectionEnabled": _o("v", "s", "b"),
        "getExternalCollisionProtectionEnabled": _o("b", "s"),
        "setFallManagerEnabled": _o("v", "b"),
        "getFallManagerEnabled": _o("b"),
        "setSmartStiffnessEnabled": _o("v", "b"),
        "getSmartStiffnessEnabled": _o("b"),
        "setBreathEnabled": _o("v", "s", "b"),
        "getBreathEnabled": _o("b", "s"),
        "setIdlePostureEnabled": _o("v", "s", "b"),
        "getIdlePostureEnabled": _o("b", "s"),
        "setMotionConfig": _m("v", 1),
        "getBodyNames": _o("[s]", "s"),
        "getJointNames": _o("[s]", "s"),
        "getSensorNames": _o("[s]"),
        "getSummary": _o("s"),
        # NAOqi 1.x names, still called by old SDK scripts
        "walkTo": (Overload("b", ("d", "d", "d")), Overload("b", ("d", "d", "d", "m"))),
        "walkInit": _o("v"),
        "setWalkTargetVelocity": _o("v", "d", "d", "d", "d"),
        "waitUntilWalkIsFinished": _o("v"),
        "walkIsActive": _o("b"),
        "stopWalk": _o("b"),
        "setWalkArmsEnabled": _o("v", "b", "b"),
        "getWalkArmsEnabled": _o("[b]"),
    },
    VIDEO: {
        "subscribeCamera": _o("s", "s", "i", "i", "i", "i"),
        "subscribe": _o("s", "s", "i", "i", "i"),
        "unsubscribe": _o("b", "s"),
        "getSubscribers": _o("[s]"),
        "getImageRemote": _o(IMAGE_SIGNATURE, "s"),
        "getImageLocal": _o("m", "s"),
        "releaseImage": _o("b", "s"),
        "setActiveCamera": _o("b", "i"),
        "getActiveCamera": _o("i"),
        "getHorizontalFOV": _o("d", "i"),
        "getVerticalFOV": _o("d", "i"),
        "getResolution": _o("i", "s"),
        "getColorSpace": _o("i", "s"),
        "getFrameRate": _o("i", "s"),
        "getCameraIndex": _o("i", "s"),
        "setFrameRate": _o("b", "s", "i"),
        "setResolution": _o("b", "s", "i"),
        "setColorSpace": _o("b", "s", "i"),
        "setParameter": _o("b", "i", "i", "i"),
        "getParameter": _o("i", "i", "i"),
        "setCameraParameter": _o("b", "s", "i", "i"),
        "getCameraParameter": _o("i", "s", "i"),
        "setAllParametersToDefaultValue": _o("b", "i"),
        "getCameraName": _o("s", "i"),
        "isCameraOpen": _o("b", "i"),
    },
    POSTURE: {
        "goToPosture": _o("b", "s", "d"),
        "applyPosture": _o("b", "s", "d"),
        "getPosture": _o("s"),
        "getPostureList": _o("[s]"),
        "getPostureFamily": _o("s"),
        "getPostureFamilyList": _o("[s]"),
        "stopMove": _o("v"),
        "setMaxTryNumber": _o("v", "i"),
    },
    MEMORY: {
        "getData": (Overload("m", ("s",)), Overload("m", ("s", "i"))),
        "getListData": _m("m", 1),
        "insertData": _o("v", "s", "m"),
        "insertListData": _m("v", 1),
        "removeData": _o("v", "s"),
        "raiseEvent": _o("v", "s", "m"),
        "raiseMicroEvent": _o("v", "s", "m"),
        "declareEvent": _o("v", "s"),
        "getEventList": _o("[s]"),
        "getDataList": _o("[s]", "s"),
        "getDataListName": _o("[s]"),
        "getDataOnChange": _o("m", "s", "m"),
        "subscriber": _o("o", "s"),
        "subscribeToEvent": _o("v", "s", "s", "s"),
        "unsubscribeToEvent": _o("v", "s", "s"),
    },
    TTS: {
        "say": (Overload("v", ("s",)), Overload("v", ("s", "s"))),
        "stopAll": _o("v"),
        "setLanguage": _o("v", "s"),
        "getLanguage": _o("s"),
        "getAvailableLanguages": _o("[s]"),
        "getSupportedLanguages": _o("[s]"),
        "setVolume": _o("v", "d"),
        "getVolume": _o("d"),
        "setParameter": _o("v", "s", "d"),
        "getParameter": _o("d", "s"),
        "getAvailableVoices": _o("[s]"),
        "setVoice": _o("v", "s"),
        "sayToFile": _o("v", "s", "s"),
    },
    ANIMATED_SPEECH: {
        "say": (Overload("v", ("s",)), Overload("v", ("s", "m"))),
        "setBodyLanguageMode": _o("v", "i"),
        "getBodyLanguageMode": _o("i"),
        "setBodyLanguageModeFromStr": _o("v", "s"),
        "getBodyLanguageModeToStr": _o("s"),
    },
    LEDS: {
        "on": _o("v", "s"),
        "off": _o("v", "s"),
        "setIntensity": _o("v", "s", "d"),
        "getIntensity": _o("d", "s"),
        "fade": _o("v", "s", "d", "d"),
        "fadeRGB": (
            Overload("v", ("s", "m", "d")),
            Overload("v", ("s", "d", "d", "d", "d")),
        ),
        "fadeListRGB": _o("v", "s", "m", "m"),
        "getRGB": _o("i", "s"),
        "rasta": _o("v", "d"),
        "randomEyes": _o("v", "d"),
        "rotateEyes": _o("v", "i", "d", "d"),
        "reset": _o("v", "s"),
        "listGroups": _o("[s]"),
        "listGroup": _o("[s]", "s"),
        "listLEDs": _o("[s]"),
        "createGroup": _o("v", "s", "m"),
    },
    TOUCH: {
        "getSensorList": _o("[s]"),
        "getStatus": _o("m"),
    },
    LIFE: {
        "getState": _o("s"),
        "setState": _o("v", "s"),
        "setAutonomousAbilityEnabled": _o("v", "s", "b"),
        "getAutonomousAbilityEnabled": _o("b", "s"),
        "getAutonomousAbilitiesStatus": _o("m"),
    },
    AWARENESS: {
        "startAwareness": _o("v"),
        "stopAwareness": _o("v"),
        "setEnabled": _o("v", "b"),
        "isEnabled": _o("b"),
        "isAwarenessRunning": _o("b"),
        "pauseAwareness": _o("v"),
        "resumeAwareness": _o("v"),
        "setEngagementMode": _o("v", "s"),
        "getEngagementMode": _o("s"),
        "setTrackingMode": _o("v", "s"),
        "getTrackingMode": _o("s"),
        "setStimulusDetectionEnabled": _o("v", "s", "b"),
        "isStimulusDetectionEnabled": _o("b", "s"),
    },
    BATTERY: {
        "getBatteryCharge": _o("i"),
        "getBatteryCapacity": _o("i"),
    },
    SYSTEM: {
        "robotName": _o("s"),
        "setRobotName": _o("b", "s"),
        "systemVersion": _o("s"),
        "robotIcon": _o("s"),
        "timezone": _o("s"),
        "shutdown": _o("b"),
        "reboot": _o("b"),
    },
    SPEECH_RECOGNITION: {
        "setLanguage": _o("v", "s"),
        "getLanguage": _o("s"),
        "getAvailableLanguages": _o("[s]"),
        "setVocabulary": _o("v", "m", "b"),
        "setWordListAsVocabulary": _o("v", "m"),
        "subscribe": _o("v", "s"),
        "unsubscribe": _o("v", "s"),
        "getSubscribersInfo": _o("m"),
        "pause": _o("v", "b"),
        "setAudioExpression": _o("v", "b"),
        "setVisualExpression": _o("v", "b"),
        "setParameter": _o("v", "s", "d"),
        "getParameter": _o("d", "s"),
    },
}

_EXTRACTOR: dict[str, tuple[Overload, ...]] = {
    "subscribe": (Overload("v", ("s",)), Overload("v", ("s", "i", "d"))),
    "unsubscribe": _o("v", "s"),
    "getSubscribersInfo": _o("m"),
    "updatePeriod": _o("v", "s", "i"),
    "getCurrentPeriod": _o("i"),
    "getOutputNames": _o("[s]"),
}
# Issue 32: the services NAO scripts open first (see naoloc.backends.naoqi.emulation).
_SERVICES.update(
    {
        SONAR: {
            "subscribe": (Overload("v", ("s",)), Overload("v", ("s", "i", "d"))),
            "unsubscribe": _o("v", "s"),
            "getSubscribersInfo": _o("m"),
            "getCurrentPeriod": _o("i"),
            "getCurrentPrecision": _o("d"),
            "getMyPeriod": _o("i", "s"),
            "getOutputNames": _o("[s]"),
            "getEventList": _o("[s]"),
        },
        NAVIGATION: {
            "navigateTo": (Overload("b", ("d", "d")), Overload("b", ("d", "d", "d"))),
            "moveAlong": _m("b", 1),
            "stopNavigateTo": _o("v"),
            "setSecurityDistance": _o("v", "d"),
            "getSecurityDistance": _o("d"),
        },
        ANIMATION_PLAYER: {
            "run": (Overload("v", ("s",)), Overload("v", ("s", "m"))),
            "runTag": (Overload("v", ("s",)), Overload("v", ("s", "m"))),
            "reset": _o("v"),
            "declarePathForTags": _o("v", "s"),
            "addTagForAnimations": _m("v", 1),
        },
        VIDEO_RECORDER: {
            "setCameraID": _o("v", "i"),
            "getCameraID": _o("i"),
            "setResolution": _o("v", "i"),
            "getResolution": _o("i"),
            "setFrameRate": _o("v", "d"),
            "getFrameRate": _o("i"),
            "setColorSpace": _o("v", "i"),
            "getColorSpace": _o("i"),
            "setVideoFormat": _o("v", "s"),
            "getVideoFormat": _o("s"),
            "startRecording": (Overload("v", ("s", "s")), Overload("v", ("s", "s", "b"))),
            "stopRecording": _o("m"),
            "isRecording": _o("b"),
        },
        FACE_DETECTION: {
            **_EXTRACTOR,
            "setTrackingEnabled": _o("v", "b"),
            "isTrackingEnabled": _o("b"),
            "setRecognitionEnabled": _o("v", "b"),
            "isRecognitionEnabled": _o("b"),
            "learnFace": _o("b", "s"),
            "reLearnFace": _o("b", "s"),
            "forgetPerson": _o("b", "s"),
            "clearDatabase": _o("b"),
            "getLearnedFacesList": _o("[s]"),
        },
        LANDMARK_DETECTION: dict(_EXTRACTOR),
        TRACKER: {
            "registerTarget": _o("v", "s", "m"),
            "unregisterTarget": _o("v", "s"),
            "unregisterAllTargets": _o("v"),
            "getRegisteredTargets": _o("[s]"),
            "getSupportedTargets": _o("[s]"),
            "track": _o("v", "s"),
            "trackEvent": _o("v", "s"),
            "stopTracker": _o("v"),
            "isActive": _o("b"),
            "getActiveTarget": _o("s"),
            "isNewTargetDetected": _o("b"),
            "isTargetLost": _o("b"),
            "getTargetPosition": (Overload("[d]", ()), Overload("[d]", ("i",))),
            "setMode": _o("v", "s"),
            "getMode": _o("s"),
            "setMaximumDistanceDetection": _o("v", "d"),
            "getMaximumDistanceDetection": _o("d"),
            "lookAt": _o("v", "[d]", "i", "d", "b"),
            "pointAt": _o("v", "s", "[d]", "i", "d"),
        },
        LOCALIZATION: {
            "learnHome": _o("i"),
            "localize": _o("i"),
            "goToHome": _o("i"),
            "getRobotPosition": _o("[d]"),
            "isDataAvailable": _o("b"),
        },
    }
)

SERVICES: Final[dict[str, dict[str, tuple[Overload, ...]]]] = {
    name: {**MODULE_METHODS, **methods} for name, methods in _SERVICES.items()
}
SERVICES[SIM] = {
    "true_pose": _o("[d]"),
    "teleport": _o("v", "d", "d", "d"),
    "room_size": _o("[d]"),
    "is_free": _o("b", "d", "d", "d"),
    "sim_time": _o("d"),
    "true_camera_pose": _o("[d]", "i"),
}
SERVICES[WATCHDOG] = {"ping": _o("b")}

# Calls that start a walk that keeps going after the call returns (dead-man applies),
# and blocking walks (dead-man applies while they run).
STARTS_MOTION: Final = frozenset(
    {(MOTION, "move"), (MOTION, "moveToward"), (MOTION, "setWalkTargetVelocity")}
)
BLOCKING_WALKS: Final = frozenset(
    {
        (MOTION, "moveTo"),
        (MOTION, "walkTo"),
        (NAVIGATION, "navigateTo"),
        (NAVIGATION, "moveAlong"),
        (LOCALIZATION, "learnHome"),
        (LOCALIZATION, "localize"),
        (LOCALIZATION, "goToHome"),
    }
)
# Calls after which no walk started by a client is running any more.
ENDS_MOTION: Final = frozenset(
    {
        (MOTION, "stopMove"),
        (MOTION, "killMove"),
        (MOTION, "killAll"),
        (MOTION, "stopWalk"),
        (MOTION, "rest"),
        (MOTION, "waitUntilMoveIsFinished"),
        (POSTURE, "stopMove"),
        (POSTURE, "goToPosture"),
        (POSTURE, "applyPosture"),
        (NAVIGATION, "stopNavigateTo"),
    }
)

_INT32 = (-(1 << 31), (1 << 31) - 1)


def _matches(sig: str, value: Any) -> bool:
    if sig in ("m", "o"):
        return True
    if sig == "b":
        return isinstance(value, bool) or (isinstance(value, int) and value in (0, 1))
    if sig == "i":
        return (
            isinstance(value, int)
            and not isinstance(value, bool)
            and _INT32[0] <= value <= _INT32[1]
        )
    if sig in ("d", "f"):
        return isinstance(value, int | float) and not isinstance(value, bool)
    if sig == "s":
        return isinstance(value, str)
    if sig.startswith("[") and sig.endswith("]"):
        return isinstance(value, list) and all(_matches(sig[1:-1], v) for v in value)
    return False


def _convert(sig: str, value: Any) -> Any:
    if sig == "b":
        return bool(value)
    if sig in ("d", "f"):
        return float(value)
    return value


def select_overload(service: str, method: str, args: list[Any]) -> list[Any]:
    """Check call arguments against the method's signatures; return them converted.

    Args:
        service: Service name, e.g. "ALMotion".
        method: Method name, e.g. "moveTo".
        args: Decoded arguments.

    Returns:
        The arguments converted to the parameter types (ints to floats for ``d``...).

    Raises:
        RobotError: Unknown service or method, or no overload accepts the arguments.
    """
    methods = SERVICES.get(service)
    if methods is None:
        raise RobotError(f"unknown service {service!r}")
    overloads = methods.get(method)
    if overloads is None:
        raise RobotError(f"{service} has no method {method!r}")
    for overload in overloads:
        if len(overload.params) == len(args) and all(
            _matches(p, a) for p, a in zip(overload.params, args, strict=True)
        ):
            return [_convert(p, a) for p, a in zip(overload.params, args, strict=True)]
    shapes = " or ".join("(" + ", ".join(o.params) + ")" for o in overloads)
    raise RobotError(f"{service}.{method}: arguments do not match {shapes}")
