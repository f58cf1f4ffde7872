"""Compute of one localization on one core: feature extraction and the verified localizer.

Usage::

    naoloc survey -o /tmp/s.mcap && naoloc build-map /tmp/s.mcap -o /tmp/m.npz
    python tools/bench_localize.py /tmp/s.mcap /tmp/m.npz [--pictures 7 28] [--repeats 5]

Queries are survey pictures of the dataset taken 4 apart (the timing does not depend on
where they were taken; their answers are not scored here, tools/eval_unseen_rooms.py does
that). In the same process, best of ``--repeats`` CPU times:

1. A-KAZE extraction per picture: the adaptive threshold in one pass (the current
   :class:`naoloc.perception.features.FeatureExtractor`) against a pass per threshold (the
   code before it, kept here as the baseline), with the ratio and how many pictures give
   the same keypoints.
2. One localization of ``--pictures`` pictures (a 7-yaw sweep, and four of them after
   turns in place): extraction plus the verified localizer, with the two-point planar
   RANSAC (``map.tuning.localizer.planar_samples``) and without it.
3. The floor-line fix's vote (:func:`naoloc.mapping.support.pose_support`) over
   ``--candidates`` poses (keyframe poses stand in for the floor's candidates: the time
   does not depend on where they are), against that localization; and its search of the
   axes no wall line gave (:func:`naoloc.mapping.support.axis_peaks`): the features
   matched once, then 32 searches (4 headings x 2 axes x 4 coordinates, more than a
   scan's lines give).
4. The two kernels made faster, each against its former code in the same process: the
   Hamming matching of the vote (descriptors zero-padded to 64 bytes for OpenCV's SIMD
   popcount, against ``BFMatcher.knnMatch`` on the 61-byte descriptors) and the planar
   RANSAC's scoring (float32 without angles, against float64 with ``arctan2``), on this
   scan's matches.
5. A whole worst-case scan as the localize behaviour runs it: four sweeps of 7 pictures
   (three quarter turns while unsure), the map asked after each, the heading again from
   the last sweep, then the floor step's matching, vote and axis searches; with the
   localizer's match memo (as the behaviour runs it) and without. Floor-line detection is
   not in a survey's dataset: tools/bench_scan_cpu.py times whole localizations in the
   simulator, and ``naoloc evaluate`` records each one's CPU (``compute_ms``).
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from typing import Any  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from naoloc.data.dataset import read_dataset  # noqa: E402
from naoloc.errors import NaolocError  # noqa: E402
from naoloc.geometry import Pose2D  # noqa: E402
from naoloc.mapping import load_map  # noqa: E402
from naoloc.mapping.landmarks import hamming_matcher  # noqa: E402
from naoloc.mapping.localizer import MatchMemo  # noqa: E402
from naoloc.mapping.planar_ransac import _score, lift  # noqa: E402
from naoloc.mapping.support import (  # noqa: E402
    SupportMatches,
    axis_peaks,
    pose_support,
    support_matches,
)
from naoloc.perception.features import FeatureExtractor  # noqa: E402


def _best_cpu(fn: Callable[[], Any], repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


AXIS_SEARCHES = 32


def _axis_searches(matches: SupportMatches) -> None:
    """4 headings x 2 axes x 4 coordinates of the other axis, along 7 m."""
    frame = Pose2D(0.0, 0.0, 0.0)
    for i in range(AXIS_SEARCHES):
        axis_peaks(matches, frame, (i // 8) * np.pi / 2, (i // 4) % 2, float(i % 4), (-1.0, 6.0))


def _knn_61(vmap: Any, feats: Any, k: int = 3) -> None:
    """The baseline matching: OpenCV's knnMatch on the unpadded descriptors."""
    points = np.asarray(vmap.kp_points, np.float64)
    desc = np.ascontiguousarray(vmap.kp_desc[np.isfinite(points).all(axis=1)])
    bf = cv2.BFMatcher(cv2.NORM_HAMMING)
    for f in feats:
        if len(f):
            bf.knnMatch(f.descriptors, desc, k=k)


def _score_f64(
    poses: np.ndarray,
    centres: np.ndarray,
    azimuths: np.ndarray,
    ranges: np.ndarray,
    points: np.ndarray,
    tol: float,
) -> np.ndarray:
    """The baseline scoring: float64 with arctan2 (the code before the float32 one)."""
    cos, sin = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    dx = points[None, :, 0] - poses[:, 0, None]
    dy = points[None, :, 1] - poses[:, 1, None]
    rx = cos * dx + sin * dy - centres[None, :, 0]
    ry = -sin * dx + cos * dy - centres[None, :, 1]
    err = np.abs((np.arctan2(ry, rx) - azimuths[None, :] + np.pi) % (2 * np.pi) - np.pi)
    dist = np.hypot(rx, ry)
    near = (dist < 1.6 * ranges[None, :] + 0.1) & (ranges[None, :] < 1.6 * dist + 0.1)
    return ((err < tol) & near).sum(axis=1)


def _kernels(vmap: Any, feats: Any, matches: SupportMatches, repeats: int) -> None:
    """Print the two kernels' times against their baselines (module doc, item 4)."""
    points = np.asarray(vmap.kp_points, np.float64)
    desc = np.ascontiguousarray(vmap.kp_desc[np.isfinite(points).all(axis=1)])
    matcher = hamming_matcher(True)
    t_pad = _best_cpu(
        lambda: [matcher.knn(f.descriptors, desc, 3) for f in feats if len(f)], repeats
    )
    t_61 = _best_cpu(lambda: _knn_61(vmap, feats), repeats)
    n_q = sum(len(f) for f in feats)
    print(
        f"    Hamming 3-NN of {n_q} features over {len(desc)} landmarks: padded {t_pad * 1e3:.0f}"
        f" ms, knnMatch on 61 bytes {t_61 * 1e3:.0f} ms = {t_61 / t_pad:.2f}x"
    )
    centres, az, _lifted, ranges, valid = lift(matches.mats, matches.points, matches.pixels)
    c, a, r, p = centres[valid], az[valid], ranges[valid], matches.points[valid, :2]
    rng = np.random.default_rng(0)
    lo, hi = p.min(axis=0), p.max(axis=0)
    poses = np.column_stack([rng.uniform(lo, hi, (512, 2)), rng.uniform(-np.pi, np.pi, 512)])
    tol = 4.0 / 280.0
    t32 = _best_cpu(lambda: _score(poses, c, a, r, p, tol), repeats)
    t64 = _best_cpu(lambda: _score_f64(poses, c, a, r, p, tol), repeats)
    same = int((_score(poses, c, a, r, p, tol) == _score_f64(poses, c, a, r, p, tol)).sum())
    print(
        f"    planar scoring of 512 poses over {len(a)} matches: float32 {t32 * 1e3:.1f} ms, "
        f"float64 arctan2 {t64 * 1e3:.1f} ms = {t64 / t32:.2f}x; same count for {same} of 512"
    )


def _whole_scan(vmap: Any, queries: list[Any], cands: list[Pose2D], memo: bool = True) -> None:
    """Four 7-picture sweeps as the localize behaviour runs them (module doc, item 5);
    ``memo``: with one :class:`naoloc.mapping.localizer.MatchMemo`, as the behaviour."""
    feats: list[Any] = []
    kept = MatchMemo() if memo else None
    for k in range(0, len(queries), 7):
        feats += vmap.extract(queries[k : k + 7])
        vmap.localize_features(feats, queries[: k + 7], memo=kept)
    vmap.localize_features(feats[-7:], queries[-7:], memo=kept)
    matches = support_matches(vmap, feats, queries)
    pose_support(vmap, feats, queries, cands, matches=matches)
    _axis_searches(matches)


def _per_threshold(ex: FeatureExtractor, gray: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The baseline: describe again at each lower threshold until enough keypoints."""
    kps: Any = ()
    desc: Any = None
    for t in ex.thresholds:
        kps, desc = cv2.AKAZE_create(threshold=t).detectAndCompute(gray, None)  # type: ignore[attr-defined]
        if len(kps) >= ex.min_keypoints:
            break
    return np.array([k.pt for k in kps], np.float32).reshape(-1, 2), desc


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset")
    parser.add_argument("map")
    parser.add_argument("--pictures", type=int, nargs="+", default=[7, 28])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--candidates", type=int, default=36)
    args = parser.parse_args(argv)
    cv2.setNumThreads(1)
    try:
        data = read_dataset(args.dataset)
        vmap = load_map(args.map)
    except NaolocError as err:
        print(f"bench_localize: {err}", file=sys.stderr)
        return 2
    ex = vmap.extractor()
    grays = [kf.gray() for kf in data.keyframes[::4]]
    same = 0
    for g in grays:
        a_xy, a_desc = _per_threshold(ex, g)
        b = ex.extract(g)
        same += int(a_xy.shape == b.xy.shape and np.array_equal(a_desc, b.descriptors))
    old = _best_cpu(lambda: [_per_threshold(ex, g) for g in grays], args.repeats)
    new = _best_cpu(lambda: [ex.extract(g) for g in grays], args.repeats)
    n = len(grays)
    print(
        f"A-KAZE (min_keypoints {ex.min_keypoints}), {n} QVGA pictures: one pass "
        f"{new / n * 1e3:.1f} ms/picture, a pass per threshold {old / n * 1e3:.1f} ms/picture "
        f"= {old / new:.2f}x; same keypoints in {same} of {n}"
    )
    tuning = vmap.config.tuning
    off = dataclasses.replace(
        vmap,
        config=vmap.config.model_copy(
            update={
                "tuning": tuning.model_copy(
                    update={"localizer": tuning.localizer.model_copy(update={"planar_samples": 0})}
                )
            }
        ),
    )
    for k in args.pictures:
        queries = data.keyframes[1::4][:k]
        if len(queries) < k:
            print(f"  {k} pictures: the dataset has too few", file=sys.stderr)
            continue
        t_on = _best_cpu(lambda q=queries: vmap.localize(q), args.repeats)
        t_off = _best_cpu(lambda q=queries: off.localize(q), args.repeats)
        t_ex = _best_cpu(lambda q=queries: vmap.extract(q), args.repeats)
        print(
            f"  localize {k:2d} pictures: {t_on * 1e3:.0f} ms CPU (extraction {t_ex * 1e3:.0f} "
            f"ms); without the planar RANSAC {t_off * 1e3:.0f} ms = {t_on / t_off:.2f}x"
        )
        feats = vmap.extract(queries)
        step = max(1, len(vmap.refined_poses) // args.candidates)
        cands = [Pose2D(*map(float, p)) for p in vmap.refined_poses[::step][: args.candidates]]
        t_vote = _best_cpu(
            lambda f=feats, q=queries, c=cands: pose_support(vmap, f, q, c), args.repeats
        )
        print(
            f"    floor-line vote over {len(cands)} candidates: {t_vote * 1e3:.0f} ms CPU "
            f"(the pictures' features reused) = {t_vote / t_on:.2f}x the localization"
        )
        t_match = _best_cpu(lambda f=feats, q=queries: support_matches(vmap, f, q), args.repeats)
        matches = support_matches(vmap, feats, queries)
        t_axes = _best_cpu(lambda m=matches: _axis_searches(m), args.repeats)
        print(
            f"    matching for the votes {t_match * 1e3:.0f} ms CPU; {AXIS_SEARCHES} axis "
            f"searches {t_axes * 1e3:.0f} ms = {t_axes / t_on:.2f}x the localization"
        )
        _kernels(vmap, feats, matches, args.repeats)
        if k == 28:
            t_scan = _best_cpu(lambda q=queries, c=cands: _whole_scan(vmap, q, c), args.repeats)
            t_bare = _best_cpu(
                lambda q=queries, c=cands: _whole_scan(vmap, q, c, memo=False), args.repeats
            )
            print(
                f"  a whole worst-case scan (4 sweeps of 7, asked after each, heading, floor "
                f"vote and axes): {t_scan * 1e3:.0f} ms CPU; without the match memo "
                f"{t_bare * 1e3:.0f} ms = {t_bare / t_scan:.2f}x"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
