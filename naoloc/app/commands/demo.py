"""``naoloc demo [-o OUTDIR] [-c CFG]``: survey -> build map -> localize at several poses.

Runs in one simulated robot (the default paper room): the survey is written to
``OUTDIR/survey.mcap``, the map to ``OUTDIR/map.npz`` (and ``map.png``), then the robot is
teleported to the paper's Table 3 positions (scaled to the survey rectangle) and to two
seeded random poses 0.6-1.4 m from the walls, and localized at each. A table of truth,
estimate and error is printed, and a picture of all estimates is written.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from naoloc.config import Config
from naoloc.errors import BackendError, MotionError, NaolocError
from naoloc.geometry import Pose2D
from naoloc.robot import Robot

if TYPE_CHECKING:
    from naoloc.behaviours.survey import SurveyResult

# The paper's Table 3 positions in the map frame, as fractions of the 4 x 4 m survey square.
# Fewer triangulated landmarks than this and the demo says the map cannot recognise a view.
MIN_LANDMARKS = 30
TABLE3_FRACTIONS: tuple[tuple[float, float], ...] = ((0.875, 0.125), (0, 0), (0.125, 0.875), (1, 1))


NEEDS_A_SIMULATOR = (
    "the demo needs a simulated robot (backend {backend} has no simulator: it teleports the "
    "robot between poses); on a real NAO run `naoloc check`, then survey, build-map and "
    "localize (docs/real-nao.md)"
)


def refuse_a_real_robot(cfg: Config) -> None:
    """Refuse, before connecting, a config whose robot cannot be a simulator.

    Raises:
        BackendError: ``robot.backend: naoqi`` without ``robot.sim_service`` (a real NAO,
            or a served one whose simulator the demo may not use).
    """
    if cfg.robot.backend == "naoqi" and not cfg.robot.sim_service:
        raise BackendError(NEEDS_A_SIMULATOR.format(backend="naoqi"))


def demo_poses(robot: Robot, meta: dict[str, Any], sides: tuple[float, float], seed: int = 0,
               extra: int = 2) -> list[Pose2D]:  # fmt: skip
    """Demo test poses in the room frame: Table 3's (scaled) plus ``extra`` random ones.

    Args:
        robot: A simulated robot (``robot.sim`` answers room size and free space).
        meta: Survey meta with ``origin_room_pose`` and ``direction``.
        sides: Survey rectangle sides, m.
        seed: Seed of headings and random positions.
        extra: Random poses 0.6-1.4 m from the nearest wall, on free floor (more replace
            Table 3 positions that are not on free floor).

    Returns:
        Poses (x, y m; theta rad) in the room frame.
    """
    if robot.sim is None or meta.get("origin_room_pose") is None:
        raise BackendError("the demo needs a simulated robot (world.* config, mujoco or fake)")
    rng = np.random.default_rng(seed)
    origin = Pose2D.from_list(meta["origin_room_pose"])
    turn = 1.0 if meta.get("direction", "ccw") == "ccw" else -1.0
    poses: list[Pose2D] = []
    for fx, fy in TABLE3_FRACTIONS:
        p = origin * Pose2D(
            fx * sides[0], turn * fy * sides[1], float(rng.uniform(-math.pi, math.pi))
        )
        if robot.sim.is_free(p.x, p.y, 0.3):  # a survey that went astray can put it outside
            poses.append(p.normalized())
    sx, sy = robot.sim.room_size()
    tries = 0
    while len(poses) < len(TABLE3_FRACTIONS) + extra and tries < 10000:
        tries += 1
        x, y = float(rng.uniform(0, sx)), float(rng.uniform(0, sy))
        wall = min(x, y, sx - x, sy - y)
        if 0.6 <= wall <= 1.4 and robot.sim.is_free(x, y, 0.3):
            poses.append(Pose2D(x, y, float(rng.uniform(-math.pi, math.pi))))
    return poses


def run(args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    """Survey, build the map and localize at several poses; print a table and summarize."""
    from naoloc.app.commands.build_map import build_from_dataset
    from naoloc.app.interrupt import interruptible
    from naoloc.behaviours.localize import localize
    from naoloc.data.outputs import write_resolved_config
    from naoloc.robot.registry import connect
    from naoloc.viz.plots import furniture_footprints, plot_estimates

    t0 = time.monotonic()
    refuse_a_real_robot(cfg)  # before connecting: a real NAO never hears from the demo
    out: Path = args.output
    out.mkdir(parents=True, exist_ok=True)
    dataset, map_path = out / "survey.mcap", out / "map.npz"
    rows: list[dict[str, Any]] = []
    pairs: list[tuple[Pose2D, Pose2D | None]] = []
    covariances: list[Any] = []
    with interruptible(), connect(cfg) as robot:
        if robot.sim is None:  # before the first motion call
            raise BackendError(NEEDS_A_SIMULATOR.format(backend=robot.backend))
        room = cfg.world.room
        print(
            f"demo: backend {robot.backend}, room {room.size_m[0]:g} x {room.size_m[1]:g} m "
            f"(seed {room.seed}), map {cfg.map.features} {cfg.map.neurons} neurons, "
            f"localize mode {cfg.localize.mode}",
            flush=True,
        )
        surveyed, frames, dataset, stopped = _survey(robot, cfg, dataset)
        try:
            vmap, built = build_from_dataset(dataset, cfg, map_path)
        except NaolocError as err:  # no map, no localization: say why, finish the demo
            print(f"demo: no map: {_one_line(err)}", flush=True)
            write_resolved_config(cfg, out / "config.yaml")
            return _summary(cfg, t0, frames, None, rows, dataset, map_path, None, stopped)
        print(
            f"demo: map {built['neurons']} neurons, {built['distinct_poses']} distinct poses, "
            f"{vmap.landmarks} landmarks, {built['total_s']:.1f} s -> {map_path}"
        )
        if vmap.landmarks < MIN_LANDMARKS:
            print(
                f"demo: the map has {vmap.landmarks} landmarks (median "
                f"{_median_keypoints(vmap)} keypoints per image): too few to recognise a view",
                flush=True,
            )
        poses = demo_poses(robot, surveyed.meta, cfg.survey_sides(), seed=cfg.map.seed)
        for i, pose in enumerate(poses):
            robot.sim.teleport(*pose)  # type: ignore[union-attr]  # demo_poses checked sim
            try:
                loc = localize(robot, vmap, cfg)
            except MotionError as err:  # a turn in place failed: a miss, not a crash
                print(f"demo: pose {i + 1}/{len(poses)}: {_one_line(err)}", flush=True)
                rows.append(_miss_row())
                continue
            est = loc.estimate
            if est.found:
                pairs.append((Pose2D(est.x, est.y, est.theta), loc.truth))
                covariances.append(est.covariance)
            truth = loc.truth
            rows.append(
                {
                    "truth": None if truth is None else [round(v, 3) for v in truth],
                    "estimate": [round(est.x, 3), round(est.y, 3), round(est.theta, 3)]
                    if est.found
                    else None,
                    "error_m": _rounded(loc.error_m, 3),
                    "heading_error_deg": _rounded(loc.heading_error_deg, 2),
                    "confidence": round(float(est.confidence), 3),
                    "localize_s": round(loc.wall_s, 3),
                }
            )
            err_m = math.nan if loc.error_m is None else loc.error_m
            note = "" if est.found else " (no estimate)"
            print(f"demo: pose {i + 1}/{len(poses)}: error {err_m:.2f} m{note}", flush=True)
    furniture = furniture_footprints(cfg, surveyed.meta.get("origin_room_pose"))
    png = plot_estimates(
        vmap, pairs, out / "localize.png", furniture=furniture, covariances=covariances
    )  # fmt: skip
    write_resolved_config(cfg, out / "config.yaml")  # with the outputs it describes
    _print_table(rows)
    return _summary(cfg, t0, frames, built, rows, dataset, map_path, png, stopped)


def _survey(robot: Robot, cfg: Config, dataset: Path) -> tuple[SurveyResult, int, Path, str | None]:
    """Record the survey; when it stops early (a step failed), go on with the frames so far.

    Returns:
        The survey summary, the frames written, the dataset to build from (the partial file
        when the survey stopped) and why it stopped (None when it completed).
    """
    from naoloc.behaviours.survey import SurveyResult, frames_per_lap
    from naoloc.data.dataset import partial_path_for
    from naoloc.data.recorder import record_survey
    from naoloc.viz.progress import Progress

    try:
        expected = frames_per_lap(cfg.survey_sides(), cfg.survey.step_m) * cfg.survey.laps
        with Progress(expected, "survey") as bar:
            surveyed, frames = record_survey(robot, cfg, dataset, bar.update)
    except MotionError as err:  # the robot is stopped; the frames so far are on disk
        partial = partial_path_for(dataset)
        print(f"demo: the survey stopped early: {_one_line(err)}", flush=True)
        if not partial.is_file():
            return SurveyResult(), 0, partial, str(err)
        from naoloc.data.dataset import read_dataset

        try:
            data = read_dataset(partial)
        except NaolocError:  # unreadable: the map build says why in one line
            return SurveyResult(), 0, partial, str(err)
        result = SurveyResult(meta=dict(data.meta), frames=len(data.keyframes))
        return result, len(data.keyframes), partial, str(err)
    print(
        f"demo: survey {frames} frames, {surveyed.laps} laps, {surveyed.path_m:.1f} m, "
        f"{surveyed.wall_s:.1f} s -> {dataset}"
    )
    return surveyed, frames, dataset, None


def _summary(
    cfg: Config,
    t0: float,
    frames: int,
    built: dict[str, Any] | None,
    rows: list[dict[str, Any]],
    dataset: Path,
    map_path: Path,
    png: Path | None,
    stopped: str | None,
) -> dict[str, Any]:
    """The demo's JSON line; misses (no estimate) count in ``no_estimate``."""
    errors = [r["error_m"] for r in rows if r["error_m"] is not None]
    headings = [r["heading_error_deg"] for r in rows if r["heading_error_deg"] is not None]
    times = [r["localize_s"] for r in rows if r.get("localize_s") is not None]
    return {
        "backend": cfg.robot.backend,
        "frames": frames,
        "survey_stopped": stopped,
        "images": None if built is None else built["images"],
        "neurons": None if built is None else built["neurons"],
        "distinct_poses": None if built is None else built["distinct_poses"],
        "map_build_s": None if built is None else built["total_s"],
        "n": len(rows),
        "no_estimate": sum(1 for r in rows if r["estimate"] is None),
        "median_error_m": round(statistics.median(errors), 3) if errors else None,
        "max_error_m": round(max(errors), 3) if errors else None,
        "median_heading_error_deg": round(statistics.median(headings), 2) if headings else None,
        "localize_s_median": round(statistics.median(times), 3) if times else None,
        "wall_s": round(time.monotonic() - t0, 1),
        "dataset": str(dataset),
        "map": None if built is None else str(map_path),
        "png": None if png is None else str(png),
        "positions": rows,
    }


def _miss_row() -> dict[str, Any]:
    return {
        "truth": None,
        "estimate": None,
        "error_m": None,
        "heading_error_deg": None,
        "confidence": 0.0,
        "localize_s": None,
    }


def _one_line(err: BaseException) -> str:
    notes = [str(n) for n in getattr(err, "__notes__", ())]
    return "; ".join([str(err), *notes]).replace("\n", " ")


def _median_keypoints(vmap: Any) -> int:
    """Median keypoints per map image (from the map's ``kp_offsets``)."""
    offsets = np.asarray(getattr(vmap, "kp_offsets", np.zeros(0)))
    return int(np.median(np.diff(offsets))) if offsets.size >= 2 else 0


def _rounded(value: float | None, digits: int) -> float | None:
    return None if value is None else round(value, digits)


def _nan(value: float | None) -> float:
    return math.nan if value is None else value


def _print_table(rows: list[dict[str, Any]]) -> None:
    print(f"{'#':>2}  {'truth (map frame)':>24}  {'estimate':>24}  {'error m':>8}  {'head deg':>8}")
    for i, r in enumerate(rows):
        t, e = r["truth"] or [math.nan] * 3, r["estimate"] or [math.nan] * 3  # None: a miss
        print(
            f"{i + 1:>2}  ({t[0]:6.2f}, {t[1]:6.2f}, {t[2]:5.2f})  "
            f"({e[0]:6.2f}, {e[1]:6.2f}, {e[2]:5.2f})  {_nan(r['error_m']):8.2f}  "
            f"{_nan(r['heading_error_deg']):8.1f}"
        )
