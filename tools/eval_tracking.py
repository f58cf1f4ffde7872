"""Tracking while walking, and recovery from being carried away, in unseen rooms.

Usage::

    python tools/eval_tracking.py --seeds S1 S2 [--walks 3] [--walk-m 10] [--kidnap]

Per room (drawn from its seed as ``tools/eval_unseen_rooms.py`` draws them; default: three
seeds from os.urandom): the survey and its map, then ``--walks`` walks from random free
starts: a short look from standstill, then a walk along random waypoints over the map's
floor grid for ``--walk-m`` metres with the pose tracked at every camera frame
(:func:`naoloc.behaviours.track.walk_route`). Printed per room and pooled:

- the error of the tracked pose (median, p90) over the frames that had one, the share of
  frames without one, and those more than 0.3 m off at confidence >= 0.5;
- the pose rate (poses per second of robot time: every camera frame, and between frames
  the odometry's), the camera frame rate, and the CPU time per frame (process time, one
  core: OpenCV and BLAS on one thread).

``--kidnap`` (Fox, Burgard and Thrun's protocol): halfway through each walk the simulator
carries the robot to a random free pose without telling its odometry, and it walks on. A
walk has recovered when the pose is tracked within 0.45 m of the truth for 10 s of robot
time after the carry; the time to recover and the confident wrong poses in between
(more than 0.3 m off at confidence >= 0.5) are reported. With ``--recover-by look`` a
carried robot that has been lost for 20 frames, or is lost when a contact stopped it, stops
and looks from standstill with the same filter (:func:`naoloc.behaviours.localize.localize`,
as go-home does), then walks on from the pose it found; by default it walks on blind (the
protocol of stops 37-45).

The maps are built as ``naoloc build-map --keep-unchecked`` would: a room whose map fails a
check is said so, and the kidnap figures are given again over the maps that pass.

A walk stops when the body touches a wall or furniture (the simulator's contacts, as a
NAO's bumpers would tell); ``blocked`` counts those stops. After a carry, a blocked robot
tracks standing (its head sweeping) for 15 s, so that its recovery can still be judged.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
os.environ.setdefault("MUJOCO_GL", "egl")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from eval_unseen_rooms import room_config  # noqa: E402

from naoloc.behaviours.localize import localize, robot_clock  # noqa: E402
from naoloc.behaviours.track import Tracker, TrackPoint, walk_route  # noqa: E402
from naoloc.data.dataset import read_dataset  # noqa: E402
from naoloc.data.recorder import record_survey  # noqa: E402
from naoloc.errors import NaolocError  # noqa: E402
from naoloc.geometry import Pose2D  # noqa: E402
from naoloc.localization import Localizer  # noqa: E402
from naoloc.mapping.from_survey import build_from_survey  # noqa: E402
from naoloc.navigation.grid import FloorGrid, NoPath, grid_of_map  # noqa: E402
from naoloc.robot.registry import connect  # noqa: E402

RECOVERED_M = 0.45
RECOVERED_S = 10.0


def random_route(
    grid: FloorGrid, start: Pose2D, length_m: float, rng: np.random.Generator
) -> list[Pose2D]:
    """Waypoints over passable cells from ``start``, at least ``length_m`` long (map frame)."""
    ok = np.argwhere(grid.passable())
    route: list[Pose2D] = []
    here, total = start, 0.0
    for _ in range(50):
        if total >= length_m or ok.size == 0:
            break
        r, c = ok[int(rng.integers(len(ok)))]
        goal = Pose2D(*grid.centre(int(r), int(c)))
        if math.hypot(goal.x - here.x, goal.y - here.y) < 1.0:
            continue
        try:
            leg = grid.plan(here, goal)
        except NoPath:
            continue
        prev = here
        for p in leg:
            total += math.hypot(p.x - prev.x, p.y - prev.y)
            prev = p
        route += leg
        here = leg[-1]
    return route


def one_walk(
    robot: Any, vmap: Any, cfg: Any, grid: FloorGrid, rng: np.random.Generator, args: Any
) -> dict[str, Any]:
    """A random start, a short look, a tracked walk (with a carry when ``--kidnap``)."""
    sim = robot.sim
    sx, sy = sim.room_size()
    for _ in range(200):
        x, y = rng.uniform(0.5, sx - 0.5), rng.uniform(0.5, sy - 0.5)
        if sim.is_free(float(x), float(y), 0.35):
            break
    sim.teleport(float(x), float(y), float(rng.uniform(-math.pi, math.pi)))
    loc = Localizer(vmap, cfg.localize.filter)
    first = localize(robot, vmap, cfg, localizer=loc)
    out: dict[str, Any] = {"start_found": first.estimate.found, "look_s": first.robot_s}
    if not first.estimate.found:
        return out
    route = random_route(grid, first.estimate.pose(), args.walk_m, rng)
    tracker = Tracker(robot, loc, cfg)
    points: list[TrackPoint] = []
    ends: list[str] = []  # why each walk_route ended
    looks: list[tuple[float, float]] = []  # (start, robot s) of each look after the carry
    carried_at = None
    try:
        if args.kidnap:
            half = route[: max(1, len(route) // 2)]
            pts, why = walk_route(robot, tracker, half, max_s=args.walk_m / 0.1 * 1.5)
            points += pts
            ends.append(why)
            for _ in range(200):
                x, y = rng.uniform(0.5, sx - 0.5), rng.uniform(0.5, sy - 0.5)
                if sim.is_free(float(x), float(y), 0.35):
                    break
            sim.teleport(float(x), float(y), float(rng.uniform(-math.pi, math.pi)))
            carried_at = robot_clock(robot)
            est = loc.pose()
            here = est.pose() if est.found else first.estimate.pose()
            rest = random_route(grid, here, args.walk_m / 2, rng)
            t_walk = carried_at + args.walk_m / 0.1
            looking = args.recover_by == "look"
            # Walking on blind: never stop for being lost (walk_route's default stops).
            blind = {} if looking else {"lost_steps": 10**6}

            def look_again() -> Any:
                """Stop and look, as go-home does (the same filter)."""
                look = localize(robot, vmap, cfg, localizer=loc)
                looks.append((robot_clock(robot) - look.robot_s, look.robot_s))
                return look

            while True:
                left_s = t_walk - robot_clock(robot)
                pts, why = walk_route(robot, tracker, rest, max_s=left_s, **blind)
                points += pts
                ends.append(why)
                if why != "lost" or robot_clock(robot) >= t_walk:
                    break
                look = look_again()  # lost: look, then walk on from where it found itself
                if look.estimate.found:
                    rest = random_route(grid, look.estimate.pose(), args.walk_m / 4, rng)
            if why == "blocked":  # stopped at a contact: it tracks standing, head sweeping
                if looking and not loc.pose().found:  # lost: look first
                    look_again()
                t_end = robot_clock(robot) + RECOVERED_S + 5.0
                while robot_clock(robot) < t_end:
                    points.append(tracker.step())
        else:
            pts, why = walk_route(robot, tracker, route, max_s=args.walk_m / 0.1 * 1.5)
            points += pts
            ends.append(why)
    finally:
        robot.motion.stopMove()
        tracker.close()
    out["points"] = [
        {
            "t": p.t,
            "found": p.estimate.found,
            "error_m": p.error_m,
            "cpu_s": p.cpu_s,
            "confidence": p.estimate.confidence,
            "frame": p.frame,
        }
        for p in points
    ]
    out["carried_at"] = carried_at
    out["ends"] = ends
    out["looks"] = looks
    return out


def recovery(points: list[dict[str, Any]], carried_at: float) -> tuple[float | None, int]:
    """Seconds from the carry until the pose stayed within RECOVERED_M for RECOVERED_S, and
    the confident wrong poses (> 0.3 m, confidence >= 0.5) before that."""
    after = [p for p in points if p["t"] >= carried_at]
    wrong = 0
    for i, p in enumerate(after):
        good_since = p["t"]
        ok = True
        for q in after[i:]:
            if q["t"] - good_since > RECOVERED_S:
                break
            if not (q["found"] and q["error_m"] is not None and q["error_m"] < RECOVERED_M):
                ok = False
                break
        if ok and after[-1]["t"] - good_since >= RECOVERED_S:
            return good_since - carried_at, wrong
        if (
            p["found"]
            and p["error_m"] is not None
            and p["error_m"] > 0.3
            and p["confidence"] >= 0.5
        ):
            wrong += 1
    return None, wrong


def main() -> int:
    """Walk, track, print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=None)
    parser.add_argument("--walks", type=int, default=3, help="walks per room")
    parser.add_argument("--walk-m", type=float, default=10.0, help="length of a walk (m)")
    parser.add_argument("--kidnap", action="store_true", help="carry the robot halfway")
    parser.add_argument("--mixed", action="store_true", help="rooms of every kind")
    parser.add_argument(
        "--recover-by",
        choices=("walk", "look"),
        default="walk",
        help="after a carry, a lost robot walks on (walk) or stops to look after 20 frames "
        "without a pose, as go-home does (look)",
    )
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    cv2.setNumThreads(1)
    seeds = args.seeds or [int.from_bytes(os.urandom(4), "little") >> 1 for _ in range(3)]
    out = args.out or Path(tempfile.mkdtemp(prefix="naoloc_tracking_"))
    out.mkdir(parents=True, exist_ok=True)
    pooled: list[dict[str, Any]] = []
    walks_out: list[dict[str, Any]] = []
    t0 = time.monotonic()
    for seed in seeds:
        cfg = room_config(seed, mixed=args.mixed)
        dataset = out / f"room_{seed}.mcap"
        try:
            with connect(cfg) as robot:
                record_survey(robot, cfg, dataset)
            vmap, facts = build_from_survey(
                read_dataset(dataset), cfg.map, offset=cfg.survey.wall_offset_m
            )
        except NaolocError as err:  # the survey or the map failed: nothing to track in
            print(f"room {seed}: no map: {err}", flush=True)
            continue
        # build-map would refuse a map that failed a check; it is tracked in anyway, and said
        checked = bool(facts.get("checked"))
        failed = [c["name"] for c in facts.get("checks", []) if c.get("verdict") == "fail"]
        grid = grid_of_map(vmap)
        rng = np.random.default_rng(seed)
        room_points: list[dict[str, Any]] = []
        with connect(cfg) as robot:
            for _ in range(args.walks):
                walk = one_walk(robot, vmap, cfg, grid, rng, args)
                walk["seed"] = seed
                walk["checked"] = checked
                walks_out.append(walk)
                room_points += walk.get("points", [])
        pooled += room_points
        refused = "" if checked else f" (build-map would refuse its map: {', '.join(failed)})"
        print(f"room {seed}: {_figures(room_points)}{refused}", flush=True)
    kid = [w for w in walks_out if w.get("carried_at") is not None]
    summary: dict[str, Any] = {"walks": len(walks_out), **_figures(pooled)}
    # walks that stopped because the body touched a wall or furniture (a NAO's bumpers)
    summary["blocked"] = sum(w.get("ends", []).count("blocked") for w in walks_out)
    if kid:
        summary["kidnap"] = _kidnap(kid)
        accepted = [w for w in kid if w.get("checked")]
        if len(accepted) < len(kid):  # the same, in the maps build-map accepts
            summary["kidnap_checked_maps"] = _kidnap(accepted) if accepted else {"carried": 0}
    summary["wall_s"] = round(time.monotonic() - t0, 1)
    print(f"pooled: {json.dumps(summary)}")
    (out / "tracking.json").write_text(json.dumps({"summary": summary, "walks": walks_out}))
    return 0


def _kidnap(walks: list[dict[str, Any]]) -> dict[str, Any]:
    """Recovery figures of carried walks."""
    rec = [recovery(w["points"], w["carried_at"]) for w in walks]
    times = [r for r, _ in rec if r is not None]
    return {
        "carried": len(walks),
        "recovered_within_15s": sum(1 for r in times if r <= 15.0),
        "recovery_s_median": round(float(np.median(times)), 1) if times else None,
        "confident_wrong_between": int(sum(w for _, w in rec)),
    }


def _figures(points: list[dict[str, Any]]) -> dict[str, Any]:
    """Error, rate and CPU figures of tracked points."""
    if len(points) < 2:
        return {"frames": len(points)}
    errs = np.array([p["error_m"] for p in points if p["found"] and p["error_m"] is not None])
    conf = np.array([p["confidence"] for p in points if p["found"] and p["error_m"] is not None])
    frames = [p for p in points if p.get("frame", True)]
    cpu = np.array([p["cpu_s"] for p in frames]) * 1e3
    # Robot time tracked: the steps between consecutive poses (a gap of a second or more, or
    # a clock that went back, starts another walk or room).
    steps = np.diff([p["t"] for p in points])
    span = float(steps[(steps > 0) & (steps < 1.0)].sum())
    return {
        "frames": len(points),
        "no_pose": round(1.0 - len(errs) / len(points), 3),
        "median_m": round(float(np.median(errs)), 4) if errs.size else None,
        "p90_m": round(float(np.quantile(errs, 0.9)), 4) if errs.size else None,
        "confident_wrong": int(np.sum((errs > 0.3) & (conf >= 0.5))),
        "rate_hz": round(len(points) / span, 1) if span > 0 else None,
        "frame_hz": round(len(frames) / span, 1) if span > 0 else None,
        "cpu_ms_median": round(float(np.median(cpu)), 1),
        "cpu_ms_p90": round(float(np.quantile(cpu, 0.9)), 1),
    }


if __name__ == "__main__":
    raise SystemExit(main())
