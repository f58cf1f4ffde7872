"""How far a survey's keyframe poses are from the simulator's truth: odometry vs walls.

Usage::

    naoloc survey -c paper_room -o /tmp/s.mcap
    python tools/wall_pose_accuracy.py /tmp/s.mcap [more.mcap ...] [--map MAP.npz]

For each dataset it prints, in the map frame (the survey start), the position error of
the keyframes' odometry poses and of the wall-referenced poses build-map uses
(``map.wall_poses``, :mod:`naoloc.mapping.wall_poses`): median, p90 and max (m), the median heading
error (rad), and the ratio of the medians; then the survey's floor-wall lines against the
truth (the wall the measured normal points at, the room's size): side lines, and front lines
by distance band. Needs a simulator's dataset (true poses, ``origin_room_pose``,
``room_size_m``) of a rectangular room.

``--along`` prints instead, pooled over the datasets that completed, each wall pose's error
along its side (the walking direction; the error across a side is the side lines') with
the survey's far front lines (``far_front``) and without them, as build-map would place the
poses (the survey's skirting included), then the survey's last side (which no next wall
ends): its RMS and its last frame's error (the survey's start, where go-home ends)::

    python tools/wall_pose_accuracy.py --along /tmp/es/survey_*.mcap
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from naoloc.data.dataset import read_dataset
from naoloc.errors import NaolocError
from naoloc.geometry import Pose2D
from naoloc.mapping.wall_poses import wall_poses


def sim_survey(path: str | Path) -> tuple[Any, list[Pose2D]]:
    """A simulator's survey and its keyframes' true poses in the map frame.

    Raises:
        NaolocError: The file is not a readable dataset, or has no ground truth.
    """
    data = read_dataset(path)
    origin = data.meta.get("origin_room_pose")
    if origin is None or any(kf.true_pose is None for kf in data.keyframes):
        raise NaolocError(f"{path}: no ground truth (not a simulator's survey)")
    o = Pose2D(*origin)
    return data, [o.inverse() * kf.true_pose for kf in data.keyframes if kf.true_pose]


def pose_errors(poses: list[Pose2D], truth: list[Pose2D]) -> tuple[np.ndarray, np.ndarray]:
    """Position (m) and wrapped heading (rad) errors of poses against the truth."""
    pos = np.array([math.dist((p.x, p.y), (t.x, t.y)) for p, t in zip(poses, truth, strict=True)])
    head = np.array(
        [
            abs(math.remainder(p.theta - t.theta, 2 * math.pi))
            for p, t in zip(poses, truth, strict=True)
        ]
    )
    return pos, head


def _wall_distance(pose: Pose2D, normal: float, size: tuple[float, float]) -> float:
    """True distance from ``pose`` (room frame) to the room wall in direction ``normal``
    (FRAME_ROBOT, rad)."""
    a = pose.theta + normal
    c, s = math.cos(a), math.sin(a)
    if abs(c) >= abs(s):
        return size[0] - pose.x if c > 0 else pose.x
    return size[1] - pose.y if s > 0 else pose.y


def line_errors(data: Any) -> None:
    """Print the floor lines' errors (measured minus true distance) of one dataset."""
    size = data.meta.get("room_size_m")
    vision = data.meta.get("vision")
    if not isinstance(size, list) or not isinstance(vision, list):
        return
    sides: list[float] = []
    fronts: list[tuple[float, float]] = []
    for i, (kf, entry) in enumerate(zip(data.keyframes, vision, strict=False)):
        side = entry.get("side")
        if side and kf.true_pose is not None:
            true = _wall_distance(kf.true_pose, side["normal_rad"], (size[0], size[1]))
            sides.append(side["distance_m"] - true)
        front = entry.get("front")
        before = data.keyframes[i - 1].true_pose if i else None
        if front and before is not None:  # measured at the frame before the step
            true = _wall_distance(before, front["normal_rad"], (size[0], size[1]))
            fronts.append((true, front["distance_m"] - true))
    if sides:
        err = np.abs(sides)
        print(f"  side lines: n {len(sides)}, median error {np.median(sides):+.3f} m, |error| "
              f"median {np.median(err):.3f} m, p90 {np.percentile(err, 90):.3f} m")  # fmt: skip
    for lo, hi in ((0.9, 1.3), (1.3, 1.7), (1.7, 2.2)):
        band = [(t, e) for t, e in fronts if lo <= t < hi]
        if band:
            rel = np.median([e / t for t, e in band]) * 100
            print(f"  front lines {lo:.1f}-{hi:.1f} m: n {len(band)}, median error "
                  f"{np.median([e for _, e in band]):+.3f} m ({rel:+.1f} %)")  # fmt: skip


def along_errors(data: Any, truth: list[Pose2D], far: bool) -> np.ndarray | None:
    """Each wall pose's error along its side (m, + ahead of the truth), in the room frame;
    ``far``: with the survey's far front lines. None when build-map keeps the odometry."""
    from naoloc.mapping.from_survey import survey_skirting

    meta = data.meta
    if not far and isinstance(meta.get("vision"), list):
        meta = {**meta, "vision": [{k: v for k, v in e.items() if k != "far_front"}
                                   for e in meta["vision"]]}  # fmt: skip
    offset = float(data.config.get("survey", {}).get("wall_offset_m", 1.0))
    walled = wall_poses(data.keyframes, meta, offset=offset, skirting=survey_skirting(data))
    if walled is None:
        return None
    turn = float(meta["origin_room_pose"][2])  # the map frame's heading in the room
    out = []
    for kf, t in zip(walled.keyframes, truth, strict=True):
        c, s = math.cos(turn), math.sin(turn)
        ex, ey = kf.pose.x - t.x, kf.pose.y - t.y
        room = (c * ex - s * ey, s * ex + c * ey)
        walk = round((t.theta + turn) / (math.pi / 2)) * math.pi / 2  # the side's direction
        out.append(room[0] * math.cos(walk) + room[1] * math.sin(walk))
    return np.array(out)


def along_report(paths: list[str]) -> int:
    """Print the pooled along-side errors with and without the far front lines."""
    pooled: dict[bool, list[np.ndarray]] = {True: [], False: []}
    last_side: list[float] = []  # per survey: its last side's RMS, and its last frame's error
    home: list[float] = []
    for path in paths:
        try:
            data, truth = sim_survey(path)
        except NaolocError as err:
            print(f"wall_pose_accuracy: {err}", file=sys.stderr)
            return 2
        if not data.complete:
            continue
        runs = {far: along_errors(data, truth, far) for far in (False, True)}
        if runs[False] is None or runs[True] is None:
            continue
        for far, errors in runs.items():
            pooled[far].append(errors)
        sides = [entry.get("side_index") for entry in data.meta["vision"]]
        last = runs[True][[i for i, k in enumerate(sides) if k == sides[-1]]]
        last_side.append(float(np.sqrt(np.mean(last**2))))
        home.append(abs(float(runs[True][-1])))
    for far in (False, True):
        if not pooled[far]:
            print("no completed survey with wall poses")
            return 2
        every = np.abs(np.concatenate(pooled[far]))
        rms = [float(np.sqrt(np.mean(e**2))) for e in pooled[far]]
        print(
            f"{'with' if far else 'without':7s} far fronts: {len(rms)} surveys, "
            f"|along error| median {np.median(every):.3f} m, p90 {np.percentile(every, 90):.3f}"
            f" m, p99 {np.percentile(every, 99):.3f} m; per survey RMS median "
            f"{np.median(rms):.3f} m, max {max(rms):.3f} m"
        )
    print(
        f"the last side (no next wall ends it): RMS median {np.median(last_side):.3f} m, p90 "
        f"{np.percentile(last_side, 90):.3f} m; its last frame (at the start, home) |error| "
        f"median {np.median(home):.3f} m, p90 {np.percentile(home, 90):.3f} m, max "
        f"{max(home):.3f} m, more than 0.05 m in {sum(h > 0.05 for h in home)} of {len(home)}"
    )
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("datasets", nargs="+")
    parser.add_argument(
        "--map", help="a map built from the (one) dataset: also its bundle-adjusted poses"
    )
    parser.add_argument(
        "--along",
        action="store_true",
        help="pooled error along the sides, with and without the far front lines",
    )
    args = parser.parse_args(argv)
    if args.along:
        return along_report(args.datasets)
    for path in args.datasets:
        try:
            data, truth = sim_survey(path)
        except NaolocError as err:
            print(f"wall_pose_accuracy: {err}", file=sys.stderr)
            return 2
        offset = float(data.config.get("survey", {}).get("wall_offset_m", 1.0))
        walled = wall_poses(data.keyframes, data.meta, offset=offset)
        rows = [("odometry", [kf.pose for kf in data.keyframes])]
        if walled is not None:
            rows.append(("walls", [kf.pose for kf in walled.keyframes]))
        medians = []
        for name, poses in rows:
            pos, head = pose_errors(poses, truth)
            medians.append(float(np.median(pos)))
            print(
                f"{path}: {name:8s} median {np.median(pos):.3f} m"
                f"  p90 {np.percentile(pos, 90):.3f} m  max {pos.max():.3f} m"
                f"  heading median {np.median(head):.4f} rad"
            )
        if walled is not None:
            print(
                f"{path}: {walled.summary()}; "
                f"odometry/walls median ratio {medians[0] / medians[1]:.1f}x"
            )
        else:
            print(
                f"{path}: build-map keeps the odometry poses "
                "(no floor-line records, or too few corners)"
            )
        if args.map:
            from naoloc.mapping import load_map

            vmap = load_map(args.map)
            refined = [Pose2D(*p) for p in vmap.refined_poses[: vmap.wall_images]]
            if len(refined) == len(truth):
                pos, head = pose_errors(refined, truth)
                print(f"{path}: map      median {np.median(pos):.3f} m"
                      f"  p90 {np.percentile(pos, 90):.3f} m  max {pos.max():.3f} m"
                      f"  heading median {np.median(head):.4f} rad (bundle-adjusted)")  # fmt: skip
        line_errors(data)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
