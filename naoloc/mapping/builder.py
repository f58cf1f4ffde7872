"""Algorithm 4: build the map from survey keyframes, then refine it geometrically.

features -> vocabulary -> TF-IDF histograms -> GCS -> neuron poses (the paper); then the
visual loop-closure pose graph (naoloc.mapping.posegraph), landmarks
(naoloc.mapping.landmarks) and bundle adjustment (naoloc.mapping.bundle), all tuned by
``MapConfig.tuning``.

Frames: keyframe poses, neuron poses and landmarks are in the map frame (the odometry frame
at the start of the survey: x forward, y left, theta counter-clockwise; landmarks add z up),
metres and radians.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from naoloc.config import MapConfig
from naoloc.errors import DatasetError
from naoloc.geometry import Pose2D, circular_mean, relative_pose
from naoloc.mapping.bundle import BundleProblem, bundle_adjust, tracks_from_links
from naoloc.mapping.data import MapData
from naoloc.mapping.gcs import train_gcs
from naoloc.mapping.landmarks import camera_poses, query_camera, triangulate
from naoloc.mapping.posegraph import refine_poses
from naoloc.mapping.vocabulary import train_vocabulary
from naoloc.perception.features import FeatureExtractor, Features, to_pinhole
from naoloc.robot.keyframe import CameraInfo, Keyframe
from naoloc.robot.lens import Lens

ProgressFn = Callable[[str, int, int], None]


def _neuron_poses(
    winners: np.ndarray, poses: np.ndarray, views: np.ndarray, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """Algorithm 4, line 7: each neuron's pose is the mean pose of the images it wins."""
    out = np.full((k, 3), np.nan)
    view = np.full(k, np.nan)
    for n in np.unique(winners).tolist():
        sel = winners == n
        out[n, :2] = poses[sel, :2].mean(axis=0)
        out[n, 2] = circular_mean(poses[sel, 2])
        view[n] = circular_mean(views[sel])
    return out, view


def carried(stop_now: Pose2D, stop_then: Pose2D, far_then: Pose2D) -> Pose2D:
    """A far picture's pose once its stop's wall picture moved from ``stop_then`` to
    ``stop_now``: the same odometry step from the wall picture to it (map frame)."""
    return (stop_now * relative_pose(stop_then, far_then)).normalized()


def ride_with_stops(walls: np.ndarray, given: np.ndarray, stops: Sequence[int]) -> np.ndarray:
    """Every keyframe's pose once the wall pictures' poses are refined: the far pictures
    (rows after the walls) move with the wall picture of their stop.

    Args:
        walls: ``(W, 3)`` refined poses of the wall pictures (map frame: m, m, rad).
        given: ``(W + F, 3)`` poses every keyframe came with, walls first.
        stops: Per far picture, the index of its stop's wall picture.

    Returns:
        ``(W + F, 3)``: the refined walls, then each far picture at its stop's refined pose
        composed with the given odometry from that wall picture to it.
    """
    rows = [walls]
    for j, s in enumerate(stops):
        pose = carried(Pose2D(*walls[s]), Pose2D(*given[s]), Pose2D(*given[walls.shape[0] + j]))
        rows.append(np.array([pose.to_list()]))
    return np.concatenate(rows, axis=0)


def map_extractor(cfg: MapConfig) -> FeatureExtractor:
    """The feature extractor ``cfg`` builds maps with."""
    return FeatureExtractor(
        cfg.features, akaze_threshold=cfg.akaze_threshold, min_keypoints=cfg.min_keypoints
    )


def pinhole_features(
    extractor: FeatureExtractor, kf: Keyframe, cam: CameraInfo, lens: Lens | None
) -> Features:
    """The features of one picture, moved to the pinhole ``cam`` the map models.

    Args:
        extractor: The map's feature extractor.
        kf: The picture (survey keyframe or query).
        cam: Its camera (:func:`naoloc.mapping.landmarks.query_camera`).
        lens: The camera's lens (None: the picture is a pinhole's already).
    """
    found = extractor.extract(kf.gray())
    return to_pinhole(found, lens, cam.width, cam.height, cam.hfov, cam.vfov)


def build_map_data(
    keyframes: Sequence[Keyframe],
    cfg: MapConfig,
    *,
    meta: dict[str, Any] | None = None,
    progress: ProgressFn | None = None,
    extractor: FeatureExtractor | None = None,
    far: Sequence[tuple[int, Keyframe]] = (),
    wall_features: Sequence[Features] | None = None,
) -> MapData:
    """Algorithm 4: features -> vocabulary -> histograms -> GCS -> neuron poses; landmarks.

    The far pictures (``survey.far_yaws_rad``) join the map's keyframes after the wall
    pictures, for the verified localizer: their features, histograms and landmarks. The
    paper's part is the wall pictures' alone (vocabulary, GCS and neuron poses are the
    same with or without far pictures), and so are the pose graph and bundle adjustment: a
    far picture rides with the wall picture of its stop (the same place, another head
    yaw), carried by the odometry between the two. The map's meta counts them
    (``far_pictures``).

    Args:
        keyframes: Survey images; ``pose`` is the odometry pose in the map frame, head angles
            and camera give the view.
        cfg: Feature kind, GCS size, epochs, seed, vocabulary size.
        meta: JSON-able metadata stored in the map file.
        progress: Called as ``progress(stage, done, total)``.
        extractor: The feature extractor to use (default: one for ``cfg.features``).
        far: Far pictures, each with its stop (an index into ``keyframes``); poses in the
            frame of the keyframes' poses.
        wall_features: The features of ``keyframes`` already extracted with ``extractor``
            (build-map's checks extract them first); None extracts them here.

    Returns:
        The map.

    Raises:
        DatasetError: When there are no keyframes, or a far picture's stop is not one.
    """
    if not keyframes:
        raise DatasetError("no keyframes to build a map from")
    stops = [int(s) for s, _ in far]
    if any(not 0 <= s < len(keyframes) for s in stops):
        raise DatasetError(f"a far picture's stop is not one of the {len(keyframes)} keyframes")
    report = progress or (lambda _s, _d, _t: None)
    walls = len(keyframes)
    keyframes = [*keyframes, *(kf for _, kf in far)]
    n = len(keyframes)
    t0 = time.perf_counter()
    extractor = extractor or map_extractor(cfg)
    tune = cfg.tuning
    lens = Lens.from_dict((meta or {}).get("lens"))  # the survey camera's, when recorded
    cams_info = [query_camera(kf) for kf in keyframes]
    feats: list[Features] = list(wall_features or [])
    if len(feats) not in (0, walls):
        raise DatasetError(f"{len(feats)} wall pictures' features for {walls} wall pictures")
    for i in range(len(feats), n):
        feats.append(pinhole_features(extractor, keyframes[i], cams_info[i], lens))
        report("features", i + 1, n)
    t1 = time.perf_counter()
    vocab = train_vocabulary(
        [f.descriptors for f in feats[:walls]], cfg.vocabulary_size, extractor.binary, cfg.seed
    )
    hists = vocab.histograms([f.descriptors for f in feats])
    report("vocabulary", 1, 1)
    t2 = time.perf_counter()
    gcs = train_gcs(hists[:walls], cfg.neurons, cfg.epochs, cfg.seed)
    report("gcs", 1, 1)
    t3 = time.perf_counter()
    poses = np.array([[kf.pose.x, kf.pose.y, kf.pose.theta] for kf in keyframes], np.float64)
    heads = np.array([[kf.head_yaw, kf.head_pitch] for kf in keyframes], np.float64)
    cameras = np.array(
        [[c.width, c.height, c.hfov, c.vfov, c.index] for c in cams_info], np.float64
    )
    winners = gcs.winners(hists)
    w = slice(0, walls)  # the wall pictures: the paper's images, the pose graph's nodes
    neuron_poses, neuron_views = _neuron_poses(
        winners[w], poses[w], poses[w, 2] + heads[w, 0], gcs.size
    )
    xys, descs = [f.xy for f in feats], [f.descriptors for f in feats]
    kmats = [c.matrix() for c in cams_info]
    cam_index = [c.index for c in cams_info]
    refined = refine_poses(
        poses[w], heads[w], xys[w], descs[w], kmats[w], cam_index[w], hists[w],
        extractor.binary, tune.pose_graph,
    )  # fmt: skip
    report("poses", 1, 1)
    # Landmarks from the pose-graph poses link keypoints into tracks; bundle adjustment
    # refines the poses with them; the landmarks are then triangulated from those poses.
    binary = extractor.binary
    cams = camera_poses(refined.poses, heads[w], cam_index[w])
    lm = triangulate(xys[w], descs[w], cams, kmats[w], binary, tuning=tune.landmarks)
    kp_xy = np.concatenate(xys[w])
    kp_frame = np.repeat(np.arange(walls), [len(f) for f in feats[w]])
    tracks = tracks_from_links(kp_xy.shape[0], lm.matches)
    odometry = [e for e in refined.edges if e.odometry]
    # Wall-referenced poses (map.wall_poses) are each good to a few centimetres and
    # milliradians on their own: they hold the adjustment, which without them bent whole
    # sides (six surveys, tools/map_pose_accuracy.py: heading median 0.004-0.037 rad
    # without the prior, 0.002-0.011 rad with it).
    problem = BundleProblem(
        refined.poses, heads[w], cam_index[w], kmats[w], kp_xy, kp_frame, tracks, lm.points,
        odometry, tune.pose_graph,
    )  # fmt: skip
    sigma = tune.bundle.wall_prior_sigma
    if (meta or {}).get("wall_poses") is not None and sigma is not None:
        problem = dataclasses.replace(problem, priors=poses[w].copy(), prior_sigma=sigma)
    # Odometry edges only: the loop closures' relative poses carry the errors of their
    # odometry-triangulated landmarks (measured: they make the result worse), and tracks
    # seen from both laps (spanning half the loop-closure gap) tie the laps. Without
    # enough such tracks the loops are kept.
    loop_gaps = [abs(e.b - e.a) for e in refined.edges if not e.odometry]
    gap = int(np.median(loop_gaps)) // 2 if loop_gaps else n
    bias = refined.heading_bias
    adjusted = bundle_adjust(problem, tune.bundle, heading_bias=bias, long_gap=gap)
    if adjusted.long_tracks < tune.bundle.min_long_tracks and loop_gaps:
        problem = dataclasses.replace(problem, edges=list(refined.edges))
        adjusted = bundle_adjust(problem, tune.bundle, heading_bias=bias, long_gap=gap)
    final_poses = ride_with_stops(adjusted.poses, poses, stops)
    cams = camera_poses(final_poses, heads, cam_index)
    lm = triangulate(xys, descs, cams, kmats, binary, tuning=tune.landmarks, far_from=walls)
    report("landmarks", 1, 1)
    t4 = time.perf_counter()
    offsets = np.concatenate([[0], np.cumsum([len(f) for f in feats])]).astype(np.int64)
    timings = {
        "features_s": t1 - t0,
        "vocabulary_s": t2 - t1,
        "gcs_s": t3 - t2,
        "landmarks_s": t4 - t3,
        "total_s": t4 - t0,
    }
    return MapData(
        config=cfg,
        meta={
            **dict(meta or {}),
            "far_pictures": n - walls,
            "loop_closures": refined.loops,
            "heading_bias_rad_per_m": round(adjusted.heading_bias, 6),
            "bundle_tracks": adjusted.tracks,
            "bundle_long_tracks": adjusted.long_tracks,
            "bundle_rms_px": round(adjusted.rms_px, 3),
        },
        feature_params=extractor.params(),
        vocabulary=vocab,
        gcs=gcs,
        neuron_poses=neuron_poses,
        neuron_views=neuron_views,
        keyframe_poses=poses,
        refined_poses=final_poses,
        keyframe_heads=heads,
        keyframe_cameras=cameras,
        histograms=hists,
        winners=winners,
        kp_offsets=offsets,
        kp_xy=np.concatenate([f.xy for f in feats]).astype(np.float32),
        kp_desc=np.concatenate([f.descriptors for f in feats]),
        kp_points=lm.points,
        timings=timings,
    )
