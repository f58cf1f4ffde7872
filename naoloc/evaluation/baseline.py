"""The plain nearest-neighbour baseline: does the GCS network earn its place?

Exactly the paper's Algorithm 5 with the network taken out: each query's histogram (same
features, same vocabulary, same distance as the GCS winner search) is matched to the
nearest *training image* histogram instead of the nearest neuron, and the estimate is
the mean pose of those images. Training images without keypoints are left out. Built
only from the map's public data (``vocabulary``, ``histograms``, ``keyframe_poses``,
``keyframe_heads``, ``kp_offsets``, ``extract``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from naoloc.geometry import modulo2PI, relative_pose
from naoloc.robot.keyframe import Keyframe


def nearest_neighbour(vmap: Any, queries: Sequence[Keyframe]) -> Any:
    """Estimate the robot pose from the nearest training image of each query.

    Args:
        vmap: A :class:`naoloc.mapping.VisualMap`.
        queries: Query images; their odometry poses give the turn between them.

    Returns:
        A :class:`naoloc.mapping.Estimate` (mode ``"nearest"``) for the pose at the last query,
        map frame; no pose (method ``none``, NaN, confidence 0) when no query has features.
    """
    from naoloc.mapping import Estimate
    from naoloc.mapping.localizer import no_estimate

    feats = vmap.extract(queries)
    usable = [i for i, f in enumerate(feats) if len(f) > 0]
    poses = np.asarray(vmap.keyframe_poses, dtype=np.float64)
    if not usable or len(poses) == 0:
        return no_estimate("nearest", "no features")
    hists = np.asarray(vmap.histograms, dtype=np.float64)
    heads = np.asarray(vmap.keyframe_heads, dtype=np.float64)
    # Training images without a keypoint have no histogram to compare: leave them out (an
    # empty histogram would be the nearest one to every unusual query).
    has_kp = np.diff(np.asarray(vmap.kp_offsets)) > 0
    if not has_kp.any():
        has_kp[:] = True
    has_kp[vmap.wall_images :] = False  # the paper's training images: the wall pictures
    hists = np.where(has_kp[:, None], hists, np.inf)
    last = queries[-1].pose
    xs, ys, sin_sum, cos_sum, closeness, images = [], [], 0.0, 0.0, [], []
    for i in usable:
        hist = vmap.vocabulary.histogram(feats[i].descriptors)
        d2 = np.sum((hists - hist[None, :]) ** 2, axis=1)
        j = int(np.argmin(d2))
        images.append(j)
        xs.append(poses[j, 0])
        ys.append(poses[j, 1])
        view = poses[j, 2] + heads[j, 0]  # camera heading of the training image, map frame
        theta_q = view - queries[i].head_yaw  # robot heading when query i was taken
        theta_last = theta_q + relative_pose(queries[i].pose, last).theta
        sin_sum += math.sin(theta_last)
        cos_sum += math.cos(theta_last)
        closeness.append(max(0.0, 1.0 - math.sqrt(float(d2[j])) / math.sqrt(2.0)))
    conf = len(usable) / len(feats) * float(np.mean(closeness))
    return Estimate(
        float(np.mean(xs)),
        float(np.mean(ys)),
        modulo2PI(math.atan2(sin_sum, cos_sum)),
        float(np.clip(conf, 0.0, 1.0)),
        "nearest",
        {"method": "nearest-image", "images": images},
    )
