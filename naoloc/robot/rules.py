"""NAOqi's argument rules and error texts, in one place for every simulated backend.

Names: a joint ("HeadYaw"), a chain ("Head", "LArm", "RArm", "LLeg", "RLeg"), a group
("Body", "Joints", "JointActuators", "Arms", "Legs") or a list of them, expanded in order.
Angles in radians, speeds as a fraction of each joint's maximum speed in (0, 1], walk
velocities in m/s and rad/s in FRAME_ROBOT.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, Final

from naoloc.constants import (
    CAMERA_FPS,
    CHAINS,
    COLORSPACE_LAYERS,
    JOINT_NAMES,
    MAX_STEP_THETA,
    MAX_STEP_X,
    MAX_STEP_Y,
    POSTURES,
    RESOLUTIONS,
    kBottomCamera,
    kTopCamera,
)
from naoloc.errors import RobotError

NAOQI_VERSION: Final = "2.8.6.23"  # the NAOqi release whose API naoloc mirrors (NAO V6)

GROUPS: Final[dict[str, tuple[str, ...]]] = {
    **CHAINS,
    "Joints": JOINT_NAMES,
    # LHipYawPitch and RHipYawPitch share one motor: NAOqi lists 25 actuators.
    "JointActuators": tuple(j for j in JOINT_NAMES if j != "RHipYawPitch"),
    "Actuators": tuple(j for j in JOINT_NAMES if j != "RHipYawPitch"),
    "Arms": CHAINS["LArm"] + CHAINS["RArm"],
    "Legs": CHAINS["LLeg"] + CHAINS["RLeg"],
}
HANDS: Final = ("LHand", "RHand")
# NAOqi's frame-rate range for subscribers (any whole number, not only 5/10/15/30).
FPS_RANGE: Final = (1, 30)
MAX_SUBSCRIBERS: Final = 64  # camera subscribers at once
MOVE_CONFIG_KEYS: Final = {
    "MaxStepX": MAX_STEP_X,
    "MaxStepY": MAX_STEP_Y,
    "MaxStepTheta": MAX_STEP_THETA,
    "MaxStepFrequency": (1.0, 0.0, 1.0),
    "StepHeight": (0.020, 0.005, 0.040),
    "TorsoWx": (0.0, -0.122, 0.122),
    "TorsoWy": (0.0, -0.122, 0.122),
}
POSTURE_FAMILIES: Final[dict[str, str]] = {
    "Stand": "Standing",
    "StandInit": "Standing",
    "StandZero": "Standing",
    "Crouch": "Crouching",
    "Sit": "Sitting",
    "SitRelax": "Sitting",
    "LyingBelly": "LyingBelly",
    "LyingBack": "LyingBack",
    "Unknown": "Unknown",
}


def expand_names(names: Any, what: str = "names") -> list[str]:
    """Expand a joint, chain or group name, or a list of them, into joint names.

    Raises:
        RobotError: A name that is neither a joint nor a chain or group, or an empty list.
    """
    items = [names] if isinstance(names, str) else names
    if not isinstance(items, Sequence) or isinstance(items, bytes | bytearray):
        raise RobotError(f"{what} must be a joint or chain name or a list of them, got {names!r}")
    out: list[str] = []
    for item in items:
        if not isinstance(item, str):
            raise RobotError(f"{what} must be strings, got {item!r}")
        if item in GROUPS:
            out.extend(GROUPS[item])
        elif item in JOINT_NAMES:
            out.append(item)
        else:
            raise RobotError(f"unknown joint or chain name {item!r}")
    if not out:
        raise RobotError(f"{what}: no joint names given")
    return out


def finite(value: Any, what: str) -> float:
    """``value`` as a finite float.

    Raises:
        RobotError: Not a number, or NaN / infinite.
    """
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise RobotError(f"{what} must be a number, got {value!r}")
    out = float(value)
    if not math.isfinite(out):
        raise RobotError(f"{what} must be finite, got {value!r}")
    return out


def per_joint(values: Any, count: int, what: str) -> list[float]:
    """One finite float per joint: a number is repeated, a list must have ``count`` items.

    Raises:
        RobotError: Wrong count or non-finite values.
    """
    if isinstance(values, int | float) and not isinstance(values, bool):
        return [finite(values, what)] * count
    if not isinstance(values, Sequence) or isinstance(values, str | bytes | bytearray):
        raise RobotError(f"{what} must be a number or a list of numbers, got {values!r}")
    out = [finite(v, what) for v in values]
    if len(out) == 1 and count > 1:
        return out * count
    if len(out) != count:
        raise RobotError(f"{count} joint names but {len(out)} {what}")
    return out


def fraction(value: Any, what: str = "speed fraction") -> float:
    """A speed fraction in (0, 1].

    Raises:
        RobotError: Outside (0, 1] or not finite.
    """
    out = finite(value, what)
    if not 0.0 < out <= 1.0:
        raise RobotError(f"{what} must be in (0, 1], got {value}")
    return out


def move_config(config: Any) -> dict[str, float]:
    """A NAOqi moveConfig ``[["MaxStepX", 0.04], ...]`` (or a dict) checked against the limits.

    Raises:
        RobotError: Malformed, an unknown parameter, or a value outside NAOqi's range.
    """
    if config is None:
        return {}
    try:
        pairs = list(config.items()) if isinstance(config, dict) else [tuple(p) for p in config]
        if any(len(p) != 2 for p in pairs):
            raise ValueError
    except (TypeError, ValueError):
        raise RobotError(f"moveConfig must be [[name, value], ...], got {config!r}") from None
    out: dict[str, float] = {}
    for name, value in pairs:
        limits = MOVE_CONFIG_KEYS.get(str(name))
        if limits is None:
            raise RobotError(
                f"unknown moveConfig parameter {name!r}; valid: {sorted(MOVE_CONFIG_KEYS)}"
            )
        v = finite(value, f"moveConfig {name}")
        if not limits[1] <= v <= limits[2]:
            raise RobotError(f"moveConfig {name} must be in [{limits[1]}, {limits[2]}], got {v}")
        out[str(name)] = v
    return out


def move_to_points(args: Sequence[Any]) -> tuple[list[list[float]], dict[str, float]]:
    """Parse the moveTo overloads into control points (FRAME_ROBOT) and a moveConfig.

    Forms: ``(x, y, theta)``, ``(x, y, theta, moveConfig)``, ``([[x, y, theta], ...])``,
    ``([[x, y, theta], ...], moveConfig)``; metres and radians.

    Raises:
        RobotError: Any other shape, or values that are not finite.
    """
    usage = "moveTo takes (x, y, theta[, moveConfig]) or ([[x, y, theta], ...][, moveConfig])"
    config: Any = None
    if len(args) in (3, 4) and all(isinstance(a, int | float) for a in args[:3]):
        points = [[finite(a, "moveTo target") for a in args[:3]]]
        config = args[3] if len(args) == 4 else None
    elif len(args) in (1, 2) and isinstance(args[0], Sequence) and args[0]:
        raw = list(args[0])
        if all(isinstance(v, int | float) for v in raw):
            raw = [raw]
        points = []
        for p in raw:
            if not isinstance(p, Sequence) or len(p) != 3:
                raise RobotError(usage)
            points.append([finite(v, "moveTo target") for v in p])
        config = args[1] if len(args) == 2 else None
    else:
        raise RobotError(usage)
    return points, move_config(config)


def velocity(
    args: Sequence[Any], normalised: bool, method: str
) -> tuple[list[float], dict[str, float]]:
    """Parse ``(x, y, theta[, moveConfig])`` of move / moveToward.

    Raises:
        RobotError: Wrong shape, non-finite values, or a normalised value outside [-1, 1].
    """
    if len(args) not in (3, 4):
        raise RobotError(f"{method} takes (x, y, theta[, moveConfig])")
    values = [finite(a, f"{method} velocity") for a in args[:3]]
    if normalised and not all(-1.0 <= v <= 1.0 for v in values):
        raise RobotError(f"{method}: each component must be in [-1, 1], got {values}")
    return values, move_config(args[3] if len(args) == 4 else None)


def camera_index(index: Any) -> int:
    """A NAO camera index (0 top, 1 bottom).

    Raises:
        RobotError: Any other value (NAO has no depth camera).
    """
    if (
        isinstance(index, bool)
        or not isinstance(index, int)
        or index not in (kTopCamera, kBottomCamera)
    ):
        raise RobotError(f"camera index {index!r} does not exist on NAO (0 top, 1 bottom)")
    return int(index)


def subscription(resolution: Any, colorspace: Any, fps: Any) -> tuple[int, int, int]:
    """Check a subscriber's resolution id, colorspace id and frame rate (1-30).

    Raises:
        RobotError: Unknown ids or a frame rate outside 1-30.
    """
    if resolution not in RESOLUTIONS or isinstance(resolution, bool):
        raise RobotError(f"unknown resolution id {resolution!r}; valid: {sorted(RESOLUTIONS)}")
    if colorspace not in COLORSPACE_LAYERS or isinstance(colorspace, bool):
        raise RobotError(
            f"unknown colorspace id {colorspace!r}; valid: {sorted(COLORSPACE_LAYERS)}"
        )
    if isinstance(fps, bool) or not isinstance(fps, int) or not FPS_RANGE[0] <= fps <= FPS_RANGE[1]:
        raise RobotError(f"fps must be a whole number in [1, 30], got {fps!r}")
    return int(resolution), int(colorspace), int(fps)


def backend_fps(fps: int) -> int:
    """The nearest frame rate the simulated cameras render at (5, 10, 15 or 30)."""
    return min(CAMERA_FPS, key=lambda f: (abs(f - fps), f))


def posture_name(name: Any) -> str:
    """A predefined posture name.

    Raises:
        RobotError: Any other name (listing the valid ones).
    """
    if not isinstance(name, str) or name not in POSTURES:
        raise RobotError(f"unknown posture {name!r}; valid: {', '.join(POSTURES)}")
    return name


def hand_name(name: Any) -> str:
    """ "LHand" or "RHand".

    Raises:
        RobotError: Any other name.
    """
    if name not in HANDS:
        raise RobotError(f"hand name must be LHand or RHand, got {name!r}")
    return str(name)


def error_line(service: str, method: str, err: BaseException) -> str:
    """NAOqi-style one-line error text: ``"<Type>: <Service>.<method>: <problem>"``.

    The naoloc error type comes first so naoloc's clients map it back; the text never
    holds a traceback or a server path.
    """
    message = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
    for prefix in (f"{service}.{method}: ", f"{method}: "):
        if message.startswith(prefix):
            message = message[len(prefix) :]
    kind = type(err).__name__
    from naoloc.errors import NaolocError

    if not isinstance(err, NaolocError):
        kind = "RobotError"
        message = f"internal error ({type(err).__name__}: {message})"
    return f"{kind}: {service}.{method}: {message}"


def _speeds() -> dict[str, float]:
    pitch, roll, yaw = 8.26797, 7.19407, 8.26797
    out = {"HeadYaw": 8.26797, "HeadPitch": 7.19407}
    for s in "LR":
        out.update({
            f"{s}ShoulderPitch": pitch, f"{s}ShoulderRoll": roll, f"{s}ElbowYaw": yaw,
            f"{s}ElbowRoll": roll, f"{s}WristYaw": 24.6229, f"{s}Hand": 8.33,
            f"{s}HipYawPitch": 4.16174, f"{s}HipRoll": 4.16174, f"{s}HipPitch": 6.40239,
            f"{s}KneePitch": 6.40239, f"{s}AnklePitch": 6.40239, f"{s}AnkleRoll": 4.16174,
        })  # fmt: skip
    return out


# Maximum joint speeds (rad/s) of NAO's motors, as NAOqi's getLimits reports them.
JOINT_MAX_SPEED: Final[dict[str, float]] = _speeds()


def keyframes(
    joints: list[str], values: Any, times: Any, what: str
) -> list[list[tuple[float, float]]]:
    """Parse angleInterpolation-style key frames: per joint ``[(time s, value), ...]``.

    One joint takes a number or a list for values and times; several joints take one
    list per joint (a single list of times is shared). Times must increase and be > 0.

    Raises:
        RobotError: Shapes that do not match the names, or times that do not increase.
    """

    def as_list(v: Any) -> list[Any]:
        return [v] if isinstance(v, int | float) and not isinstance(v, bool) else list(v)

    n = len(joints)

    def numbers(v: Any) -> bool:
        return isinstance(v, list | tuple) and all(
            isinstance(x, int | float) and not isinstance(x, bool) for x in v
        )

    try:
        if n == 1:
            value_lists = [as_list(values)]
            time_lists = [as_list(times)]
        else:
            if isinstance(values, int | float) and not isinstance(values, bool):
                value_lists = [[values]] * n
            elif numbers(values) and len(values) in (1, n):
                value_lists = [[v] for v in values] if len(values) == n else [list(values)] * n
            else:
                value_lists = [as_list(v) for v in values]
            if isinstance(times, int | float) and not isinstance(times, bool):
                time_lists = [[times]] * n
            elif numbers(times) and all(len(v) == 1 for v in value_lists) and len(times) == n:
                time_lists = [[t] for t in times]
            elif numbers(times):
                time_lists = [list(times)] * n
            else:
                time_lists = [as_list(t) for t in times]
    except TypeError:
        raise RobotError(f"{what}: values and times must be numbers or lists") from None
    if len(value_lists) != len(joints) or len(time_lists) != len(joints):
        raise RobotError(f"{what}: {len(joints)} joint names but {len(value_lists)} lists")
    out = []
    for joint, vals, ts in zip(joints, value_lists, time_lists, strict=True):
        if len(vals) != len(ts) or not vals:
            raise RobotError(f"{what}: {joint} has {len(vals)} values but {len(ts)} times")
        keys = [
            (finite(t, f"{what} time"), finite(v, f"{what} value"))
            for t, v in zip(ts, vals, strict=True)
        ]
        previous = 0.0
        for t, _ in keys:
            if t <= previous:
                raise RobotError(f"{what}: times must be > 0 and increasing, got {ts}")
            previous = t
        out.append(keys)
    return out
