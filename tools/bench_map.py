"""Benchmark of the map (Algorithms 4 and 5) on one core, printed next to the paper.

Usage::

    .venv/bin/python tools/bench_map.py [--seed 0] [--trials 20]
    .venv/bin/python tools/bench_map.py --vocabulary [--dataset SURVEY.mcap] [--images 200]
        [--old-rev REV] [--repeats 5]

1. Surveys the default 6 x 6 m room on the fake backend (two laps of a 4 x 4 m square,
   0.2 m steps, head to the wall) and keeps 164 QVGA images, as in the paper's Table 1.
2. Builds maps of 100/200/300 neurons and epochs and prints the build time split into
   features, vocabulary and GCS (plus landmarks) next to the paper's Table 2.
3. Times localization from two QVGA images in both modes next to the A-KAZE extraction
   time of the same two images, in the same run, and prints both modes' errors at random
   poses 0.6-1.4 m from the walls (scan of 5 head yaws, and the 2-image case).

``--vocabulary``: the vocabulary stage of build-map (training plus the images' histograms)
of the current code against ``naoloc/mapping/vocabulary.py`` of git revision ``--old-rev``
(default: the last one before the packed-Hamming speed-up), in the same process on the same
descriptors (A-KAZE of ``--dataset``, or of a 200-image survey of the fake backend),
alternating old and new; prints best-of-N times, the ratio, and whether centres, IDF, every
word assignment and every histogram are identical. Then it builds the whole map with the
old revision (in a subprocess, from ``git archive``) and with the current code and compares
every array and the metadata of the two map files.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import math  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from types import ModuleType  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

import naoloc  # noqa: E402
from naoloc.config import CameraConfig, MapConfig, load_config  # noqa: E402
from naoloc.data.dataset import read_dataset  # noqa: E402
from naoloc.geometry import Pose2D, relative_pose  # noqa: E402
from naoloc.localization import Localizer, Picture, PoseEstimate  # noqa: E402
from naoloc.localization.paper import localize_paper  # noqa: E402
from naoloc.mapping import VisualMap, build_map, load_map  # noqa: E402
from naoloc.mapping.gcs import train_gcs  # noqa: E402
from naoloc.mapping.mapfile import map_bytes  # noqa: E402
from naoloc.mapping.vocabulary import train_vocabulary  # noqa: E402
from naoloc.perception.features import FeatureExtractor  # noqa: E402
from naoloc.robot.camera import Camera, look  # noqa: E402
from naoloc.robot.keyframe import Keyframe  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
OLD_VOCAB_REV = "670fda5d215446d16c5736d5a718c3f651a35f44"  # before the packed-Hamming speed-up

PAPER_TABLE2 = {100: (4.063, 72), 200: (14.287, 111), 300: (33.347, 132)}
PITCH = -0.2
SCAN_YAWS = (-2.0, -1.0, 0.0, 1.0, 2.0)


def _shot(camera: Camera, yaw: float) -> Keyframe:
    """A picture with the head at ``yaw`` (rad), pose from raw odometry (FRAME_WORLD)."""
    look(camera.robot, yaw, PITCH)
    return camera.keyframe()[0]


def collect(
    seed: int, trials: int, images: int = 164
) -> tuple[list[Keyframe], list[tuple[list[Keyframe], Pose2D]]]:
    """``images`` survey keyframes and ``trials`` scans at random poses with their truth."""
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
        while len(survey) < images:
            for side in (sx, sy, sx, sy):
                for _ in range(round(side / 0.2)):
                    if len(survey) < images:
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


def load_old_package(rev: str) -> Path:
    """A temporary folder holding the ``naoloc`` package of git revision ``rev``."""
    folder = Path(tempfile.mkdtemp(prefix="naoloc_old_"))
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", rev, "naoloc"], check=True, capture_output=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    return folder


def load_old_vocabulary(folder: Path) -> ModuleType:
    """``naoloc/mapping/vocabulary.py`` of the old package as a stand-alone module."""
    spec = importlib.util.spec_from_file_location(
        "vocabulary_old", folder / "naoloc" / "mapping" / "vocabulary.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["vocabulary_old"] = module  # dataclasses look their module up while decorating
    spec.loader.exec_module(module)
    return module


def _vocabulary_stage(
    module: ModuleType, descs: list[np.ndarray], cfg: MapConfig, batch: bool
) -> tuple[float, object, np.ndarray]:
    """Seconds of train + histograms as build-map runs it, the vocabulary, the histograms."""
    t = time.perf_counter()
    vocab = module.train_vocabulary(descs, cfg.vocabulary_size, True, cfg.seed)
    # The old build_map took one histogram per image.
    hists = vocab.histograms(descs) if batch else np.stack([vocab.histogram(d) for d in descs])
    return time.perf_counter() - t, vocab, hists


def _old_map_checksum(folder: Path, keyframes_from: str, cfg: MapConfig, out: Path) -> None:
    """Build the map of a dataset with the old package in a subprocess; write it to ``out``."""
    code = (
        "import sys, numpy as np\n"
        "from naoloc.data.dataset import read_dataset\n"
        "from naoloc.config import MapConfig\n"
        "from naoloc.mapping import build_map\n"
        "from naoloc.mapping.mapfile import map_bytes\n"
        "kfs = read_dataset(sys.argv[1]).keyframes\n"
        "vm = build_map(kfs, MapConfig.model_validate_json(sys.argv[2]))\n"
        "vm.timings = {}\n"
        "open(sys.argv[3], 'wb').write(map_bytes(vm))\n"
    )
    env = {**os.environ, "PYTHONPATH": str(folder)}
    subprocess.run(
        [sys.executable, "-c", code, keyframes_from, cfg.model_dump_json(), str(out)],
        check=True,
        env=env,
    )


def bench_vocabulary(args: argparse.Namespace) -> None:
    """Old vs new vocabulary stage in the same process, then old vs new map identity."""
    cfg = MapConfig(seed=0)
    work = Path(tempfile.mkdtemp(prefix="bench_vocab_"))
    if args.dataset is not None:
        dataset = Path(args.dataset)
    else:  # a survey of args.images frames on the fake backend: 2 laps of a 4 x 4 m square
        dataset = work / "survey.mcap"
        survey_cfg = work / "survey.yaml"
        survey_cfg.write_text(
            "robot: {backend: fake}\n"
            f"world: {{room: {{size_m: [6.0, 6.0], seed: {args.seed}}}}}\n"
            f"survey: {{laps: 2, step_m: {32.0 / args.images}, wall_offset_m: 1.0}}\n"
        )
        subprocess.run(
            [sys.executable, "-m", "naoloc.app.cli", "survey", "-c", str(survey_cfg), "-o",
             str(dataset)],
            check=True,
            capture_output=True,
        )  # fmt: skip
    keyframes = read_dataset(dataset).keyframes
    extractor = FeatureExtractor(cfg.features)
    descs = [extractor.extract(kf.gray()).descriptors for kf in keyframes]
    print(
        f"vocabulary stage: {len(descs)} images, {sum(len(d) for d in descs)} A-KAZE "
        f"descriptors, {cfg.vocabulary_size} words, old = {args.old_rev[:10]}"
    )
    folder = load_old_package(args.old_rev)
    old_mod = load_old_vocabulary(folder)
    new_mod = sys.modules[train_vocabulary.__module__]
    old_t, new_t = [], []
    for _ in range(args.repeats):
        t, old_v, old_h = _vocabulary_stage(old_mod, descs, cfg, batch=False)
        old_t.append(t)
        t, new_v, new_h = _vocabulary_stage(new_mod, descs, cfg, batch=True)
        new_t.append(t)
    same_words = all(
        np.array_equal(old_v.assign(d), new_v.assign(d))  # type: ignore[attr-defined]
        for d in descs
    )
    same = (
        np.array_equal(old_v.centres, new_v.centres)  # type: ignore[attr-defined]
        and np.array_equal(old_v.idf, new_v.idf)  # type: ignore[attr-defined]
        and np.array_equal(old_h, new_h)
    )
    print(
        f"  old {min(old_t):.3f} s, new {min(new_t):.3f} s (best of {args.repeats}): "
        f"{min(old_t) / min(new_t):.2f}x faster; centres/IDF/histograms identical: {same}; "
        f"every word assignment identical: {same_words}"
    )
    old_path, new_path = work / "old.npz", work / "new.npz"
    _old_map_checksum(folder, str(dataset), cfg, old_path)
    vm = build_map(keyframes, cfg)
    vm.timings = {}
    new_path.write_bytes(map_bytes(vm))
    old_map, new_map = load_map(old_path), load_map(new_path)
    fields = [
        "neuron_poses", "neuron_views", "keyframe_poses", "refined_poses", "keyframe_heads",
        "keyframe_cameras", "histograms", "winners", "kp_offsets", "kp_points", "kp_desc",
        "kp_xy",
    ]  # fmt: skip
    diff = [
        f
        for f in fields
        if not np.array_equal(getattr(old_map, f), getattr(new_map, f), equal_nan=True)
    ]
    for name, a, b in (
        ("vocabulary", old_map.vocabulary.centres, new_map.vocabulary.centres),
        ("idf", old_map.vocabulary.idf, new_map.vocabulary.idf),
        ("gcs", old_map.gcs.weights, new_map.gcs.weights),
    ):
        if not np.array_equal(a, b):
            diff.append(name)
    old_cfg = old_map.config.model_dump()  # the old file has no tuning: read as the defaults
    new_cfg = new_map.config.model_dump()
    same_meta = old_map.meta == new_map.meta and old_map.feature_params == new_map.feature_params
    print(
        f"  whole map, old vs new build: arrays that differ: {diff or 'none'}; metadata "
        f"identical: {same_meta}; config identical (the new tuning block at its defaults): "
        f"{old_cfg == new_cfg}; vocabulary_s of a new build "
        f"{build_map(keyframes, cfg).timings['vocabulary_s']:.3f} s"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="room seed")
    parser.add_argument("--trials", type=int, default=20, help="random localization poses")
    parser.add_argument(
        "--vocabulary", action="store_true", help="old vs new vocabulary stage and map identity"
    )
    parser.add_argument("--dataset", help="survey .mcap for --vocabulary (default: fake survey)")
    parser.add_argument("--images", type=int, default=200, help="fake survey size (--vocabulary)")
    parser.add_argument("--old-rev", default=OLD_VOCAB_REV, help="git revision of the old code")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs of each (--vocabulary)")
    args = parser.parse_args()
    cv2.setNumThreads(1)
    if args.vocabulary:
        bench_vocabulary(args)
        return
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
            _estimate(vm, pair, mode)
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
                est = _estimate(vm, [queries[i] for i in pick], mode)
                errs.append(math.hypot(est.x - truth.x, est.y - truth.y))
                heads.append(abs(math.degrees(naoloc.modulo2PI(est.theta - truth.theta))))
            print(
                f"  {label:20s} {mode:8s}: median {np.median(errs):.3f} m, "
                f"p90 {np.percentile(errs, 90):.3f} m, max {np.max(errs):.3f} m, "
                f"median heading {np.median(heads):.1f} deg"
            )


def _estimate(vm: VisualMap, queries: list[Keyframe], mode: str) -> PoseEstimate:
    """The paper's Algorithm 5, or the filter fed the pictures (``verified``)."""
    if mode == "paper":
        return localize_paper(vm, vm.extract(queries), queries)
    loc = Localizer(vm)
    for q in queries:
        loc.update(Picture(q))
    return loc.pose()


if __name__ == "__main__":
    main()
