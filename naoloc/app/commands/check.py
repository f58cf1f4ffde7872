"""``naoloc check -c CFG [--nod]``: is this robot ready for a survey? Nothing walks.

Connects and reads, without a single motion call: the link, the camera (one image, its
size and brightness, the lens naoloc assumes), odometry (sensors and commands), the
head joints and the camera's place from the robot's kinematics, the posture, whether
the robot is awake, and the battery (ALBattery, on a network robot). With ``--nod`` the
head alone nods (HeadPitch down 0.15 rad and back, a slow head interpolation), to show
the joints answer. It checks the config a survey would walk (offset, rectangle, a real
robot's ``survey.side_m``) and says how long the survey would walk.

Prints one line per item (``check: camera: ok, ...``) and the JSON line; exits 0 when
nothing is missing, 4 otherwise (the JSON line is still printed, ``missing`` says what).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from naoloc.config import Config
from naoloc.errors import NaolocError
from naoloc.robot import Robot

LOW_BATTERY_PERCENT = 30  # below this a 3-lap survey may not finish (a NAO walks ~60 min)
NOD_RAD = 0.15  # HeadPitch nod amplitude (down, then back)
NOD_SPEED = 0.1  # fraction of the head's maximum joint speed
DARK_MEAN = 20.0  # mean grey level (0-255) under which the image is too dark to map
PICTURE_S = 2.0  # s a survey stop takes (stop, settle, picture), besides walking


class CheckFailed(NaolocError):
    """``naoloc check`` found something missing (exit 4; the JSON line is printed).

    Attributes:
        result: The JSON-able result line.
        exit_code: 4.
    """

    exit_code = 4

    def __init__(self, message: str, result: dict[str, Any]) -> None:
        """An error carrying the result line to print."""
        super().__init__(message)
        self.result = result


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Connect, read what a survey needs, print what is there and what is missing."""
    from naoloc.app.interrupt import interruptible
    from naoloc.robot.registry import connect

    found: dict[str, Any] = {}
    missing: list[str] = []
    found["survey"] = survey_plan(cfg, missing)
    with interruptible(), connect(cfg) as robot:
        found["link"] = {"backend": robot.backend, **_plain_info(robot.info)}
        _say("link", "ok", f"backend {robot.backend} {robot.info.get('url', '')}".strip())
        if robot.sim is None and cfg.survey.side_m is None:
            missing.append("survey.side_m: a real robot walks the rectangle you measured")
        for name, step in _STEPS:
            found[name] = _attempt(name, step, robot, cfg, missing)
        if getattr(args, "nod", False):
            found["nod"] = _attempt("nod", _nod, robot, cfg, missing)
    result = {"ok": not missing, "missing": missing, **found}
    if missing:
        _say("missing", "", "; ".join(missing))
        raise CheckFailed(f"{len(missing)} missing: {'; '.join(missing)}", result)
    _say("ready", "", "nothing missing: `naoloc survey` may walk")
    return result


def survey_plan(cfg: Config, missing: list[str]) -> dict[str, Any]:
    """What a survey with ``cfg`` walks and roughly for how long (at a NAO's 0.1 m/s).

    Args:
        cfg: The config.
        missing: Problems found are appended here.

    Returns:
        Sides (m), laps, path length (m), stops and minutes.
    """
    from naoloc.behaviours.wall_follow import MIN_OFFSET_M
    from naoloc.constants import WALK_SPEED

    sides = cfg.survey_sides()
    laps = cfg.survey.laps
    path = 2.0 * (sides[0] + sides[1]) * laps
    stops = math.ceil(path / cfg.survey.step_m)
    minutes = (path / WALK_SPEED + stops * PICTURE_S) / 60.0
    offset = cfg.survey.wall_offset_m
    if offset < MIN_OFFSET_M:
        missing.append(f"survey.wall_offset_m {offset:g} m: the survey needs {MIN_OFFSET_M:g} m")
    plan = {
        "side_m": [round(s, 3) for s in sides],
        "wall_offset_m": offset,
        "laps": laps,
        "path_m": round(path, 1),
        "stops": stops,
        "minutes": round(minutes, 1),
    }
    _say(
        "survey",
        "",
        f"{laps} laps of {sides[0]:g} x {sides[1]:g} m, {offset:g} m from the walls: "
        f"{path:.0f} m, {stops} pictures, about {minutes:.0f} min",
    )
    return plan


def _camera(robot: Robot, cfg: Config) -> dict[str, Any]:
    from naoloc.robot.camera import Camera, lens_of

    with Camera(robot, cfg.camera, "naoloc_check") as camera:
        frame = camera.frame()
    mean = float(np.mean(frame.gray()))
    model = lens_of(cfg)
    fx, fy, cx, cy = model.at(frame.width, frame.height)
    lens = {"fx": fx, "fy": fy, "cx": cx, "cy": cy, "k1": model.to_dict()["k1"]}
    lens = {k: round(float(v), 3) for k, v in lens.items()}
    out = {
        "width": frame.width,
        "height": frame.height,
        "colorspace": frame.colorspace,
        "index": frame.camera,
        "mean_grey": round(mean, 1),
        "lens": lens,
    }
    if mean < DARK_MEAN:
        raise _Missing(f"camera: the image is dark (mean grey {mean:.0f} of 255): light the room")
    _say(
        "camera", "ok", f"{frame.width}x{frame.height}, camera {frame.camera}, mean grey {mean:.0f}"
    )
    return out


def _odometry(robot: Robot, cfg: Config) -> dict[str, Any]:
    sensors = [float(v) for v in robot.motion.getRobotPosition(True)]
    commands = [float(v) for v in robot.motion.getRobotPosition(False)]
    if len(sensors) != 3 or not all(math.isfinite(v) for v in sensors + commands):
        raise _Missing(f"odometry: getRobotPosition answered {sensors}")
    _say("odometry", "ok", f"({sensors[0]:.2f}, {sensors[1]:.2f}, {sensors[2]:.2f}) odom frame")
    return {"sensors": _rounded(sensors), "commands": _rounded(commands)}


def _joints(robot: Robot, cfg: Config) -> dict[str, Any]:
    from naoloc.constants import FRAME_ROBOT

    yaw, pitch = (float(a) for a in robot.motion.getAngles(["HeadYaw", "HeadPitch"], True))
    name = "CameraTop" if cfg.camera.index == 0 else "CameraBottom"
    transform = [float(v) for v in robot.motion.getTransform(name, FRAME_ROBOT, True)]
    if len(transform) != 16 or not all(math.isfinite(v) for v in (yaw, pitch, *transform)):
        raise _Missing("joints: the head angles or the camera's transform are not finite")
    height = transform[11]
    _say("joints", "ok", f"head yaw {yaw:.2f} pitch {pitch:.2f} rad, {name} {height:.2f} m high")
    return {
        "head_yaw": round(yaw, 4),
        "head_pitch": round(pitch, 4),
        "camera_z_m": round(height, 3),
    }


def _posture(robot: Robot, cfg: Config) -> dict[str, Any]:
    posture = str(robot.posture.getPosture())
    awake = bool(robot.motion.robotIsWakeUp())
    note = "awake" if awake else "at rest (the survey wakes it and stands it up)"
    _say("posture", "ok", f"{posture}, {note}")
    return {"posture": posture, "awake": awake}


def _battery(robot: Robot, cfg: Config) -> dict[str, Any]:
    if robot.read is None:
        _say("battery", "ok", "a simulator: no battery")
        return {"charge_percent": None}
    charge = robot.read("ALBattery", "getBatteryCharge")
    if charge is None:
        raise _Missing("battery: the robot serves no ALBattery")
    charge = int(charge)
    if charge < LOW_BATTERY_PERCENT:
        raise _Missing(f"battery: {charge} % (charge it to {LOW_BATTERY_PERCENT} % or more)")
    _say("battery", "ok", f"{charge} %")
    return {"charge_percent": charge}


def _nod(robot: Robot, cfg: Config) -> dict[str, Any]:
    """The head alone: stiffen it, HeadPitch down :data:`NOD_RAD` and back."""
    motion = robot.motion
    start = float(motion.getAngles(["HeadPitch"], True)[0])
    motion.setStiffnesses("Head", 1.0)
    motion.angleInterpolationWithSpeed(["HeadPitch"], [start + NOD_RAD], NOD_SPEED)
    low = float(motion.getAngles(["HeadPitch"], True)[0])
    motion.angleInterpolationWithSpeed(["HeadPitch"], [start], NOD_SPEED)
    moved = low - start
    if moved < NOD_RAD / 2:
        raise _Missing(f"nod: HeadPitch moved {moved:.3f} rad of {NOD_RAD} (stiffness off?)")
    _say("nod", "ok", f"HeadPitch moved {moved:.2f} rad and back")
    return {"moved_rad": round(moved, 3)}


_Step = Callable[[Robot, Config], dict[str, Any]]
_STEPS: tuple[tuple[str, _Step], ...] = (
    ("camera", _camera),
    ("odometry", _odometry),
    ("joints", _joints),
    ("posture", _posture),
    ("battery", _battery),
)


class _Missing(Exception):
    """A check step found something missing (its message says what)."""


def _attempt(name: str, step: _Step, robot: Robot, cfg: Config, missing: list[str]) -> Any:
    """Run one step; a failure is one ``missing`` entry, not the end of the check."""
    try:
        return step(robot, cfg)
    except _Missing as err:
        missing.append(str(err))
    except (NaolocError, OSError) as err:  # a service refused or the link dropped
        missing.append(f"{name}: {type(err).__name__}: {' '.join(str(err).split())}")
    _say(name, "MISSING", missing[-1])
    return None


def _say(item: str, state: str, text: str) -> None:
    print(f"check: {item}: {state + ', ' if state else ''}{text}", flush=True)


def _plain_info(info: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in info.items() if isinstance(v, (str, int, float, bool))}


def _rounded(values: list[float]) -> list[float]:
    return [round(v, 4) for v in values]
