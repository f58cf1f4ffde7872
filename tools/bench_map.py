"""Benchmark of the map (Algorithms 4 and 5) on one core, printed next to the paper.

Usage::

    .venv/bin/python tools/bench_map.py [--seed 0] [--trials 20]

1. Surveys the default 6 x 6 m room on the fake backend (two laps of a 4 x 4 m square,
   0.2 m steps, head to the wall) and keeps 164 QVGA images, as in the paper's Table 1.
2. Builds maps of 100/200/300 neurons and epochs and prints the build time split into
   features, vocabulary and GCS (plus landmarks) next to the paper's Table 2.
3. Times localization from two QVGA images in both modes next to the A-KAZE extraction
   time of the same two images, in the same run, and prints both modes' errors at random
   poses 0.6-1.4 m from the walls (scan of 5 head yaws, and the 2-image case).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

import naoloc  # noqa: E402
from naoloc.behaviours.camera import Camera, look  # noqa: E402
from naoloc.config import CameraConfig, MapConfig, load_config  # noqa: E402
from naoloc.geometry import Pose2D, relative_pose  # noqa: E402
from naoloc.keyframe import Keyframe  # noqa: E402
from naoloc.mapping import build_map  # noqa: E402
from naoloc.mapping.gcs import train_gcs  # noqa: E402

PAPER_TABLE2 = {100: (4.063, 72), 200: (14.287, 111), 300: (33.347, 132)}
PITCH = -0.2
SCAN_YAWS = (-2.0, -1.0, 0.0, 1.0, 2.0)


def _shot(camera: Camera, yaw: float) -> Keyframe:
    """A picture with the head at ``yaw`` (rad), pose from raw odometry (FRAME_WORLD)."""
    look(camera.robot, yaw, PITCH)
    return camera.keyframe()[0]


def collect(seed: int, trials: int) -> tuple[list[Keyframe], list[tuple[list[Keyframe], Pose2D]]]:
    """164 survey keyframes and ``trials`` scans at random poses with their truth (map frame)."""
    cfg = load_config({"robot": {"backend": "fake"}, "world": {"room": {"seed": seed}}})
    start = Pose2D(*cfg.start_pose())
    sx, sy = cfg.survey_sides()
    survey: list[Keyframe] = []
    scans: list[tuple[list[Keyframe], Pose2D]] = []
    rng = np.random.default_rng(seed + 100)
    room_x, room_y = cfg.world.room.size_m
    with naoloc.connect(cfg) as robot:
        assert robot.sim is not None
        robot.motion.wakeUp()
        robot.posture.goToPosture("StandInit", 0.5)
        camera = Camera(robot, CameraConfig(), "bench")
        while len(survey) < 164:
            for side in (sx, sy, sx, sy):
                for _ in range(round(side / 0.2)):
                    if len(survey) < 164:
                        survey.append(_shot(camera, -math.pi / 2))
                    robot.motion.moveTo(0.2, 0.0, 0.0)
                robot.motion.moveTo(0.0, 0.0, math.pi / 2)
        while len(scans) < trials:
            x, y = rng.uniform(0.6, room_x - 0.6), rng.uniform(0.6, room_y - 0.6)
            if not 0.6 <= min(x, y, room_x - x, room_y - y) <= 1.4:
                continue
            robot.sim.teleport(float(x), float(y), float(rng.uniform(-math.pi, math.pi)))
            queries = [_shot(camera, yaw) for yaw in SCAN_YAWS]
            scans.append((queries, relative_pose(start, Pose2D(*robot.sim.true_pose()))))
    return survey, scans


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="room seed")
    parser.add_argument("--trials", type=int, default=20, help="random localization poses")
    args = parser.parse_args()
    cv2.setNumThreads(1)
    t0 = time.perf_counter()
    survey, scans = collect(args.seed, args.trials)
    print(
        f"survey: {len(survey)} QVGA images, {len(scans)} scans ({time.perf_counter() - t0:.1f} s)"
    )

    print("\nBuild (one core)       features  vocab   GCS     landm.  total   distinct", end="")
    print(" | paper GCS  distinct")
    maps = {}
    for n in (100, 200, 300):
        vm = build_map(survey, MapConfig(neurons=n, epochs=n, seed=0))
        maps[n] = vm
        tm = vm.timings
        paper_s, paper_d = PAPER_TABLE2[n]
        print(
            f"  {n} neurons/{n} epochs  {tm['features_s']:6.2f}s {tm['vocabulary_s']:6.2f}s "
            f"{tm['gcs_s']:6.2f}s {tm['landmarks_s']:6.2f}s {tm['total_s']:6.2f}s "
            f"{vm.distinct_poses:5d}    | {paper_s:6.2f}s   {paper_d:4d}"
        )
    vm = maps[300]
    gcs_cpu, gcs_wall = [], []
    for _ in range(5):
        t, c = time.perf_counter(), time.process_time()
        train_gcs(vm.histograms, 300, 300, seed=0)
        gcs_cpu.append(time.process_time() - c)
        gcs_wall.append(time.perf_counter() - t)
    steps = 300 * len(survey)
    best = min(gcs_cpu)
    print(
        f"GCS alone, {len(survey)} x 300 epochs = {steps} steps, 300 neurons: best of 5 "
        f"{best:.3f} s CPU ({best / steps * 1e6:.1f} us/step), {min(gcs_wall):.3f} s wall, "
        f"load average {os.getloadavg()[0]:.1f} (target 0.5 s; see tools/bench_gcs.py)"
    )

    print("\nLocalize two QVGA images (same images, same run, median of 20):")
    extractor = vm.extractor()
    pair = [scans[0][0][1], scans[0][0][3]]
    ext: list[float] = []
    loc: dict[str, list[float]] = {"paper": [], "verified": []}
    for _ in range(20):
        t = time.perf_counter()
        for q in pair:
            extractor.extract(q.gray())
        ext.append(time.perf_counter() - t)
        for mode, times in loc.items():
            t = time.perf_counter()
            vm.localize(pair, mode=mode)
            times.append(time.perf_counter() - t)
    e_ms = 1000 * float(np.median(ext))
    print(f"  A-KAZE extraction of the 2 images: {e_ms:.1f} ms")
    for mode, target in (("paper", 1.2), ("verified", 2.0)):
        l_ms = 1000 * float(np.median(loc[mode]))
        print(
            f"  localize {mode:8s}: {l_ms:.1f} ms = {l_ms / e_ms:.2f}x extraction "
            f"(target <= {target}x)"
        )

    print("\nAccuracy at random poses 0.6-1.4 m from the walls (300-neuron map):")
    for label, pick in (("scan of 5 head yaws", [0, 1, 2, 3, 4]), ("2 images", [1, 3])):
        for mode in ("paper", "verified"):
            errs, heads = [], []
            for queries, truth in scans:
                est = vm.localize([queries[i] for i in pick], mode=mode)
                errs.append(math.hypot(est.x - truth.x, est.y - truth.y))
                heads.append(abs(math.degrees(naoloc.modulo2PI(est.theta - truth.theta))))
            print(
                f"  {label:20s} {mode:8s}: median {np.median(errs):.3f} m, "
                f"p90 {np.percentile(errs, 90):.3f} m, max {np.max(errs):.3f} m, "
                f"median heading {np.median(heads):.1f} deg"
            )


if __name__ == "__main__":
    main()
