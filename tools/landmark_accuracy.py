"""How far a map's landmarks stand from where the true keyframe poses put them.

Usage::

    python tools/landmark_accuracy.py OUT/room_* [--map akaze-300.npz]

Each folder is one of ``tools/eval_unseen_rooms.py``'s rooms (``surveys/base.mcap`` and
``maps/MAP``). The map's landmarks were triangulated from its keyframes' map poses; the
same keypoints are triangulated again from the survey's true poses (the simulator's, in
the map frame), and each landmark's error is split along the ray from its keyframe's camera
(the depth a short baseline gives, which a landmark's own error mostly is) and across it.
Prints, per kind of picture (wall: the survey's pictures of the wall beside it; far: its
views across the room) and per range of that ray's length: the robust std of the error
along the ray (1.4826 MAD), that std per metre of ray, and the error across the ray. The
reference carries its own pixel noise, so the figures are upper bounds.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from naoloc.data.dataset import read_dataset
from naoloc.geometry import Pose2D
from naoloc.mapping import load_map
from naoloc.mapping.builder import map_extractor
from naoloc.mapping.landmarks import camera_poses, triangulate

RANGES = ((0.0, 1.0), (1.0, 1.5), (1.5, 2.0), (2.0, 3.0), (3.0, 4.0), (4.0, 5.0), (5.0, 6.0),
          (6.0, 8.0), (8.0, 12.0))  # fmt: skip


def room_errors(room: Path, map_name: str) -> np.ndarray:
    """``(n, 4)``: far (0/1), ray length (m), error along the ray (m), across it (m)."""
    data = read_dataset(room / "surveys" / "base.mcap")
    vmap = load_map(room / "maps" / map_name)
    origin = Pose2D.from_list(data.meta["origin_room_pose"])
    keyframes = [*data.keyframes, *(kf for _, kf in data.far)]
    n = len(keyframes)
    if n != vmap.keyframe_poses.shape[0]:
        raise SystemExit(f"{room}: the map has {vmap.keyframe_poses.shape[0]} keyframes, "
                         f"the survey {n}")  # fmt: skip
    truth = np.array([(origin.inverse() * kf.true_pose).to_list() for kf in keyframes])
    index = [int(c[4]) for c in vmap.keyframe_cameras]
    cams = camera_poses(vmap.refined_poses, vmap.keyframe_heads, index)
    true_cams = camera_poses(truth, vmap.keyframe_heads, index)
    offsets = vmap.kp_offsets
    xys = [vmap.kp_xy[offsets[i] : offsets[i + 1]].astype(float) for i in range(n)]
    descs = [vmap.kp_desc[offsets[i] : offsets[i + 1]] for i in range(n)]
    kmats = [vmap.keyframe_camera(i).matrix() for i in range(n)]
    reference = triangulate(
        xys, descs, true_cams, kmats, map_extractor(vmap.config).binary,
        tuning=vmap.config.tuning.landmarks, far_from=len(data.keyframes),
    ).points  # fmt: skip
    points = vmap.kp_points
    frame = np.repeat(np.arange(n), np.diff(offsets))
    both = np.isfinite(points[:, 0]) & np.isfinite(reference[:, 0])
    ray = points - cams[frame, :3, 3]
    length = np.linalg.norm(ray, axis=1)
    unit = ray / np.maximum(length, 1e-9)[:, None]
    err = points - reference
    along = np.einsum("ij,ij->i", err, unit)
    across = np.linalg.norm(err - along[:, None] * unit, axis=1)
    far = (frame >= len(data.keyframes)).astype(float)
    return np.column_stack([far, length, along, across])[both]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rooms", type=Path, nargs="+", help="eval_unseen_rooms room folders")
    parser.add_argument("--map", default="akaze-300.npz", help="map file in each maps/ folder")
    args = parser.parse_args(argv)
    rows = np.concatenate([room_errors(room, args.map) for room in args.rooms])
    for kind, name in ((0.0, "wall"), (1.0, "far")):
        sel = rows[:, 0] == kind
        print(f"{name} pictures' landmarks: {int(sel.sum())}")
        for lo, hi in RANGES:
            k = sel & (rows[:, 1] >= lo) & (rows[:, 1] < hi)
            if k.sum() < 30:
                continue
            along, across = rows[k, 2], rows[k, 3]
            sd = 1.4826 * float(np.median(np.abs(along - np.median(along))))
            print(f"  ray {lo:g}-{hi:g} m: {int(k.sum()):6d} landmarks, along the ray std "
                  f"{sd:.3f} m ({sd / ((lo + hi) / 2) * 100:.1f} % of the ray), p90 "
                  f"{np.percentile(np.abs(along), 90):.3f} m; across it median "
                  f"{np.median(across):.3f} m, p90 {np.percentile(across, 90):.3f} m")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
