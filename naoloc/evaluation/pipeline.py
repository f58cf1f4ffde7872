"""The whole evaluation: survey -> maps -> localizations -> summary.json, report and PNGs.

Stages run over :func:`naoloc.evaluation.runner.run_tasks` (a spawn process pool, one
simulator per task). Output folder::

    config.yaml        the resolved config
    surveys/*.mcap     survey datasets (base, and drift levels with the robustness study)
    maps/*.npz         every map built
    summary.json       the JSON line's fields, positions, per-variant summaries, tables
    estimates.json     every estimate (all variants)
    report.md          tables laid out like the paper's Tables 1-3, comparisons, robustness
    map.png estimates.png cdf.png
"""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from naoloc.config import Config, RoomChanges
from naoloc.data.outputs import atomic_write_text, folder_lock
from naoloc.errors import BackendError, ConfigError, MotionError
from naoloc.evaluation import figures, report
from naoloc.evaluation.plan import STUDIES, Plan, make_plan
from naoloc.evaluation.protocols import (
    PAPER_POSITIONS,
    PAPER_SQUARE_M,
    EvalPose,
    lap_of,
    paper_poses,
    sample_protocol_poses,
    wall_seen,
)
from naoloc.evaluation.runner import (
    Executor,
    LocalizeChunk,
    MapTask,
    Scorer,
    SurveyTask,
    chunked,
    jsonable,
    localize_chunk,
    map_task,
    run_tasks,
    survey_task,
)
from naoloc.evaluation.stats import group_rows, heading_errors, json_float, summarize


def check_simulated(cfg: Config) -> None:
    """Refuse a config whose robot has no simulator (evaluate needs ``robot.sim``).

    Raises:
        BackendError: ``robot.backend`` is not a simulated backend.
    """
    if cfg.robot.backend not in ("mujoco", "fake"):
        raise BackendError(
            f"evaluate needs a simulated robot (robot.sim); robot.backend is {cfg.robot.backend!r}"
        )


def parse_studies(text: str | None) -> tuple[str, ...]:
    """``"compare,robustness"``, ``"all"`` or ``"none"`` -> study names (main always first).

    Raises:
        ConfigError: An unknown study name.
    """
    if text is None or text.strip() in ("", "none", "main"):
        return ("main",)
    names = [t.strip() for t in text.split(",") if t.strip()]
    if names == ["all"]:
        return STUDIES
    for name in names:
        if name not in STUDIES:
            raise ConfigError(f"unknown study {name!r}; valid: all, none, {', '.join(STUDIES)}")
    return ("main", *[s for s in STUDIES[1:] if s in names])


def evaluate(
    cfg: Config,
    protocol: str,
    n: int,
    seed: int,
    outdir: Path,
    *,
    workers: int | None = None,
    studies: tuple[str, ...] = ("main",),
    chunk_size: int | None = None,
    progress: bool | None = None,
    executor: Executor | None = None,
    record: bool = False,
) -> dict[str, Any]:
    """Run an evaluation and write its outputs.

    Args:
        cfg: Resolved config of a simulated robot (survey settings, main map, mode).
        protocol: "paper" or "random".
        n: Test poses (random protocol; the paper protocol has 4 x 5).
        seed: Seed of the test poses (and of the paper protocol's heading perturbations).
        outdir: Output folder (created).
        workers: Processes; default: CPU cores.
        studies: Studies to run besides "main" (see :mod:`naoloc.evaluation.plan`).
        chunk_size: Poses per localization task; default: spread over 3 tasks per worker.
        progress: Force progress bars on or off; default: on when stderr is a terminal.
        executor: Where the tasks run (default: the local process pool); same results.
        record: Record each filter localization's observations in ``outdir/recordings``
            (``VARIANT_INDEX.mcap``; ``naoloc replay`` re-runs one without a robot).

    Returns:
        The JSON line: protocol, n, median_error_m, p90_error_m, max_error_m,
        median_heading_error_deg, map_build_s, localize_ms_median, and more.

    Raises:
        BackendError: The robot is not simulated.
        ConfigError: The protocol does not fit the config.
        OutputBusy: Another run is writing into ``outdir``.
    """
    check_simulated(cfg)
    if protocol not in ("paper", "random", "anywhere", "changed"):
        raise ConfigError(f"unknown protocol {protocol!r}; valid: paper, random, anywhere, changed")
    if protocol == "paper" and tuple(round(s, 6) for s in cfg.survey_sides()) != PAPER_SQUARE_M:
        raise ConfigError(
            f"the paper protocol needs a 4 x 4 m survey square; this config walks "
            f"{cfg.survey_sides()[0]:g} x {cfg.survey_sides()[1]:g} m"
        )
    with folder_lock(outdir, "naoloc evaluate"):
        return _evaluate(
            cfg, protocol, n, seed, outdir, workers=workers, studies=studies,
            chunk_size=chunk_size, progress=progress, executor=executor, record=record,
        )  # fmt: skip


def _evaluate(
    cfg: Config,
    protocol: str,
    n: int,
    seed: int,
    outdir: Path,
    *,
    workers: int | None,
    studies: tuple[str, ...],
    chunk_size: int | None,
    progress: bool | None,
    executor: Executor | None,
    record: bool = False,
) -> dict[str, Any]:
    """:func:`evaluate` with ``outdir`` held."""
    from naoloc.data.outputs import write_resolved_config

    t_start = time.monotonic()
    workers = max(1, workers if workers is not None else (os.cpu_count() or 1))
    test_cfg = cfg  # the room the robot localizes in
    if protocol == "changed":
        # The survey (and the map) sees the room as it was; the test, the changed room.
        changes = cfg.world.room.changes or RoomChanges()
        test_cfg = cfg.with_overrides({"world": {"room": {"changes": changes.model_dump()}}})
        cfg = cfg.with_overrides({"world": {"room": {"changes": None}}})
    plan = make_plan(cfg, protocol, studies)
    base_dict = test_cfg.to_dict()

    # 1. Surveys: the base one, plus the drift levels of the robustness study.
    survey_tasks = [
        SurveyTask(name, cfg.with_overrides(ov).to_dict(), str(outdir / "surveys" / f"{name}.mcap"))
        for name, ov in plan.surveys.items()
    ]
    surveys = {
        r["name"]: r
        for r in run_tasks(
            survey_task, survey_tasks, workers, "survey", progress=progress, executor=executor
        )
    }
    base = surveys["base"]
    if "failed" in base:
        raise MotionError(f"the survey failed: {base['failed']}")
    failed = {k: f"survey failed: {v['failed']}" for k, v in surveys.items() if "failed" in v}
    origin: tuple[float, float, float] = tuple(base["meta"]["origin_room_pose"])  # type: ignore[assignment]
    room_size: tuple[float, float] = tuple(base["meta"]["room_size_m"])  # type: ignore[assignment]

    # 2. Maps, all in parallel.
    map_paths = {name: str(outdir / "maps" / f"{name.replace('/', '_')}.npz") for name in plan.maps}
    map_tasks = [
        MapTask(name, surveys[survey]["dataset"], mc.model_dump(mode="json"), map_paths[name])
        for name, (survey, mc) in plan.maps.items()
        if survey not in failed
    ]
    maps = {
        r["name"]: r
        for r in run_tasks(
            map_task, map_tasks, workers, "maps", progress=progress, executor=executor
        )
    }

    # 3. Test poses and localizations.
    poses = _test_poses(test_cfg, protocol, n, seed, origin, room_size)
    skipped = {v.name: failed[plan.maps[v.map_name][0]] for v in plan.variants
               if plan.maps[v.map_name][0] in failed}  # fmt: skip
    runnable = Plan(plan.surveys, plan.maps, [v for v in plan.variants if v.name not in skipped],
                    plan.robots)  # fmt: skip
    record_dir = str(outdir / "recordings") if record else None
    chunks = _chunks(
        runnable, cfg, base_dict, poses, origin, map_paths, workers, chunk_size, record_dir
    )
    results = run_tasks(
        localize_chunk, chunks, workers, "localize", progress=progress, executor=executor
    )
    flat = [rec for chunk in results for rec in chunk]
    records = [r for r in flat if "skipped" not in r]
    skipped.update({r["variant"]: r["skipped"] for r in flat if "skipped" in r})

    # 4. Outputs.
    summary = _summary(
        plan, protocol, seed, workers, cfg, surveys, maps, records, origin, room_size, skipped
    )
    summary["wall_s"] = round(time.monotonic() - t_start, 2)
    _write_outputs(outdir, summary, records, plan, maps, surveys, origin, room_size, protocol)
    write_resolved_config(test_cfg, outdir / "config.yaml")  # last: it describes the outputs
    line = {k: summary[k] for k in _LINE_KEYS}
    line.update(
        {
            "seed": seed,
            "survey_frames": base["frames"],
            "wall_s": summary["wall_s"],
            "report": str(outdir / "report.md"),
            "summary": str(outdir / "summary.json"),
        }
    )
    return line


_LINE_KEYS = (
    "protocol",
    "n",
    "median_error_m",
    "p90_error_m",
    "max_error_m",
    "median_heading_error_deg",
    "map_build_s",
    "localize_ms_median",
    "no_estimate",
)


def _test_poses(
    cfg: Config,
    protocol: str,
    n: int,
    seed: int,
    origin: tuple[float, float, float],
    room_size: tuple[float, float],
) -> list[EvalPose]:
    if protocol == "paper":
        return paper_poses(origin, seed)
    from naoloc.robot.registry import connect

    with connect(cfg) as robot:
        if robot.sim is None:
            raise BackendError(f"evaluate needs robot.sim; the {robot.backend} backend has none")
        return sample_protocol_poses(protocol, n, seed, room_size, robot.sim.is_free)


def _chunks(
    plan: Plan,
    cfg: Config,
    base_dict: dict[str, Any],
    poses: Sequence[EvalPose],
    origin: tuple[float, float, float],
    map_paths: dict[str, str],
    workers: int,
    chunk_size: int | None,
    record_dir: str | None = None,
) -> list[LocalizeChunk]:
    size = chunk_size or max(1, math.ceil(len(poses) / (3 * workers)))
    chunks: list[LocalizeChunk] = []
    for robot in plan.robots.values():
        variants = [v for v in plan.variants if v.robot == robot.name]
        if not variants:
            continue
        scorers = tuple(
            Scorer(v.name, map_paths[v.map_name], v.mode, v.strategy)
            for v in sorted(variants, key=lambda v: v.strategy != variants[0].strategy)
        )
        config = cfg.with_overrides(robot.overrides).to_dict() if robot.overrides else base_dict
        for part in chunked(list(poses), size):
            chunks.append(
                LocalizeChunk(config, origin, part, scorers, robot.world_changes, record_dir)
            )
    return chunks


def _variant_summary(records: Sequence[dict[str, Any]]) -> dict[str, Any]:
    err = np.array([r["error_m"] for r in records], dtype=np.float64)
    head = heading_errors(
        np.array([r["truth"][2] for r in records]), np.array([r["estimate"][2] for r in records])
    )
    s = summarize(err, head)
    out: dict[str, Any] = {
        k: json_float(v) if isinstance(v, float) else v for k, v in s.to_dict().items()
    }
    ms = [r["localize_ms"] for r in records]
    out["localize_ms_median"] = json_float(float(np.median(ms))) if ms else None
    # CPU of the map's work alone (records of older runs have none).
    cpu = [r["compute_ms"] for r in records if "compute_ms" in r]
    for name, q in (("median", 50), ("p90", 90), ("max", 100)):
        out[f"compute_ms_{name}"] = json_float(float(np.percentile(cpu, q))) if cpu else None
    conf = [r["confidence"] for r in records if math.isfinite(r["confidence"])]
    out["confidence_median"] = json_float(float(np.median(conf))) if conf else None
    out["no_features"] = int(sum(1 for r in records if r["confidence"] == 0.0))
    # A pose without an estimate is a miss (its error counts as infinite above), never a guess.
    out["no_estimate"] = int(sum(1 for r in records if not math.isfinite(r["error_m"])))
    return out


def _summary(
    plan: Plan,
    protocol: str,
    seed: int,
    workers: int,
    cfg: Config,
    surveys: dict[str, dict[str, Any]],
    maps: dict[str, dict[str, Any]],
    records: Sequence[dict[str, Any]],
    origin: tuple[float, float, float],
    room_size: tuple[float, float],
    skipped: dict[str, str],
) -> dict[str, Any]:
    by_variant: dict[str, list[dict[str, Any]]] = {v.name: [] for v in plan.variants}
    for rec in records:
        by_variant[rec["variant"]].append(rec)
    main = plan.main
    main_stats = _variant_summary(by_variant[main.name])
    main_map = maps[main.map_name]
    summary: dict[str, Any] = {
        "protocol": protocol,
        "n": len(by_variant[main.name]),
        "median_error_m": main_stats["median_error_m"],
        "p90_error_m": main_stats["p90_error_m"],
        "max_error_m": main_stats["max_error_m"],
        "median_heading_error_deg": main_stats["median_heading_error_deg"],
        "map_build_s": json_float(main_map["timings"].get("total_s", float("nan")), 3),
        "localize_ms_median": main_stats["localize_ms_median"],
        "compute_ms_median": main_stats["compute_ms_median"],
        "compute_ms_p90": main_stats["compute_ms_p90"],
        "compute_ms_max": main_stats["compute_ms_max"],
        "no_estimate": main_stats["no_estimate"],
        "positions": group_rows(by_variant[main.name]),
        "seed": seed,
        "workers": workers,
        "main_variant": main.name,
        "origin_room_pose": list(origin),
        "room_size_m": list(room_size),
        "room_seed": cfg.world.room.seed,
        "backend": cfg.robot.backend,
        "survey": _survey_table(surveys["base"], origin, room_size, cfg.survey.laps),
        "surveys": {
            k: {kk: v[kk] for kk in ("frames", "laps", "path_m", "wall_s", "failed") if kk in v}
            for k, v in surveys.items()
        },
        "maps": maps,
        "variants": {
            v.name: {
                "study": v.study,
                "description": v.description,
                "map": v.map_name,
                "mode": v.mode,
                "strategy": v.strategy,
                "robot": v.robot,
                **_variant_summary(by_variant[v.name]),
                **({"skipped": skipped[v.name]} if v.name in skipped else {}),
            }
            for v in plan.variants
        },
        "machine": report.machine(),
        "config": cfg.to_dict(),
    }
    if protocol == "paper":
        summary["table3"] = _table3(by_variant)
    return summary


def _table3(by_variant: dict[str, list[dict[str, Any]]]) -> list[dict[str, Any]]:
    """Rows of Table 3: for each position, estimates of every map x mode, and the paper's."""
    rows = []
    for pos in PAPER_POSITIONS:
        row: dict[str, Any] = {
            "number": pos.number,
            "paper_map": pos.paper_map,
            "truth": [pos.x, pos.y],
            "heading_deg": round(math.degrees(pos.heading), 1),
            "paper_estimates": [list(e) for e in pos.paper_estimates],
            "paper_mean_error_m": round(pos.paper_mean_error_m(), 4),
            "ours": {},
        }
        for name, recs in by_variant.items():
            mine = [r for r in recs if r["group"] == pos.number]
            if not mine:
                continue
            errors = [r["error_m"] if math.isfinite(r["error_m"]) else math.inf for r in mine]
            row["ours"][name] = {
                "estimates": [
                    [round(r["estimate"][0], 3), round(r["estimate"][1], 3)]
                    if math.isfinite(r["error_m"])
                    else None
                    for r in mine
                ],
                "mean_error_m": json_float(float(np.mean(errors))),
                "max_error_m": json_float(float(np.max(errors))),
                "no_estimate": sum(1 for e in errors if not math.isfinite(e)),
            }
        rows.append(row)
    return rows


def _survey_table(
    survey: dict[str, Any],
    origin: tuple[float, float, float],
    room_size: tuple[float, float],
    laps: int,
) -> dict[str, Any]:
    """Table 1: images per lap and per wall (wall seen by the camera's optical axis)."""
    from naoloc.data.dataset import read_dataset

    data = read_dataset(survey["dataset"])
    kfs = data.keyframes
    poses = np.array([kf.pose.to_list() for kf in kfs], dtype=np.float64).reshape(-1, 3)
    if data.laps and len(data.laps) == len(kfs):
        lap = np.asarray(data.laps, dtype=int) + 1
    else:
        sides = survey["meta"].get("sides_m", [1.0, 1.0])
        lap = lap_of(poses, 2.0 * (sides[0] + sides[1]), laps)
    rows: dict[int, list[int]] = {}
    for kf, lp in zip(kfs, lap, strict=True):
        if kf.true_pose is not None:
            room = kf.true_pose
        else:
            from naoloc.evaluation.protocols import map_to_room

            room = map_to_room(origin, kf.pose)
        wall = wall_seen((room.x, room.y, room.theta), room.theta + kf.head_yaw, room_size)
        counts = rows.setdefault(int(lp), [0, 0, 0, 0])
        counts[wall - 1] += 1
    return {
        "frames": len(kfs),
        "laps": [{"lap": k, "images": sum(v), "walls": v} for k, v in sorted(rows.items())],
        "path_m": round(float(survey["path_m"]), 3),
        "wall_s": round(float(survey["wall_s"]), 2),
        "keyframe_poses": np.round(poses, 4).tolist(),
    }


def _write_outputs(
    outdir: Path,
    summary: dict[str, Any],
    records: Sequence[dict[str, Any]],
    plan: Plan,
    maps: dict[str, dict[str, Any]],
    surveys: dict[str, dict[str, Any]],
    origin: tuple[float, float, float],
    room_size: tuple[float, float],
    protocol: str,
) -> None:
    from naoloc.config import load_config
    from naoloc.mapping import load_map
    from naoloc.viz.plots import furniture_footprints, room_corners

    poly = room_corners(origin, room_size)
    furniture = furniture_footprints(load_config(summary["config"]), origin)
    shown = [v.map_name for v in plan.variants if v.study == "paper" and v.mode == "paper"]
    shown = shown or [plan.main.map_name] + [
        v.map_name for v in plan.variants if v.name.startswith("neurons-") and v.mode == "paper"
    ]
    panels = []
    for name in dict.fromkeys(shown):
        vmap = load_map(maps[name]["map"])
        panels.append(
            (
                f"{name}: {vmap.distinct_poses} distinct poses",
                vmap.keyframe_poses[: vmap.wall_images],  # the walk (far pictures follow)
                vmap.neuron_poses,
            )
        )
    figures.plot_maps(outdir / "map.png", panels, poly, furniture)
    main_recs = [r for r in records if r["variant"] == plan.main.name]
    figures.plot_estimates(
        outdir / "estimates.png", main_recs,
        f"{protocol} protocol, {plan.main.description}\nmedian "
        f"{summary['median_error_m']} m, p90 {summary['p90_error_m']} m",
        # the survey as the verified localizer's map has it (wall poses, pose graph), not
        # its raw odometry, which drifts through walls in the honest world
        poly, _walk(load_map(maps[plan.main.map_name]["map"])), furniture,
    )  # fmt: skip
    curves: dict[str, list[float]] = {}
    for v in plan.variants:
        if v.study in ("main", "paper") or v.name in (
            "paper-mode",
            "verified-mode",
            "nearest-image",
        ):
            curves[v.name] = [r["error_m"] for r in records if r["variant"] == v.name]
    figures.plot_cdf(outdir / "cdf.png", curves, f"{protocol} protocol: cumulative position error")
    if any(v.study == "robustness" for v in plan.variants):
        rob = {"main": curves.get("main", [])}
        for v in plan.variants:
            if v.study == "robustness":
                rob[v.name] = [r["error_m"] for r in records if r["variant"] == v.name]
        figures.plot_cdf(
            outdir / "cdf_robustness.png", rob, "robustness: cumulative position error"
        )
    atomic_write_text(outdir / "estimates.json", json.dumps(jsonable(list(records))))
    atomic_write_text(outdir / "report.md", report.render(summary))
    atomic_write_text(outdir / "summary.json", json.dumps(jsonable(summary), indent=1))


def _walk(vmap: Any) -> np.ndarray:
    """The survey's walk as the map has it: the wall pictures' refined poses (map frame;
    the far pictures, taken at the same stops, follow them in the map's keyframes)."""
    return np.asarray(vmap.refined_poses)[: vmap.wall_images]
