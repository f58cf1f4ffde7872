"""The paper's Algorithm 5: the mean pose of the winning GCS neurons of 1-2 pictures.

Kept as the seed paper has it, for its protocol and tables: each picture's TF-IDF
histogram wins a neuron (among those that carry a pose), and the estimate is the mean of
those neurons' poses, turned by each picture's head yaw and odometry. It has no geometry:
its "confidence" is how close the histograms came to their neurons, not a probability.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from naoloc.geometry import circular_mean, modulo2PI
from naoloc.localization.localizer import PoseEstimate, Status, turn_scale_of
from naoloc.mapping.data import MapData
from naoloc.perception.features import Features
from naoloc.robot.keyframe import Keyframe

__all__ = ["featured_neuron_poses", "localize_nearest_image", "localize_paper"]


def featured_neuron_poses(vmap: MapData) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Neuron poses (Algorithm 4, line 7) from the keyframes that have keypoints.

    A keyframe without keypoints has an empty histogram that carries no place; a neuron that
    wins only such keyframes carries no pose and must not win a query. Only the wall
    pictures count (the paper's images; the survey's far pictures are not).

    Returns:
        ``posed`` (P,) neuron indices, their ``(P, 3)`` mean poses (map frame: m, m, rad)
        and ``(P,)`` mean camera headings (rad).
    """
    has = np.diff(vmap.kp_offsets) > 0
    has[vmap.wall_images :] = False
    win = vmap.winners[has]
    k = vmap.gcs.size
    count = np.bincount(win, minlength=k).astype(np.float64)
    posed = np.flatnonzero(count > 0)
    poses = vmap.keyframe_poses[has]
    views = poses[:, 2] + vmap.keyframe_heads[has, 0]

    def mean(v: np.ndarray) -> np.ndarray:
        return np.bincount(win, weights=v, minlength=k)[posed] / count[posed]

    def circ(a: np.ndarray) -> np.ndarray:
        return np.arctan2(mean(np.sin(a)), mean(np.cos(a)))

    out = np.column_stack([mean(poses[:, 0]), mean(poses[:, 1]), circ(poses[:, 2])])
    return posed, out, circ(views)


def _turns_to_last(queries: Sequence[Keyframe], turn_scale: float) -> list[float]:
    """Per query, the robot's turn from it to the last query (rad), de-scaled."""
    turn, out = 0.0, [0.0]
    for a, b in itertools.pairwise(reversed(queries)):  # last to first
        turn += modulo2PI(a.pose.theta - b.pose.theta)
        out.append(turn / turn_scale)
    return out[::-1]


def localize_paper(
    vmap: MapData, feats: Sequence[Features], queries: Sequence[Keyframe]
) -> PoseEstimate:
    """Algorithm 5: mean pose of the winning neurons of the query histograms (map frame)."""
    posed, neuron_poses, neuron_views = featured_neuron_poses(vmap)
    usable = [i for i, f in enumerate(feats) if len(f) > 0]
    nan = float("nan")
    if not usable or posed.size == 0:
        reason = "no features" if not usable else "no posed neuron"
        return PoseEstimate(nan, nan, nan, None, 0.0, Status.LOST, reason, "none")
    turns = _turns_to_last(queries, turn_scale_of(vmap.meta))
    xs, ys, headings, closeness, winners = [], [], [], [], []
    weights = vmap.gcs.weights[posed]
    for i in usable:
        hist = vmap.vocabulary.histogram(feats[i].descriptors)
        d2 = np.sum((weights - hist[None, :]) ** 2, axis=1)
        j = int(np.argmin(d2))
        winners.append(int(posed[j]))
        xs.append(neuron_poses[j, 0])
        ys.append(neuron_poses[j, 1])
        headings.append(neuron_views[j] - queries[i].head_yaw + turns[i])
        closeness.append(max(0.0, 1.0 - math.sqrt(float(d2[j])) / math.sqrt(2.0)))
    conf = len(usable) / len(feats) * float(np.mean(closeness))
    theta = circular_mean(np.asarray(headings), np.ones(len(headings)))
    return PoseEstimate(
        float(np.mean(xs)), float(np.mean(ys)), modulo2PI(theta),
        None, float(np.clip(conf, 0.0, 1.0)), Status.TRACKING, "", "gcs",
        {"neurons": winners},
    )  # fmt: skip


def localize_nearest_image(vmap: Any, queries: Sequence[Keyframe]) -> PoseEstimate:
    """The plain nearest-neighbour baseline: does the GCS network earn its place?

    Exactly the paper's Algorithm 5 with the network taken out: each query's histogram
    (same features, vocabulary and distance as the GCS winner search) is matched to the
    nearest *training image* histogram instead of the nearest neuron, and the estimate is
    the mean pose of those images (map frame, at the last query). Training images without
    keypoints are left out.

    Args:
        vmap: A :class:`naoloc.mapping.VisualMap`.
        queries: Query images; their odometry poses give the turn between them.
    """
    feats = vmap.extract(queries)
    usable = [i for i, f in enumerate(feats) if len(f) > 0]
    poses = np.asarray(vmap.keyframe_poses, dtype=np.float64)
    nan = float("nan")
    if not usable or len(poses) == 0:
        return PoseEstimate(nan, nan, nan, None, 0.0, Status.LOST, "no features", "none")
    hists = np.asarray(vmap.histograms, dtype=np.float64)
    heads = np.asarray(vmap.keyframe_heads, dtype=np.float64)
    # Training images without a keypoint have no histogram to compare: leave them out (an
    # empty histogram would be the nearest one to every unusual query).
    has_kp = np.diff(np.asarray(vmap.kp_offsets)) > 0
    if not has_kp.any():
        has_kp[:] = True
    has_kp[vmap.wall_images :] = False  # the paper's training images: the wall pictures
    hists = np.where(has_kp[:, None], hists, np.inf)
    turns = _turns_to_last(queries, 1.0)
    xs, ys, sin_sum, cos_sum, closeness, images = [], [], 0.0, 0.0, [], []
    for i in usable:
        hist = vmap.vocabulary.histogram(feats[i].descriptors)
        d2 = np.sum((hists - hist[None, :]) ** 2, axis=1)
        j = int(np.argmin(d2))
        images.append(j)
        xs.append(poses[j, 0])
        ys.append(poses[j, 1])
        view = poses[j, 2] + heads[j, 0]  # camera heading of the training image, map frame
        theta_last = view - queries[i].head_yaw + turns[i]
        sin_sum += math.sin(theta_last)
        cos_sum += math.cos(theta_last)
        closeness.append(max(0.0, 1.0 - math.sqrt(float(d2[j])) / math.sqrt(2.0)))
    conf = len(usable) / len(feats) * float(np.mean(closeness))
    return PoseEstimate(
        float(np.mean(xs)), float(np.mean(ys)), modulo2PI(math.atan2(sin_sum, cos_sum)),
        None, float(np.clip(conf, 0.0, 1.0)), Status.TRACKING, "", "nearest-image",
        {"images": images},
    )  # fmt: skip
