"""naoloc: a NAO humanoid learns a room and finds itself in it from what its camera sees.

Quick start::

    import naoloc
    with naoloc.connect("configs/sim_paper_room.yaml") as robot:
        robot.motion.moveTo(0.4, 0.0, 0.0)
        x, y, theta = robot.motion.getRobotPosition(True)

Importing naoloc imports no simulator, SDK or network library.
"""

from __future__ import annotations

from naoloc.config import Config, load_config
from naoloc.errors import (
    BackendError,
    ConfigError,
    ConnectionLost,
    DatasetError,
    DependencyNotInstalled,
    HandleError,
    MapFormatError,
    NaolocError,
    RobotError,
)
from naoloc.geometry import Pose2D, modulo2PI, pose2DInverse
from naoloc.robot import Motion, Posture, Robot, SimControl, VideoDevice
from naoloc.robot.image import Frame, frame_from_naoqi
from naoloc.robot.registry import backend_names, connect

__version__ = "0.1.0"

__all__ = [
    "BackendError",
    "Config",
    "ConfigError",
    "ConnectionLost",
    "DatasetError",
    "DependencyNotInstalled",
    "Frame",
    "HandleError",
    "MapFormatError",
    "Motion",
    "NaolocError",
    "Pose2D",
    "Posture",
    "Robot",
    "RobotError",
    "SimControl",
    "VideoDevice",
    "__version__",
    "backend_names",
    "connect",
    "frame_from_naoqi",
    "load_config",
    "modulo2PI",
    "pose2DInverse",
]
