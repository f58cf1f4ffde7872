"""``naoloc survey -c CFG -o DATASET.mcap``: Algorithm 3, recorded as an MCAP dataset.

Frames are written to ``DATASET.partial.mcap`` as they are taken; a survey that completes
all its laps becomes ``DATASET.mcap`` (with ``DATASET.config.yaml`` beside it). Ctrl-C,
SIGTERM or an error mid-survey stops the robot and keeps ``DATASET.partial.mcap``, marked
incomplete, beside any complete ``DATASET.mcap``, which is left as it was; the one-line
error says where the partial data is, and ``build-map -d DATASET.partial.mcap`` reads it.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from naoloc.app.interrupt import interruptible
from naoloc.behaviours.survey import check_offset, frames_per_lap
from naoloc.config import Config
from naoloc.data.outputs import config_path_for, write_resolved_config
from naoloc.data.recorder import record_survey
from naoloc.errors import ConfigError
from naoloc.robot.keyframe import Keyframe
from naoloc.robot.registry import connect
from naoloc.viz.live import NO_LIVE, live_from_args, watch
from naoloc.viz.progress import Progress

__all__ = ["check_before_walking", "run"]


def ros2_copy(args: argparse.Namespace, written: Path) -> Path | None:
    """``--format ros2``: ``NAME.ros2.mcap`` beside ``written``, as ROS 2 messages."""
    if getattr(args, "format", "naoloc") != "ros2":
        return None
    from naoloc.data.ros2 import write_ros2

    target = written.with_suffix(".ros2.mcap")
    write_ros2(written, target)
    return target


def check_before_walking(cfg: Config) -> None:
    """What the config alone tells, before connecting: an offset the survey keeps, and a
    real robot's rectangle measured rather than taken from the simulated room's size.

    Raises:
        ConfigError: The offset is too small, or a real robot has no ``survey.side_m``.
    """
    check_offset(cfg.survey.wall_offset_m)
    if cfg.robot.backend == "naoqi" and not cfg.robot.sim_service and cfg.survey.side_m is None:
        raise ConfigError(
            "survey.side_m is not set: a real robot walks the rectangle you measured in your "
            "room (docs/real-nao.md), not one derived from world.room.size_m"
        )


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Survey the room and write ``args.output`` (MCAP) and its resolved config beside it."""
    output: Path = args.output
    check_before_walking(cfg)
    sides = cfg.survey_sides()
    expected = frames_per_lap(sides, cfg.survey.step_m) * cfg.survey.laps
    live = live_from_args(args)
    taken: list[tuple[float, float, float]] = []

    def show(keyframe: Keyframe) -> None:
        taken.append((keyframe.pose.x, keyframe.pose.y, keyframe.pose.theta))
        live.map(np.asarray(taken))

    on_keyframe = None if live is NO_LIVE else show
    with interruptible(), live, connect(cfg) as robot, Progress(expected, "survey") as bar:
        result, frames = record_survey(watch(robot, live), cfg, output, bar.update, on_keyframe)
    if frames > 0:  # the config copy goes with the dataset it describes
        write_resolved_config(cfg, config_path_for(output))
    ros2 = ros2_copy(args, output)
    wall, par = result.wall, result.parallax
    detected = ""
    if wall is not None:
        detected = f"paper's detector: {wall.side} ({wall.left} vs {wall.right} keypoints), "
    if par is not None:
        detected += (
            f"parallax: {par.side} (left {par.left_shift_px:.0f} px, "
            f"right {par.right_shift_px:.0f} px), "
        )
    detected += f"head yaw from the {result.yaw_source}, "
    follow = result.meta.get("wall_follow") or {}
    if follow:
        detected += f"{follow.get('steered_steps', 0)} steps steered by the floor line, "
    print(
        f"survey: {frames} frames (and {result.far_frames} far) in {result.laps} laps of "
        f"{sides[0]:.2f} x {sides[1]:.2f} m, "
        f"{detected}{result.meta.get('direction', '?')} circuit, {result.path_m:.1f} m walked, "
        f"{result.wall_s:.1f} s -> {output}"
    )
    return {
        "frames": frames,
        "far_frames": result.far_frames,
        "laps": result.laps,
        "path_m": round(result.path_m, 3),
        "wall_s": round(result.wall_s, 3),
        "dataset": str(output),
        "direction": result.meta.get("direction"),
        "head_yaw": round(result.head_yaw, 4),
        "head_yaw_source": result.yaw_source,
        "metric_scale": result.meta.get("metric_scale"),
        "wall_follow": result.meta.get("wall_follow"),
        **({"ros2": str(ros2)} if ros2 is not None else {}),
    }
