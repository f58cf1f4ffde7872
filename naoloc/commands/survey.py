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

from naoloc.behaviours.survey import SurveyResult, frames_per_lap, survey
from naoloc.config import Config
from naoloc.dataset import DatasetWriter, interruption_reason
from naoloc.errors import NaolocError
from naoloc.geometry import Pose2D
from naoloc.interrupt import interruptible
from naoloc.keyframe import Keyframe
from naoloc.live import NO_LIVE, LiveView, live_from_args, watch
from naoloc.progress import Progress
from naoloc.registry import connect
from naoloc.robot import Robot

__all__ = ["config_path_for", "interruptible", "record_survey", "run"]


def config_path_for(output: Path) -> Path:
    """Where the resolved config of an output file goes: ``NAME.config.yaml`` beside it."""
    return output.with_name(output.stem + ".config.yaml")


def record_survey(
    robot: Robot,
    cfg: Config,
    output: Path,
    progress: Progress | None = None,
    live: LiveView = NO_LIVE,
) -> tuple[SurveyResult, int]:
    """Run the survey on ``robot`` and write every frame as it is taken.

    Frames go to ``DATASET.partial.mcap``; only when the survey completes all its laps does
    the file become ``output`` (atomically). When it does not (an exception, Ctrl-C,
    SIGTERM), the partial file is kept, marked incomplete, and the exception gets a note
    (``err.add_note``) saying where the partial data is; ``output`` is not touched. See
    :func:`naoloc.behaviours.survey.survey` for where the head yaw comes from.

    Args:
        robot: The robot, where the survey starts.
        cfg: The resolved config (stored in the dataset, without secrets).
        output: The ``.mcap`` file.
        progress: Progress bar advanced per frame.
        live: Shows the keyframe poses as they are taken (``--live``).

    Returns:
        The survey summary and the number of wall pictures written (the far pictures,
        ``result.far_frames``, come beside them).
    """
    holder: dict[str, DatasetWriter] = {}
    taken: list[tuple[float, float, float]] = []

    def on_start(meta: dict[str, Any]) -> None:
        holder["w"] = DatasetWriter(output, config=cfg.to_dict(), meta=meta)

    def on_frame(keyframe: Keyframe, lap: int, odometry: Pose2D) -> None:
        holder["w"].write(keyframe, lap=lap, odometry=odometry)
        if live is not NO_LIVE:
            taken.append((keyframe.pose.x, keyframe.pose.y, keyframe.pose.theta))
            live.map(np.asarray(taken))

    def on_far(keyframe: Keyframe, lap: int, stop: int, odometry: Pose2D) -> None:
        holder["w"].write(keyframe, lap=lap, odometry=odometry, stop=stop)

    try:
        result = survey(
            robot, cfg, on_frame, on_start=on_start,
            progress=None if progress is None else progress.update, on_far=on_far,
        )  # fmt: skip
    except BaseException as err:
        writer = holder.get("w")
        if writer is not None:
            try:
                kept = writer.close(complete=False, reason=interruption_reason(err))
            except NaolocError as failed:
                err.add_note(f"the partial dataset could not be finished: {failed}")
            else:
                if kept is not None:
                    err.add_note(f"partial dataset ({writer.wall_frames} frames) kept in {kept}")
        raise
    writer = holder.get("w")
    if writer is None:
        return result, 0
    writer.update_meta(result.meta)  # with what the survey measured (vision, metric scale)
    if result.laps < cfg.survey.laps:  # not expected: survey() walks every lap or raises
        writer.close(complete=False, reason=f"{result.laps} of {cfg.survey.laps} laps")
    else:
        writer.close(complete=True)
    return result, writer.wall_frames


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Survey the room and write ``args.output`` (MCAP) and its resolved config beside it."""
    from naoloc.cli import write_resolved_config

    output: Path = args.output
    sides = cfg.survey_sides()
    expected = frames_per_lap(sides, cfg.survey.step_m) * cfg.survey.laps
    live = live_from_args(args)
    with interruptible(), live, connect(cfg) as robot, Progress(expected, "survey") as bar:
        result, frames = record_survey(watch(robot, live), cfg, output, bar, live)
    if frames > 0:  # the config copy goes with the dataset it describes
        write_resolved_config(cfg, config_path_for(output))
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
    }
