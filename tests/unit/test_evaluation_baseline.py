"""The nearest-image baseline on a synthetic map (histograms chosen by hand)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from naoloc.geometry import Pose2D
from naoloc.localization.paper import localize_nearest_image as nearest_neighbour
from naoloc.robot.keyframe import Keyframe


def _map(n_words: int = 3) -> SimpleNamespace:
    """Image i (< n_words) holds word i only; the last image has no keypoint at all."""
    eye = np.eye(n_words)
    return SimpleNamespace(
        extract=None,  # set by each test
        vocabulary=SimpleNamespace(histogram=lambda d: eye[d] * 0.9 + 0.1 / n_words),
        histograms=np.vstack([eye, np.zeros((1, n_words))]),
        keyframe_poses=np.array([[0, 0, 0], [2, 0, 0], [2, 2, math.pi / 2], [9, 9, 0]], float),
        keyframe_heads=np.array([[-math.pi / 2, 0.0]] * 4),
        kp_offsets=np.array([0, 5, 10, 15, 15]),
        wall_images=4,  # no far pictures
    )


class _Empty:
    descriptors = None

    def __len__(self) -> int:
        return 0


class _Len(SimpleNamespace):
    def __len__(self) -> int:
        return 1


def _query(word: int, pose: Pose2D, head_yaw: float) -> Keyframe:
    return Keyframe(np.full((4, 4), word, np.uint8), pose, head_yaw=head_yaw)


def test_nearest_image_pose_and_heading() -> None:
    vmap = _map()
    vmap.extract = lambda qs: [_Len(descriptors=int(q.image[0, 0])) for q in qs]
    # Query 0 sees image 1's words with the head at -pi/2 (as the map), robot turned by 0.
    est = nearest_neighbour(vmap, [_query(1, Pose2D(5, 5, 0.3), -math.pi / 2)])
    assert (est.x, est.y) == pytest.approx((2.0, 0.0))
    assert est.theta == pytest.approx(0.0)
    assert est.method == "nearest-image" and est.evidence["images"] == [1]
    # Two queries: mean pose; the heading is the last query's (turned +0.5 rad in place).
    q1 = _query(1, Pose2D(0, 0, 0.0), -math.pi / 2)
    q2 = _query(2, Pose2D(0, 0, 0.5), -math.pi / 2)
    est = nearest_neighbour(vmap, [q1, q2])
    assert (est.x, est.y) == pytest.approx((2.0, 1.0))
    assert est.evidence["images"] == [1, 2]
    assert 0 < est.confidence <= 1


def test_images_without_keypoints_never_win_and_no_features_gives_zero_confidence() -> None:
    vmap = _map()
    vmap.extract = lambda qs: [_Len(descriptors=int(q.image[0, 0])) for q in qs]
    est = nearest_neighbour(vmap, [_query(0, Pose2D(), -math.pi / 2)])
    assert est.evidence["images"] == [0]
    vmap.extract = lambda qs: [_Empty() for _ in qs]
    est = nearest_neighbour(vmap, [_query(0, Pose2D(), 0.0)])
    assert est.confidence == 0.0 and est.method == "none" and not est.found


def test_far_pictures_are_never_the_nearest_training_image() -> None:
    """The survey's far pictures (after the wall pictures) are not the paper's training
    images: the nearest-image baseline never picks one, however close its histogram."""
    vmap = _map()
    vmap.extract = lambda qs: [_Len(descriptors=int(q.image[0, 0])) for q in qs]
    assert nearest_neighbour(vmap, [_query(2, Pose2D(), -math.pi / 2)]).evidence["images"] == [2]
    vmap.wall_images = 2  # image 2 (and the empty one) as far pictures
    est = nearest_neighbour(vmap, [_query(2, Pose2D(), -math.pi / 2)])
    assert est.evidence["images"] != [2] and est.evidence["images"][0] < 2
