"""The paper mode at the Table 3 positions, with the query pictures taken several ways.

Usage::

    naoloc evaluate -c paper_room --protocol paper -o OUT      # a survey and its maps
    python tools/paper_query_views.py OUT/config.yaml OUT/maps/akaze-300.npz

At each of the paper protocol's 20 poses (4 positions x 5 headings) it localizes in the
paper's mode (Algorithm 5, the GCS winners' mean pose) from pictures taken:

- ``paper``: the nearest wall from the keypoint halves of a forward picture, the head
  straight at it, the second picture 0.5 rad toward the front (naoloc before the change);
- ``floor lines``: the same, with the nearest wall from the bottom camera's floor lines;
- ``survey view``: nearest wall from the floor lines, the head turned by the survey's
  look-ahead (as the survey took its pictures), one picture;
- ``naoloc``: :func:`naoloc.behaviours.localize.paper_queries` as ``localize`` calls it
  (the survey view and a second picture 0.1 rad nearer the wall's normal).

It prints each pose's errors and which side each detector chose, then the mean error per
position next to the paper's. Nothing is written.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from naoloc.behaviours.localize import paper_queries, survey_look_ahead, truth_in_map
from naoloc.behaviours.nearest_wall import detect_nearest_wall, detect_wall_by_floorline
from naoloc.behaviours.wall_follow import FloorEye
from naoloc.config import load_config
from naoloc.evaluation.protocols import PAPER_POSITIONS, paper_poses
from naoloc.localization.paper import localize_paper
from naoloc.mapping import load_map
from naoloc.robot.camera import Camera, lens_of, look, stand
from naoloc.robot.keyframe import Keyframe
from naoloc.robot.registry import connect


def main() -> int:
    """Localize at the paper's poses with each way of taking the pictures; print errors."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("config", type=Path, help="the evaluation's config.yaml")
    parser.add_argument("map", type=Path, help="a map of that survey (.npz)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the paper poses")
    args = parser.parse_args()
    cfg = load_config(args.config)
    vmap = load_map(args.map)
    meta = vmap.meta
    ahead = survey_look_ahead(meta)
    pitch = cfg.localize.head_pitch_rad
    ways = ("paper", "floor lines", "survey view", "naoloc")
    errors: dict[str, list[tuple[int, float]]] = {w: [] for w in ways}
    with connect(cfg) as robot:
        if robot.sim is None:
            raise SystemExit("paper_query_views: needs a simulator backend")
        eye = FloorEye(robot, cfg.camera, "naoloc_views_floor", lens=lens_of(cfg))
        try:
            with Camera(robot, cfg.localize.camera(cfg.camera), "naoloc_views") as cam:

                def shots(yaws: list[float]) -> list[Keyframe]:
                    out = []
                    for yaw in yaws:
                        look(robot, yaw, pitch)
                        out.append(cam.keyframe()[0])
                    return out

                for pose in paper_poses(tuple(meta["origin_room_pose"]), args.seed):
                    robot.sim.teleport(*pose.room_pose)
                    stand(robot)
                    truth = truth_in_map(robot, meta)
                    assert truth is not None
                    halves = detect_nearest_wall(robot, cam, pitch).head_yaw
                    lines = detect_wall_by_floorline(robot, eye, pitch)
                    floor = lines.head_yaw if lines.side is not None else halves
                    sign = math.copysign(1.0, floor)
                    views = {
                        "paper": shots([halves, halves - math.copysign(0.5, halves)]),
                        "floor lines": shots([floor, floor - sign * 0.5]),
                        "survey view": shots([floor - sign * ahead]),
                        "naoloc": paper_queries(cam, 2, pitch=pitch, look_ahead=ahead, eye=eye),
                    }
                    line = f"position {pose.group}: halves {'left' if halves > 0 else 'right'}"
                    line += f", floor lines {lines.side}:"
                    for way, queries in views.items():
                        est = localize_paper(vmap, vmap.extract(queries), queries)
                        err = (
                            math.hypot(est.x - truth.x, est.y - truth.y) if est.found else math.inf
                        )
                        errors[way].append((pose.group, err))
                        line += f"  {way} {err:.2f}"
                    print(line, flush=True)
        finally:
            eye.close()
    print("mean error per position (m), 1 / 2 / 3 / 4:")
    for way in ways:
        table = np.array(errors[way])
        means = [float(np.mean(table[table[:, 0] == p.number, 1])) for p in PAPER_POSITIONS]
        print(f"  {way:12s} " + " / ".join(f"{m:.2f}" for m in means))
    paper = [p.paper_mean_error_m() for p in PAPER_POSITIONS]
    print(f"  {'the paper':12s} " + " / ".join(f"{m:.2f}" for m in paper))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
