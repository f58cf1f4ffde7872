"""How well a survey's bag-of-words histograms recognise places: one lap against another.

Usage::

    python tools/bow_study.py SURVEY.mcap [more.mcap ...] [--sizes 64 256 1024]

The paper's localizer (Algorithm 5, ``localize.mode: paper``) returns the pose that the
GCS winners of 1-2 query histograms carry; it can be no better than the nearest training
image over the same histograms (docs/history/RESULTS.md measured the two equal). This tool measures
that signal without the survey's pose errors, camera placement or GCS in the way: it trains
the vocabulary on the first lap's pictures, and for each picture of the later laps takes the
first lap's picture with the nearest histogram. The error is the distance between the two
pictures' true robot positions (m), so a perfect place recogniser scores the spacing of the
survey's steps. Variants:

- vocabulary size (``--sizes``);
- weighting: ``tf`` (word counts over the picture's keypoints) or ``tfidf`` (the map's);
- distance: ``l2`` between L2-normalised histograms (the GCS's) or DBoW2's ``l1`` score;
- the features' threshold: the map's adaptive A-KAZE, or a fixed 0.001 (the paper's).

It prints one line per variant: median, p90 and the share within 0.5 m; ``nearest pose`` is
the error of the first lap's picture taken nearest (the best any retrieval can do). Needs a
simulator dataset (true poses) of at least two laps. Nothing is written.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from wall_pose_accuracy import sim_survey

from naoloc.config import load_config
from naoloc.errors import NaolocError
from naoloc.mapping.vocabulary import dbow_scores, l2_normalise, train_vocabulary
from naoloc.perception.features import FeatureExtractor


def _retrieval_errors(
    hists: np.ndarray, train: np.ndarray, test: np.ndarray, xy: np.ndarray, distance: str
) -> np.ndarray:
    """Per test picture, the true distance (m) to the training picture it retrieves."""
    out = []
    for i in test:
        if distance == "l2":
            d = np.sum((hists[train] - hists[i]) ** 2, axis=1)
            j = train[int(np.argmin(d))]
        else:
            j = train[int(np.argmax(dbow_scores(hists[i], hists[train])))]
        out.append(math.dist(xy[i], xy[j]))
    return np.asarray(out)


def _line(name: str, err: np.ndarray) -> str:
    return (
        f"  {name:34s} median {np.median(err):5.2f} m  p90 {np.percentile(err, 90):5.2f} m  "
        f"within 0.5 m {np.mean(err <= 0.5):4.0%}"
    )


def study(path: Path, sizes: list[int]) -> list[str]:
    """The study's lines for one dataset (see the module doc)."""
    data, truth = sim_survey(path)
    laps = np.asarray(data.laps or [0] * len(data.keyframes))
    if laps.max() < 1:
        raise NaolocError(f"{path}: one lap only; the study needs two")
    cfg = load_config(data.config if isinstance(data.config, dict) else None).map
    xy = np.array([[t.x, t.y] for t in truth])  # map frame: distances as in the room's
    train, test = np.flatnonzero(laps == 0), np.flatnonzero(laps > 0)
    lines = [f"{path}: {len(train)} pictures in lap 1, {len(test)} in the later laps"]
    nearest = np.array([np.min(np.hypot(*(xy[train] - xy[i]).T)) for i in test])
    lines.append(_line("nearest pose (best possible)", nearest))
    extractors = {
        "adaptive A-KAZE": FeatureExtractor(
            cfg.features, akaze_threshold=cfg.akaze_threshold, min_keypoints=cfg.min_keypoints
        ),
        "A-KAZE at 0.001": FeatureExtractor(cfg.features, akaze_threshold=0.001),
    }
    for fname, extractor in extractors.items():
        descs = [extractor.extract(kf.image).descriptors for kf in data.keyframes]
        counts = np.array([len(d) for d in descs])
        lines.append(f" {fname}: keypoints per picture median {int(np.median(counts))}")
        for size in sizes:
            vocab = train_vocabulary([descs[i] for i in train], size, extractor.binary, cfg.seed)
            words = [vocab.assign(d) for d in descs]
            tf = np.array([np.bincount(w, minlength=vocab.size) / max(len(w), 1) for w in words])
            for weighting, raw in (("tf", tf), ("tfidf", tf * vocab.idf)):
                hists = l2_normalise(raw)
                for distance in ("l2", "l1"):
                    err = _retrieval_errors(hists, train, test, xy, distance)
                    lines.append(_line(f"{vocab.size} words, {weighting}, {distance}", err))
    return lines


def main() -> int:
    """Run the study on each dataset and print it."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("datasets", type=Path, nargs="+", help="simulator survey .mcap files")
    parser.add_argument("--sizes", type=int, nargs="+", default=[64, 256, 1024])
    args = parser.parse_args()
    for path in args.datasets:
        try:
            lines = study(path, args.sizes)
        except NaolocError as err:
            print(f"bow_study: {err}", file=sys.stderr)
            return 2
        print("\n".join(lines), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
