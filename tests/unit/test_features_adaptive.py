"""Adaptive A-KAZE in one pass (naoloc.perception.features.FeatureExtractor)."""

from __future__ import annotations

import cv2
import numpy as np

from naoloc.perception.features import AKAZE_FLOOR, FeatureExtractor


def _dim_image(contrast: float, seed: int = 0) -> np.ndarray:
    """A QVGA picture of soft blobs at ``contrast`` (grey levels), like a dim wall."""
    rng = np.random.default_rng(seed)
    noise = cv2.GaussianBlur(rng.normal(0, 1, (240, 320)).astype(np.float32), (0, 0), 3)
    img = 128 + contrast * noise / noise.std()
    return np.clip(img, 0, 255).astype(np.uint8)


def _per_threshold(gray: np.ndarray, ladder: tuple[float, ...], least: int) -> tuple[int, float]:
    """Keypoints of the old way (a pass per threshold) and the threshold it stopped at."""
    n, t = 0, ladder[0]
    for t in ladder:
        n = len(cv2.AKAZE_create(threshold=t).detect(gray, None))
        if n >= least:
            break
    return n, t


def test_one_pass_keeps_what_a_pass_per_threshold_keeps() -> None:
    ex = FeatureExtractor("akaze", akaze_threshold=0.001, min_keypoints=100)
    ladder = ex.thresholds
    assert ladder[0] == 0.001 and ladder[-1] >= AKAZE_FLOOR * 0.999 and len(ladder) == 4
    stopped = set()
    for contrast in (4.0, 8.0, 16.0, 40.0):
        gray = _dim_image(contrast)
        n_old, t = _per_threshold(gray, ladder, 100)
        stopped.add(t)
        feats = ex.extract(gray)
        assert abs(len(feats) - n_old) <= max(2, n_old // 50)  # a keypoint or two at most
        assert len(feats) >= 100 or t == ladder[-1]
        assert (feats.response > t * 0.999).all()
    assert len(stopped) >= 2  # the images really needed different thresholds


def test_fixed_threshold_is_opencvs_own() -> None:
    gray = _dim_image(40.0, seed=2)
    ex = FeatureExtractor("akaze", akaze_threshold=0.001)
    kps = cv2.AKAZE_create(threshold=0.001).detect(gray, None)
    assert len(ex.extract(gray)) == len(kps)
