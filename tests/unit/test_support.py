"""The landmarks' places along one axis (:func:`naoloc.mapping.support.axis_peaks`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from naoloc.geometry import Pose2D
from naoloc.mapping.support import SupportMatches, axis_peaks

FRAME = Pose2D(0.4, -0.3, 0.2)  # the wall frame in the map frame
TRUTH_W = Pose2D(2.3, 0.9, 0.6)  # the robot in the wall frame
CAMERA = np.array([0.05, 0.01])  # camera centre in the robot frame, m


def _matches(seed: int, n_true: int = 60, n_wrong: int = 200) -> SupportMatches:
    """Rays from the camera at :data:`TRUTH_W` through landmarks 0.5-4 m away, and wrong
    matches whose landmarks lie anywhere in the room."""
    rng = np.random.default_rng(seed)
    truth = FRAME * TRUTH_W
    bearing = rng.uniform(-1.2, 1.2, n_true)
    dist = rng.uniform(0.5, 4.0, n_true)
    ray_true = np.column_stack([np.cos(bearing), np.sin(bearing)])
    local = CAMERA + dist[:, None] * ray_true  # the landmarks in the robot frame
    c, s = math.cos(truth.theta), math.sin(truth.theta)
    world = local @ np.array([[c, s], [-s, c]]) + (truth.x, truth.y)
    wrong = rng.uniform([-1.0, -1.0], [5.0, 4.0], (n_wrong, 2))
    b_wrong = rng.uniform(-1.2, 1.2, n_wrong)
    ray = np.vstack([ray_true, np.column_stack([np.cos(b_wrong), np.sin(b_wrong)])])
    points = np.column_stack([np.vstack([world, wrong]), np.full(n_true + n_wrong, 1.0)])
    n = n_true + n_wrong
    return SupportMatches(
        points, np.zeros((n, 2)), np.zeros((n, 3, 4)), np.arange(n), np.tile(CAMERA, (n, 1)), ray
    )


@pytest.mark.parametrize("axis", [0, 1])
def test_the_landmarks_agree_where_the_robot_is(axis: int) -> None:
    fixed = TRUTH_W.y if axis == 0 else TRUTH_W.x
    for seed in range(3):
        peaks = axis_peaks(_matches(seed), FRAME, TRUTH_W.theta, axis, fixed, (-0.9, 3.9))
        assert peaks, seed
        best, count = peaks[0]
        assert best == pytest.approx(TRUTH_W.x if axis == 0 else TRUTH_W.y, abs=0.03)
        assert count >= 40  # rays nearly along the axis say nothing and are left out
        assert all(abs(c - best) >= 0.3 for c, _ in peaks[1:])


def test_no_peak_outside_the_span_or_from_wrong_matches_alone() -> None:
    m = _matches(0)
    assert all(c <= 2.0 for c, _ in axis_peaks(m, FRAME, TRUTH_W.theta, 0, TRUTH_W.y, (0, 2.0)))
    only_wrong = _matches(0, n_true=0, n_wrong=40)
    assert axis_peaks(only_wrong, FRAME, TRUTH_W.theta, 0, TRUTH_W.y, (-0.9, 3.9)) == []
    assert axis_peaks(m, FRAME, TRUTH_W.theta, 0, TRUTH_W.y, (1.0, 1.0)) == []
