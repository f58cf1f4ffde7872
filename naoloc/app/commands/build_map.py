"""``naoloc build-map -c CFG -d DATASET.mcap -o MAP.npz``: Algorithm 4, plus a PNG of the map.

Before anything is trained the survey's map frame is checked (:mod:`naoloc.mapping.checks`):
each check's line is printed, and a map that fails one is refused in one line naming the
check (exit 1, nothing written) unless ``--keep-unchecked`` keeps it, marked unchecked
(``checked: false`` in its meta and the JSON). The map, its PNG and the config copy
(``MAP.config.yaml``) are written under temporary names and moved into place together once
all three exist: a run that fails or is interrupted leaves an older map, PNG and config
copy as they were. A partial dataset (an interrupted survey's ``DATASET.partial.mcap``) is
read only when named, and said so.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from naoloc.config import Config
from naoloc.data.dataset import read_dataset
from naoloc.data.outputs import staged
from naoloc.errors import DatasetError
from naoloc.mapping.from_survey import MIN_MAP_FRAMES
from naoloc.viz.progress import Progress

# The stages naoloc.mapping.builder reports once each after "features" (progress bar total).
LATER_STAGES = ("vocabulary", "gcs", "poses", "landmarks")


def build_from_dataset(
    dataset: Path,
    cfg: Config,
    output: Path,
    *,
    show_progress: bool | None = None,
    config_copy: Path | None = None,
    keep_unchecked: bool = True,
    on_checks: Any = None,
) -> tuple[Any, dict[str, Any]]:
    """Read a dataset, build the map with ``cfg.map``, save it and its PNG.

    Args:
        dataset: The survey ``.mcap``.
        cfg: Config; ``cfg.map`` sets features, neurons, epochs and seed.
        output: The map file (``.npz``); the PNG goes beside it (``MAP.png``).
        show_progress: Force progress bars on or off; default: on a terminal.
        config_copy: Also write the resolved config (no secrets) here, with the map.
        keep_unchecked: Keep a map that failed a check, marked unchecked (the default,
            for the demo); ``naoloc build-map`` refuses it unless ``--keep-unchecked``.
        on_checks: Called with the checks (:class:`naoloc.mapping.checks.Check`) once run.

    Returns:
        The :class:`naoloc.mapping.VisualMap` and the JSON summary.

    Raises:
        DatasetError: The dataset is unreadable, corrupt or has too few frames.
        MapCheckFailed: The map failed a check (nothing is written) and ``keep_unchecked``
            is False.
    """
    data = read_dataset(dataset)  # before importing the map code: a bad file fails fast
    if len(data.keyframes) < MIN_MAP_FRAMES:
        raise DatasetError(
            f"{dataset}: {len(data.keyframes)} frame(s); a map needs at least {MIN_MAP_FRAMES}"
        )

    from naoloc.mapping.from_survey import build_from_survey
    from naoloc.viz.plots import furniture_footprints, plot_map

    # One bar for the whole build: a step per image's features, then one per later stage
    # (each of those reports 1/1 alone), the stage named after the bar.
    bar = Progress(None, "build-map", enabled=show_progress)
    done_in: dict[str, int] = {}

    def progress(stage: str, done: int, total: int) -> None:
        if stage == "features" and not bar.total:
            bar.total = total + len(LATER_STAGES)
        step = done - done_in.get(stage, 0)
        done_in[stage] = done
        bar.update(step, stage)

    try:
        vmap, facts = build_from_survey(
            data,
            cfg.map,
            offset=cfg.survey.wall_offset_m,
            meta={
                "dataset": str(dataset),
                "dataset_complete": data.complete,
                "frames": len(data.keyframes),
            },
            progress=progress,
            keep_unchecked=keep_unchecked,
            on_checks=on_checks,
        )
    finally:
        bar.close()
    png = output.with_suffix(".png")
    finals = [output, png] if config_copy is None else [output, png, config_copy]
    with staged(*finals) as temps:
        vmap.save(temps[0])
        plot_map(
            vmap, temps[1], furniture=furniture_footprints(cfg, vmap.meta.get("origin_room_pose"))
        )
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
        "checked": facts["checked"],
        "checks": facts["checks"],
    }
    if not data.complete:
        summary["dataset_reason"] = data.meta.get("reason")
    return vmap, summary


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Build the map of ``args.dataset`` into ``args.output``, with a PNG and the config."""
    from naoloc.data.outputs import config_path_for

    output: Path = args.output

    def show(checks: list[Any]) -> None:
        for check in checks:
            print(f"build-map check: {check.line()}")

    _, summary = build_from_dataset(
        args.dataset,
        cfg,
        output,
        config_copy=config_path_for(output),
        keep_unchecked=bool(getattr(args, "keep_unchecked", False)),
        on_checks=show,
    )
    hidden: dict[int, list[tuple[int, float]]] = {}
    for side, depth in (summary.get("wall_poses") or {}).get("hidden") or []:
        hidden.setdefault(side % 4, []).append((side // 4 + 1, depth))
    for side, laps in sorted(hidden.items()):
        print(
            f"build-map: side {side + 1} followed a front {laps[0][1]:.2f} m before its wall "
            f"all along (a wardrobe, a bed; lap {', '.join(str(lap) for lap, _ in laps)}): "
            "the sides toward it end that much early"
        )
    partial = ""
    if not summary["dataset_complete"]:
        partial = f" (partial dataset: {summary.get('dataset_reason') or 'incomplete'})"
    unchecked = "" if summary["checked"] else " UNCHECKED (a check failed; kept as asked)"
    print(
        f"build-map: {summary['images']} images{partial}{unchecked} -> "
        f"{summary['neurons']} neurons, "
        f"{summary['distinct_poses']} distinct poses in {summary['total_s']:.1f} s "
        f"-> {output}, {summary['png']}"
    )
    return summary
