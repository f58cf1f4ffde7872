"""``naoloc survey -c CFG -o DATASET.mcap``: Algorithm 3, recorded as an MCAP dataset.

Frames are written as they are taken; Ctrl-C or an error mid-survey stops the robot and
leaves a dataset that ``build-map`` reads with every frame taken so far.
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import threading
from collections.abc import Iterator
from pathlib import Path
from types import FrameType
from typing import Any

from naoloc.behaviours.survey import SurveyResult, frames_per_lap, survey
from naoloc.config import Config
from naoloc.dataset import DatasetWriter
from naoloc.geometry import Pose2D
from naoloc.keyframe import Keyframe
from naoloc.progress import Progress
from naoloc.registry import connect
from naoloc.robot import Robot


@contextlib.contextmanager
def interruptible() -> Iterator[None]:
    """Make SIGINT and SIGTERM raise KeyboardInterrupt inside the block, then restore.

    A robot command must stop the robot on Ctrl-C even when started from a shell that
    ignores SIGINT in background jobs, and on a plain ``kill``. Only in the main thread.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def raise_interrupt(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt(f"signal {signum}")

    old_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    old_term = signal.signal(signal.SIGTERM, raise_interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old_int)
        signal.signal(signal.SIGTERM, old_term)


def config_path_for(output: Path) -> Path:
    """Where the resolved config of an output file goes: ``NAME.config.yaml`` beside it."""
    return output.with_name(output.stem + ".config.yaml")


def record_survey(
    robot: Robot, cfg: Config, output: Path, progress: Progress | None = None
) -> tuple[SurveyResult, int]:
    """Run the survey on ``robot`` and write every frame to ``output`` as it is taken.

    See :func:`naoloc.behaviours.survey.survey` for where the head yaw comes from.

    Args:
        robot: The robot, where the survey starts.
        cfg: The resolved config (stored in the dataset).
        output: The ``.mcap`` file.
        progress: Progress bar advanced per frame.

    Returns:
        The survey summary and the number of frames written.
    """
    holder: dict[str, DatasetWriter] = {}

    def on_start(meta: dict[str, Any]) -> None:
        holder["w"] = DatasetWriter(output, config=cfg.to_dict(), meta=meta)

    def on_frame(keyframe: Keyframe, lap: int, odometry: Pose2D) -> None:
        holder["w"].write(keyframe, lap=lap, odometry=odometry)

    try:
        result = survey(
            robot, cfg, on_frame, on_start=on_start,
            progress=None if progress is None else progress.update,
        )  # fmt: skip
        if "w" in holder:  # with what the survey measured on the way (vision, metric scale)
            holder["w"].update_meta(result.meta)
    finally:
        if "w" in holder:
            holder["w"].close()
    return result, holder["w"].frames if "w" in holder else 0


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Survey the room and write ``args.output`` (MCAP) and its resolved config beside it."""
    from naoloc.cli import write_resolved_config

    output: Path = args.output
    write_resolved_config(cfg, config_path_for(output))
    sides = cfg.survey_sides()
    expected = frames_per_lap(sides, cfg.survey.step_m) * cfg.survey.laps
    with interruptible(), connect(cfg) as robot, Progress(expected, "survey") as bar:
        result, frames = record_survey(robot, cfg, output, bar)
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
        f"survey: {frames} frames in {result.laps} laps of {sides[0]:.2f} x {sides[1]:.2f} m, "
        f"{detected}{result.meta.get('direction', '?')} circuit, {result.path_m:.1f} m walked, "
        f"{result.wall_s:.1f} s -> {output}"
    )
    return {
        "frames": frames,
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
