"""Compute of one localization on one core: feature extraction and the verified localizer.

Usage::

    naoloc survey -o /tmp/s.mcap && naoloc build-map /tmp/s.mcap -o /tmp/m.npz
    python tools/bench_localize.py /tmp/s.mcap /tmp/m.npz [--pictures 7 28] [--repeats 5]

Queries are survey pictures of the dataset taken 4 apart (the timing does not depend on
where they were taken; their answers are not scored here, tools/eval_unseen_rooms.py does
that). In the same process, best of ``--repeats`` CPU times:

1. A-KAZE extraction per picture: the adaptive threshold in one pass (the current
   :class:`naoloc.mapping.features.FeatureExtractor`) against a pass per threshold (the
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

from naoloc.dataset import read_dataset  # noqa: E402
from naoloc.errors import NaolocError  # noqa: E402
from naoloc.geometry import Pose2D  # noqa: E402
from naoloc.mapping import load_map  # noqa: E402
from naoloc.mapping.features import FeatureExtractor  # noqa: E402
from naoloc.mapping.support import (  # noqa: E402
    SupportMatches,
    axis_peaks,
    pose_support,
    support_matches,
)


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
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
