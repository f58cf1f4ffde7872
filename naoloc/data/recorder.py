"""The survey recorder: the survey behaviour's frames written to a dataset as they come.

Frames go to ``DATASET.partial.mcap`` while the survey runs; the file becomes the dataset
only when every lap completes. ``naoloc survey``, ``naoloc demo`` and the evaluation all
record through :func:`record_survey`.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from naoloc.behaviours.survey import SurveyResult, survey
from naoloc.config import Config
from naoloc.data.dataset import DatasetWriter, interruption_reason
from naoloc.errors import NaolocError
from naoloc.geometry import Pose2D
from naoloc.robot import Robot
from naoloc.robot.keyframe import Keyframe


def record_survey(
    robot: Robot,
    cfg: Config,
    output: Path,
    progress: Callable[[int], None] | None = None,
    on_keyframe: Callable[[Keyframe], None] | None = None,
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
        progress: Called with 1 per frame taken (a progress bar's ``update``).
        on_keyframe: Called with each wall picture once it is written (e.g. ``--live``).

    Returns:
        The survey summary and the number of wall pictures written (the far pictures,
        ``result.far_frames``, come beside them).
    """
    holder: dict[str, DatasetWriter] = {}

    def on_start(meta: dict[str, Any]) -> None:
        holder["w"] = DatasetWriter(output, config=cfg.to_dict(), meta=meta)

    def on_frame(keyframe: Keyframe, lap: int, odometry: Pose2D) -> None:
        holder["w"].write(keyframe, lap=lap, odometry=odometry)
        if on_keyframe is not None:
            on_keyframe(keyframe)

    def on_far(keyframe: Keyframe, lap: int, stop: int, odometry: Pose2D) -> None:
        holder["w"].write(keyframe, lap=lap, odometry=odometry, stop=stop)

    result = SurveyResult()
    try:
        survey(
            robot, cfg, on_frame, on_start=on_start,
            progress=progress, on_far=on_far, result=result,
        )  # fmt: skip
    except BaseException as err:
        writer = holder.get("w")
        if writer is not None:
            try:
                writer.update_meta(result.meta)  # what it measured until it stopped
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
