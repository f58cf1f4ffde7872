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
SIM: Final = "NaolocSim"
WATCHDOG: Final = "NaolocWatchdog"

# Service name -> attribute of naoloc.robot.Robot that implements it.
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


SERVICES: Final[dict[str, dict[str, tuple[Overload, ...]]]] = {
    MOTION: {
        "wakeUp": _o("v"),
        "rest": _o("v"),
        "robotIsWakeUp": _o("b"),
        "setStiffnesses": _o("v", "m", "m"),
        "moveInit": _o("v"),
        "moveTo": (Overload("b", ("d", "d", "d")), Overload("b", ("m",))),
        "move": _o("v", "d", "d", "d"),
        "moveToward": _o("v", "d", "d", "d"),
        "waitUntilMoveIsFinished": _o("v"),
        "moveIsActive": _o("b"),
        "stopMove": _o("v"),
        "getRobotPosition": _o("[d]", "b"),
        "getNextRobotPosition": _o("[d]"),
        "getRobotVelocity": _o("[d]"),
        "setAngles": _o("v", "m", "m", "d"),
        "angleInterpolationWithSpeed": _o("v", "m", "m", "d"),
        "getAngles": _o("[d]", "m", "b"),
        "getPosition": _o("[d]", "s", "i", "b"),
        "getTransform": _o("[d]", "s", "i", "b"),
    },
    VIDEO: {
        "subscribeCamera": _o("s", "s", "i", "i", "i", "i"),
        "unsubscribe": _o("b", "s"),
        "getImageRemote": _o(IMAGE_SIGNATURE, "s"),
        "releaseImage": _o("v", "s"),
        "setActiveCamera": _o("b", "i"),
        "getActiveCamera": _o("i"),
        "getHorizontalFOV": _o("d", "i"),
        "getVerticalFOV": _o("d", "i"),
        "getResolution": _o("i", "s"),
        "getColorSpace": _o("i", "s"),
    },
    POSTURE: {
        "goToPosture": _o("b", "s", "d"),
        "getPosture": _o("s"),
        "getPostureList": _o("[s]"),
        "stopMove": _o("v"),
    },
    SIM: {
        "true_pose": _o("[d]"),
        "teleport": _o("v", "d", "d", "d"),
        "room_size": _o("[d]"),
        "is_free": _o("b", "d", "d", "d"),
        "sim_time": _o("d"),
        "true_camera_pose": _o("[d]", "i"),
    },
    WATCHDOG: {
        "ping": _o("b"),
    },
}

# Calls that start a motion that keeps going after the call returns (dead-man applies).
STARTS_MOTION: Final = frozenset({(MOTION, "move"), (MOTION, "moveToward")})
# Calls after which no motion started by a client is running any more.
ENDS_MOTION: Final = frozenset(
    {
        (MOTION, "stopMove"),
        (MOTION, "rest"),
        (MOTION, "moveTo"),
        (MOTION, "waitUntilMoveIsFinished"),
        (POSTURE, "stopMove"),
        (POSTURE, "goToPosture"),
    }
)

_INT32 = (-(1 << 31), (1 << 31) - 1)


def _matches(sig: str, value: Any) -> bool:
    if sig == "m":
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
