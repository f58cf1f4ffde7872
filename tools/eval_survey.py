"""The survey and its map frame in rooms the code was never tuned to (issue 31, item 6).

Each room is drawn from a seed (os.urandom when none are given): its size (3 x 3 to
10 x 8 m), style (home or office), light (0.3-1.5), the survey's wall offset (0.5-1.2 m,
at most what leaves a 1.5 m circuit side) and the start: one of the four corners, with
the wall on the robot's right (counter-clockwise circuit) or left (clockwise). The room's
furniture, posters and textures come from the same seed. The world is the default honest
one (NAO odometry, NAO camera). For each room it runs ``naoloc survey`` (the recorder and
the survey behaviour, the side found by the robot itself) and what ``naoloc build-map``
does before it trains the map: the wall-referenced keyframe poses and the map checks
(:mod:`naoloc.mapping.checks`). The vocabulary and the GCS are not trained: they do not
move the map frame.

Per room it prints:

- ``ok``: the survey completed, the checks passed, and the map frame is within 3 cm and
  1 deg of the truth with its scale within 0.5 % (the issue's success);
- the frame's error, in the map frame: the map's room (``wall_poses.wall_frame`` +
  ``walls_m``, what the localizer's floor lines use) fitted rigidly onto the true room:
  ``origin`` (how far the map origin is from where the survey truly started, relative to
  the walls, m) and ``heading`` (deg), and ``walls`` (the largest corner error before the
  fit, m); the keyframes' positions fitted onto their true ones by a similarity: ``scale``
  (%), with that fit's origin and RMS residual (m) for the keyframes themselves;
- the checks' verdicts (failed ones named), and whether the survey ended with an error;
- the robot's time (simulated seconds) against the circuit walked at NAO's speed plus the
  head's moves for the pictures.

A run is a wrong answer when its map frame is more than 0.1 m off (the map's origin, by the
room's or the keyframes' fit) and no check refused it; accepted maps whose room corners are
more than 0.1 m off (a heading error across a large room) are counted apart.

Usage:
    MUJOCO_GL=egl .venv/bin/python tools/eval_survey.py -n 24 [--seeds S ...] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from naoloc.config import Config, load_config
from naoloc.constants import WALK_SPEED, WALK_SPEED_THETA
from naoloc.errors import NaolocError

SIZE_X = (3.0, 10.0)
SIZE_Y = (3.0, 8.0)
OFFSET = (0.5, 1.2)
LIGHT = (0.3, 1.5)
MIN_SIDE_M = 1.5  # the offset is capped so that the circuit's shorter side is this long
FRAME_OK_M = 0.03
FRAME_OK_DEG = 1.0
SCALE_OK = 0.005
WRONG_M = 0.1


def draw_room(seed: int) -> dict[str, Any]:
    """The room, survey offset and start drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    sx = round(float(rng.uniform(*SIZE_X)), 1)
    sy = round(float(rng.uniform(SIZE_Y[0], min(SIZE_Y[1], sx))), 1)
    top = min(OFFSET[1], (min(sx, sy) - MIN_SIDE_M) / 2)
    offset = round(float(rng.uniform(OFFSET[0], max(OFFSET[0], top))), 2)
    return {
        "seed": seed,
        "size_m": [sx, sy],
        "style": str(rng.choice(["home", "office"])),
        "light": round(float(rng.uniform(*LIGHT)), 2),
        "offset_m": offset,
        "corner": int(rng.integers(0, 4)),
        "wall": str(rng.choice(["right", "left"])),
    }


def start_of(room: dict[str, Any]) -> tuple[tuple[float, float, float], tuple[float, float]]:
    """The start pose (room frame) and the circuit's sides (first side, second side), m.

    Corners count counter-clockwise from the room frame's origin. With the wall on the
    right the robot faces along the wall that leads counter-clockwise; on the left, the
    other one.
    """
    sx, sy = room["size_m"]
    off = room["offset_m"]
    corners = [(off, off), (sx - off, off), (sx - off, sy - off), (off, sy - off)]
    k = room["corner"]
    ccw = [0.0, math.pi / 2, math.pi, -math.pi / 2]  # wall on the right
    cw = [math.pi / 2, math.pi, -math.pi / 2, 0.0]  # wall on the left
    theta = (ccw if room["wall"] == "right" else cw)[k]
    along_x = abs(math.cos(theta)) > 0.5
    a, b = sx - 2 * off, sy - 2 * off
    sides = (a, b) if along_x else (b, a)
    return (corners[k][0], corners[k][1], theta), (round(sides[0], 3), round(sides[1], 3))


def room_config(room: dict[str, Any], laps: int) -> Config:
    """The config of one drawn room (default honest world)."""
    start, sides = start_of(room)
    if "start" in room:  # a start of one's own (room frame) and the circuit's sides
        start, sides = tuple(room["start"]), tuple(room["sides"])
    return load_config(
        {
            "robot": {"backend": "mujoco"},
            "world": {
                "room": {
                    "size_m": room["size_m"],
                    "seed": room["seed"],
                    "style": room["style"],
                    **({"posters_per_wall": room["posters"]} if "posters" in room else {}),
                },
                "sim": {"light": room["light"]},
                "start_pose": list(start),
                # each room its own NAO's odometry errors (--odometry-per-room), else seed 0's
                **(
                    {"odometry": {"seed": room["odometry_seed"]}} if "odometry_seed" in room else {}
                ),
            },
            "survey": {
                "laps": laps,
                "step_m": 0.2,
                "wall_offset_m": room["offset_m"],
                "side_m": list(sides),
            },
        }
    )


def similarity(
    src: np.ndarray, dst: np.ndarray, rigid: bool = False
) -> tuple[float, float, np.ndarray]:
    """Scale, rotation (rad) and translation mapping ``src`` (n x 2) onto ``dst`` (Umeyama;
    ``rigid``: scale 1)."""
    mu_s, mu_d = src.mean(0), dst.mean(0)
    a, b = src - mu_s, dst - mu_d
    cov = b.T @ a / len(src)
    u, sig, vt = np.linalg.svd(cov)
    d = np.diag([1.0, np.sign(np.linalg.det(u @ vt))])
    rot = u @ d @ vt
    var = float((a**2).sum() / len(src))
    scale = 1.0 if rigid else float(np.trace(np.diag(sig) @ d) / var)
    t = mu_d - scale * rot @ mu_s
    return scale, math.atan2(rot[1, 0], rot[0, 0]), t


def frame_error(keyframes: list[Any], meta: dict[str, Any], posed: list[Any]) -> dict[str, Any]:
    """The map frame against the truth: similarity fit of the map positions on the truth."""
    from naoloc.geometry import Pose2D

    origin = Pose2D.from_list(meta["origin_room_pose"])
    truth = np.array([(origin.inverse() * kf.true_pose).to_list() for kf in keyframes])
    est = np.array([kf.pose.to_list() for kf in posed])
    scale, rot, t = similarity(est[:, :2], truth[:, :2])
    residual = (
        truth[:, :2]
        - (
            scale
            * np.array([[math.cos(rot), -math.sin(rot)], [math.sin(rot), math.cos(rot)]])
            @ est[:, :2].T
        ).T
        - t
    )
    return {
        "origin_m": round(float(np.hypot(*t)), 4),
        "heading_deg": round(math.degrees(rot), 3),
        "scale_pct": round((scale - 1.0) * 100, 3),
        "fit_rms_m": round(float(np.sqrt((residual**2).sum(1).mean())), 4),
    }


def room_frame_error(meta_walls: dict[str, Any] | None, meta: dict[str, Any]) -> dict[str, Any]:
    """The map's room (``wall_poses.wall_frame`` + ``walls_m``) against the true room, both
    in the map frame: a rigid fit of the map's four corners onto the true ones gives where
    the map origin truly is (``origin_m``) and how the map is turned (``heading_deg``);
    ``walls_m`` is the largest corner distance before the fit."""
    from naoloc.geometry import Pose2D

    if not meta_walls or "wall_frame" not in meta_walls:
        return {"origin_m": None, "heading_deg": None, "walls_m": None}
    frame = Pose2D(*meta_walls["wall_frame"])
    x0, x1, y0, y1 = meta_walls["walls_m"]
    mine = [frame * Pose2D(x, y, 0.0) for x, y in ((x0, y0), (x1, y0), (x1, y1), (x0, y1))]
    origin = Pose2D.from_list(meta["origin_room_pose"])
    sx, sy = meta["room_size_m"]
    true = [origin.inverse() * Pose2D(x, y, 0.0) for x, y in ((0, 0), (sx, 0), (sx, sy), (0, sy))]
    src = np.array([[p.x, p.y] for p in mine])
    dst = np.array([min(((q.x, q.y) for q in true), key=lambda q: math.dist(q, p)) for p in src])
    _, rot, t = similarity(src, dst, rigid=True)
    return {
        "origin_m": round(float(np.hypot(*t)), 4),
        "heading_deg": round(math.degrees(rot), 3),
        "walls_m": round(float(np.max(np.hypot(*(src - dst).T))), 4),
    }


class Clock:
    """Simulated seconds spent inside the robot's moveTo and head moves."""

    def __init__(self, robot: Any) -> None:
        self.walk_s = 0.0
        self.head_s = 0.0
        sim, motion = robot.sim, robot.motion
        move, turn_head = motion.moveTo, motion.angleInterpolationWithSpeed

        def timed_move(*args: Any, **kwargs: Any) -> Any:
            t = sim.sim_time()
            try:
                return move(*args, **kwargs)
            finally:
                self.walk_s += sim.sim_time() - t

        def timed_head(*args: Any, **kwargs: Any) -> Any:
            t = sim.sim_time()
            try:
                return turn_head(*args, **kwargs)
            finally:
                self.head_s += sim.sim_time() - t

        motion.moveTo = timed_move
        motion.angleInterpolationWithSpeed = timed_head


def run_room(room: dict[str, Any], laps: int, out: Path) -> dict[str, Any]:
    """Survey one room, pose its keyframes as build-map does, check and measure them."""
    import naoloc
    from naoloc.data.recorder import record_survey

    cfg = room_config(room, laps)
    path = out / f"survey_{room['seed']}.mcap"
    row: dict[str, Any] = {**room, "error": None}
    t0 = time.monotonic()
    with naoloc.connect(cfg) as robot:
        clock = Clock(robot)
        s0 = robot.sim.sim_time()
        try:
            record_survey(robot, cfg, path)
        except NaolocError as err:
            row["error"] = str(err).splitlines()[0]
        row["robot_s"] = round(robot.sim.sim_time() - s0, 1)
        row["walk_s"] = round(clock.walk_s, 1)
        row["head_s"] = round(clock.head_s, 1)
    row["wall_s"] = round(time.monotonic() - t0, 1)
    a, b = cfg.survey_sides()
    row["circuit_s"] = round(laps * (2 * (a + b) / WALK_SPEED + 2 * math.pi / WALK_SPEED_THETA), 1)
    return analyse(row, cfg, path)


def analyse(row: dict[str, Any], cfg: Config, path: Path) -> dict[str, Any]:
    """Pose a recorded survey's keyframes as build-map does, check and measure them."""
    from naoloc.data.dataset import partial_path_for, read_dataset

    data_path = path if path.exists() else partial_path_for(path)
    if not data_path.exists():
        row.update(complete=False, frames=0)
        return row
    data = read_dataset(data_path)
    row.update(complete=data.complete, frames=len(data.keyframes))
    if len(data.keyframes) < 3:
        return row
    try:
        from naoloc.mapping.from_survey import pose_survey, run_checks
    except ImportError:  # a tree from before the checks (PYTHONPATH=that tree): no checks
        from naoloc.mapping.from_survey import survey_keyframes

        posed, facts = survey_keyframes(data, cfg.map, cfg.survey.wall_offset_m)
        row["keyframes"] = frame_error(data.keyframes, data.meta, posed)
        row["room"] = room_frame_error(facts["wall_poses"], data.meta)
        row["checks"] = None
        return row
    posed, facts, walled = pose_survey(data, cfg.map, cfg.survey.wall_offset_m)
    row["wall_poses"] = walled is not None
    row["keyframes"] = frame_error(data.keyframes, data.meta, posed)
    row["room"] = room_frame_error(facts["wall_poses"], data.meta)
    checks = run_checks(data, cfg.map, walled)
    row["checks"] = {c.name: c.verdict for c in checks}
    row["check_figures"] = {c.name: c.figure for c in checks}
    return row


def verdicts(row: dict[str, Any]) -> tuple[bool, bool, bool]:
    """(accepted: complete and every check passed; the frame within the success bounds;
    the frame more than WRONG_M off)."""
    checks = row.get("checks") or {}
    passed = bool(row.get("complete")) and row["error"] is None
    passed = passed and all(v != "fail" for v in checks.values())
    room, kf = row.get("room") or {}, row.get("keyframes") or {}
    if room.get("origin_m") is None or not kf:
        return passed, False, True
    good = (
        room["origin_m"] <= FRAME_OK_M
        and abs(room["heading_deg"]) <= FRAME_OK_DEG
        and abs(kf["scale_pct"]) <= SCALE_OK * 100
    )
    wrong = max(room["origin_m"], kf["origin_m"]) > WRONG_M
    return passed, good, wrong


def line_of(row: dict[str, Any]) -> str:
    """One printed line per room."""
    passed, good, wrong = verdicts(row)
    room, kf = row.get("room") or {}, row.get("keyframes") or {}
    failed = [k for k, v in (row.get("checks") or {}).items() if v == "fail"]
    nan = float("nan")

    def num(v: Any) -> float:
        return nan if v is None else float(v)

    return (
        f"seed {row['seed']:>10} {row['size_m'][0]:4.1f} x {row['size_m'][1]:3.1f} "
        f"{row['style']:6} light {row['light']:.2f} off {row['offset_m']:.2f} "
        f"corner {row['corner']} wall {row['wall']:5} | "
        f"{'ok ' if passed and good else 'BAD'} frames {row.get('frames', 0):3} "
        f"origin {num(room.get('origin_m')):.3f} m heading {num(room.get('heading_deg')):+.2f} "
        f"walls {num(room.get('walls_m')):.3f} m scale {num(kf.get('scale_pct')):+.2f} % "
        f"(keyframes: origin {num(kf.get('origin_m')):.3f} m, rms {num(kf.get('fit_rms_m')):.3f}"
        f" m) | checks {'pass' if passed else 'REFUSED ' + ','.join(failed or ['survey'])} | "
        f"robot {row.get('robot_s')} s (walk {row.get('walk_s')}, head {row.get('head_s')}, "
        f"circuit {row.get('circuit_s')}) | wall {row.get('wall_s')} s"
        + (f" | error: {row['error']}" if row["error"] else "")
        + (" | WRONG AND ACCEPTED" if wrong and passed else "")
    )


def main() -> int:
    """Draw the rooms, run each, print the rows and the totals."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("-n", type=int, default=24, help="rooms (seeds from os.urandom)")
    parser.add_argument("--seeds", type=int, nargs="+", default=None, help="room seeds")
    parser.add_argument("--laps", type=int, default=2)
    parser.add_argument("--out", type=Path, default=None, help="datasets folder (not the repo)")
    parser.add_argument("--json", type=Path, default=None, help="write the rows here")
    parser.add_argument(
        "--reanalyse", type=Path, default=None, metavar="ROWS.json",
        help="measure again the datasets a run wrote (its --json rows and --out folder)",
    )  # fmt: skip
    parser.add_argument(
        "--room", type=str, default=None,
        help="one room as JSON (size_m, style, light, offset_m, corner, wall, seed; optional "
        "posters, and start [x, y, theta] with sides [a, b])",
    )  # fmt: skip
    parser.add_argument(
        "--odometry-per-room", action="store_true",
        help="draw each room's odometry errors from its seed (default: world.odometry.seed 0, "
        "one NAO's odometry for every room)",
    )  # fmt: skip
    args = parser.parse_args()
    if args.room:
        rooms = [json.loads(args.room)]
    else:
        seeds = args.seeds or [int.from_bytes(os.urandom(4), "little") >> 1 for _ in range(args.n)]
        rooms = [draw_room(s) for s in seeds]
    if args.odometry_per_room:
        rooms = [{**room, "odometry_seed": room["seed"]} for room in rooms]
    out = args.out or Path(tempfile.mkdtemp(prefix="naoloc_eval_survey_"))
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    previous = {}
    if args.reanalyse:
        previous = {r["seed"]: r for r in json.loads(args.reanalyse.read_text(encoding="utf-8"))}
        rooms = [draw_room(seed) for seed in previous]
    for room in rooms:
        if room["seed"] in previous:
            keep = ("error", "robot_s", "walk_s", "head_s", "wall_s", "circuit_s")
            row = {**room, **{k: previous[room["seed"]].get(k) for k in keep}}
            row = analyse(row, room_config(room, args.laps), out / f"survey_{room['seed']}.mcap")
        else:
            row = run_room(room, args.laps, out)
        rows.append(row)
        print(line_of(row), flush=True)
        if args.json:
            args.json.write_text(json.dumps(rows, indent=1), encoding="utf-8")
    n = len(rows)
    flags = [verdicts(r) for r in rows]
    success = sum(1 for p, g, _ in flags if p and g)
    wrong_accepted = sum(1 for p, _, w in flags if p and w)
    wrong = sum(1 for _, _, w in flags if w)
    far_walls = [r for r, (p, _, _) in zip(rows, flags, strict=True)
                 if p and ((r.get("room") or {}).get("walls_m") or 0) > WRONG_M]  # fmt: skip
    origins = [r["room"]["origin_m"] for r in rows if (r.get("room") or {}).get("origin_m")]
    ratio = [r["robot_s"] / (r["circuit_s"] + r["head_s"]) for r in rows if r.get("complete")]
    print(
        f"rooms {n}: success {success}/{n} ({100 * success / max(1, n):.0f} %); "
        f"frames more than {WRONG_M} m off: {wrong}, accepted by the checks: {wrong_accepted}; "
        f"accepted maps with a room corner more than {WRONG_M} m off: {len(far_walls)}; "
        f"origin error median {np.median(origins) if origins else float('nan'):.3f} m, "
        f"max {max(origins) if origins else float('nan'):.3f} m; robot time / (circuit at "
        f"NAO speed + head moves) median {np.median(ratio) if ratio else float('nan'):.2f}, "
        f"max {max(ratio) if ratio else float('nan'):.2f}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
