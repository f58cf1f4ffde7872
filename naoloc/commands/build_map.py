"""``naoloc build-map -c CFG -d DATASET.mcap -o MAP.npz``: Algorithm 4, plus a PNG of the map.

The map, its PNG and the config copy (``MAP.config.yaml``) are written under temporary
names and moved into place together once all three exist: a run that fails or is
interrupted leaves an older map, PNG and config copy as they were. A partial dataset (an
interrupted survey's ``DATASET.partial.mcap``) is read only when named, and said so.
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from naoloc.config import Config, MapConfig
from naoloc.dataset import read_dataset
from naoloc.errors import DatasetError
from naoloc.geometry import Pose2D
from naoloc.keyframe import Keyframe
from naoloc.outputs import staged
from naoloc.progress import Progress

# Fewest frames a map is built from: one or two pictures give no place to tell apart.
MIN_MAP_FRAMES = 3
# A survey's metric scale outside this range is a failed measurement, not the odometry.
SCALE_RANGE = (0.6, 1.6)


def apply_metric_scale(
    keyframes: list[Keyframe], meta: dict[str, Any]
) -> tuple[list[Keyframe], float | None]:
    """Scale the keyframes' odometry positions to metres, by the survey's ``metric_scale``.

    The survey measures it (metres per odometry metre) from the floor-wall line's
    distances, which the camera height from the kinematics makes metric
    (:func:`naoloc.behaviours.wall_follow.metric_scale`). Positions scale about the map
    origin (the survey start); headings are unchanged.

    Args:
        keyframes: Keyframes with odometry poses in the map frame.
        meta: The survey meta (``metric_scale`` may be missing or null).

    Returns:
        The keyframes to build from and the scale applied (None: left as they were).
    """
    scale = meta.get("metric_scale")
    if not isinstance(scale, (int, float)) or not SCALE_RANGE[0] <= scale <= SCALE_RANGE[1]:
        return keyframes, None
    k = float(scale)

    def scaled(p: Pose2D | None) -> Pose2D | None:
        return None if p is None else Pose2D(p.x * k, p.y * k, p.theta)

    out = [
        dataclasses.replace(kf, pose=Pose2D(kf.pose.x * k, kf.pose.y * k, kf.pose.theta),
                            command_pose=scaled(kf.command_pose))
        for kf in keyframes
    ]  # fmt: skip
    return out, k


def survey_keyframes(
    data: Any, cfg: MapConfig, offset: float | None = None
) -> tuple[list[Keyframe], dict[str, Any]]:
    """The keyframes a map is built from, with the poses ``cfg`` asks for.

    ``map.wall_poses`` (default): poses from the survey's walls
    (:func:`naoloc.wall_poses.wall_poses`), which also fixes the metric scale (the known
    circuit); a survey without floor-line records keeps its odometry. Otherwise, and
    ``map.apply_metric_scale``: odometry scaled by the survey's ``metric_scale``.

    Args:
        data: The :class:`naoloc.dataset.Dataset`.
        cfg: The map config.
        offset: ``survey.wall_offset_m`` when the dataset's own config lacks it.

    Returns:
        The keyframes and facts for the map's meta (``metric_scale``, ``wall_poses``).
    """
    from naoloc.wall_poses import wall_poses

    facts: dict[str, Any] = {"metric_scale": None, "wall_poses": None}
    if cfg.wall_poses:
        survey = data.config.get("survey") if isinstance(data.config, dict) else None
        value = survey.get("wall_offset_m") if isinstance(survey, dict) else None
        if isinstance(value, (int, float)) and value > 0:
            offset = float(value)  # the survey walked at its own offset
        walled = None if offset is None else wall_poses(data.keyframes, data.meta, offset=offset)
        if walled is not None:
            facts["wall_poses"] = walled.summary()
            return walled.keyframes, facts
    if cfg.apply_metric_scale:
        keyframes, facts["metric_scale"] = apply_metric_scale(data.keyframes, data.meta)
        return keyframes, facts
    return list(data.keyframes), facts


def far_keyframes(data: Any, keyframes: Sequence[Keyframe]) -> list[tuple[int, Keyframe]]:
    """The dataset's far pictures with their stops, posed as the map's keyframes are.

    A far picture is taken where its stop's wall picture was, the head turned: it takes
    that keyframe's pose (from the walls or the scaled odometry, :func:`survey_keyframes`)
    composed with the raw odometry from the wall picture to it.

    Args:
        data: The :class:`naoloc.dataset.Dataset`.
        keyframes: Its wall pictures as :func:`survey_keyframes` posed them.
    """
    from naoloc.mapping.builder import carried

    out = []
    for stop, kf in data.far:
        pose = carried(keyframes[stop].pose, data.keyframes[stop].pose, kf.pose)
        out.append((stop, dataclasses.replace(kf, pose=pose)))
    return out


def build_from_dataset(
    dataset: Path,
    cfg: Config,
    output: Path,
    *,
    show_progress: bool | None = None,
    config_copy: Path | None = None,
) -> tuple[Any, dict[str, Any]]:
    """Read a dataset, build the map with ``cfg.map``, save it and its PNG.

    Args:
        dataset: The survey ``.mcap``.
        cfg: Config; ``cfg.map`` sets features, neurons, epochs and seed.
        output: The map file (``.npz``); the PNG goes beside it (``MAP.png``).
        show_progress: Force progress bars on or off; default: on a terminal.
        config_copy: Also write the resolved config (no secrets) here, with the map.

    Returns:
        The :class:`naoloc.mapping.VisualMap` and the JSON summary.

    Raises:
        DatasetError: The dataset is unreadable, corrupt or has too few frames.
    """
    data = read_dataset(dataset)  # before importing the map code: a bad file fails fast
    if len(data.keyframes) < MIN_MAP_FRAMES:
        raise DatasetError(
            f"{dataset}: {len(data.keyframes)} frame(s); a map needs at least {MIN_MAP_FRAMES}"
        )

    from naoloc.mapping import build_map
    from naoloc.plots import plot_map

    keyframes, facts = survey_keyframes(data, cfg.map, cfg.survey.wall_offset_m)
    meta = dict(data.meta)
    meta.pop("vision", None)  # per-frame survey measurements stay in the dataset
    meta.update(
        {
            "dataset": str(dataset),
            "dataset_complete": data.complete,
            "frames": len(data.keyframes),
            **facts,
        }
    )
    bars: dict[str, Progress] = {}

    def progress(stage: str, done: int, total: int) -> None:
        bar = bars.get(stage)
        if bar is None:
            for old in bars.values():
                old.close()
            bars.clear()
            bar = bars[stage] = Progress(total, f"build-map {stage}", enabled=show_progress)
        bar.update(done - bar.count)

    try:
        far = far_keyframes(data, keyframes) if cfg.map.far_pictures else []
        vmap = build_map(keyframes, cfg.map, meta=meta, progress=progress, far=far)
    finally:
        for bar in bars.values():
            bar.close()
    png = output.with_suffix(".png")
    finals = [output, png] if config_copy is None else [output, png, config_copy]
    with staged(*finals) as temps:
        vmap.save(temps[0])
        plot_map(vmap, temps[1])
        if config_copy is not None:
            temps[2].write_text(cfg.to_yaml(), encoding="utf-8")
    timings = vmap.timings
    summary = {
        "images": int(vmap.images),
        "far_images": int(vmap.far_images),
        "neurons": len(vmap.neuron_poses),
        "distinct_poses": int(vmap.distinct_poses),
        "features_s": round(float(timings.get("features_s", 0.0)), 3),
        "vocabulary_s": round(float(timings.get("vocabulary_s", 0.0)), 3),
        "gcs_s": round(float(timings.get("gcs_s", 0.0)), 3),
        "total_s": round(float(timings.get("total_s", 0.0)), 3),
        "map": str(output),
        "png": str(png),
        "dataset_complete": data.complete,
        "metric_scale": facts["metric_scale"],
        "wall_poses": facts["wall_poses"],
    }
    if not data.complete:
        summary["dataset_reason"] = data.meta.get("reason")
    return vmap, summary


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Build the map of ``args.dataset`` into ``args.output``, with a PNG and the config."""
    from naoloc.commands.survey import config_path_for

    output: Path = args.output
    _, summary = build_from_dataset(args.dataset, cfg, output, config_copy=config_path_for(output))
    partial = ""
    if not summary["dataset_complete"]:
        partial = f" (partial dataset: {summary.get('dataset_reason') or 'incomplete'})"
    print(
        f"build-map: {summary['images']} images{partial} -> {summary['neurons']} neurons, "
        f"{summary['distinct_poses']} distinct poses in {summary['total_s']:.1f} s "
        f"-> {output}, {summary['png']}"
    )
    return summary
