"""The visual map: Algorithm 4 (build) and the entry point of Algorithm 5 (localize).

Frames: keyframe poses, neuron poses, landmarks and estimates are in the map frame (the
odometry frame at the start of the survey: x forward, y left, theta counter-clockwise;
landmarks add z up from the floor), metres and radians.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from naoloc.config import MapConfig
from naoloc.errors import DatasetError, NaolocError
from naoloc.keyframe import CameraInfo, Keyframe
from naoloc.mapping.bundle import bundle_adjust, tracks_from_links
from naoloc.mapping.features import FeatureExtractor, Features
from naoloc.mapping.gcs import GCSNetwork, train_gcs
from naoloc.mapping.landmarks import camera_matrix_in_map, triangulate
from naoloc.mapping.localizer import Estimate, localize_paper, localize_verified, query_camera
from naoloc.mapping.posegraph import refine_poses
from naoloc.mapping.vocabulary import Vocabulary, train_vocabulary

ProgressFn = Callable[[str, int, int], None]
MODES = ("verified", "paper")
MIN_LONG_TRACKS = 50  # bundle adjustment without loop edges needs this many lap-tying tracks


@dataclass(eq=False)
class VisualMap:
    """A learned room: vocabulary, GCS network, neuron poses, keyframes and landmarks.

    Attributes:
        config: The map config it was built with.
        meta: JSON-able metadata given at build time (e.g. origin_room_pose).
        feature_params: Parameters of the feature extractor (see FeatureExtractor.params).
        vocabulary: The visual words with their IDF.
        gcs: The trained Growing Cell Structures network.
        neuron_poses: ``(K, 3)`` mean pose (x, y m; theta rad, map frame) of the keyframes
            each neuron wins; NaN rows for neurons that win none.
        neuron_views: ``(K,)`` mean camera heading (rad, map frame) of those keyframes; NaN
            when none.
        keyframe_poses: ``(N, 3)`` odometry poses of the keyframes (map frame).
        refined_poses: ``(N, 3)`` keyframe poses after the visual loop-closure pose graph
            (naoloc.mapping.posegraph) and bundle adjustment (naoloc.mapping.bundle);
            landmarks and the verified mode use these.
        keyframe_heads: ``(N, 2)`` HeadYaw, HeadPitch (rad) of the keyframes.
        keyframe_cameras: ``(N, 5)`` width, height (px), hfov, vfov (rad), camera index.
        histograms: ``(N, V)`` L2-normalised TF-IDF histograms of the keyframes.
        winners: ``(N,)`` winning neuron of each keyframe.
        kp_offsets: ``(N + 1,)`` start of each keyframe's keypoints in the kp_* arrays.
        kp_xy: ``(M, 2)`` float32 keypoint pixels.
        kp_desc: ``(M, d)`` descriptors (uint8 binary or float32 SIFT).
        kp_points: ``(M, 3)`` float64 landmark of each keypoint (map frame), NaN if none.
        timings: Build times in seconds: features_s, vocabulary_s, gcs_s, landmarks_s,
            total_s.
    """

    config: MapConfig
    meta: dict[str, Any]
    feature_params: dict[str, Any]
    vocabulary: Vocabulary
    gcs: GCSNetwork
    neuron_poses: np.ndarray
    neuron_views: np.ndarray
    keyframe_poses: np.ndarray
    refined_poses: np.ndarray
    keyframe_heads: np.ndarray
    keyframe_cameras: np.ndarray
    histograms: np.ndarray
    winners: np.ndarray
    kp_offsets: np.ndarray
    kp_xy: np.ndarray
    kp_desc: np.ndarray
    kp_points: np.ndarray
    timings: dict[str, float] = field(default_factory=dict)
    _extractor: FeatureExtractor | None = field(default=None, repr=False)

    @property
    def images(self) -> int:
        """Number of keyframes the map was built from."""
        return int(self.keyframe_poses.shape[0])

    @property
    def distinct_poses(self) -> int:
        """Number of distinct neuron poses (positions equal to 1 mm count once)."""
        p = self.neuron_poses[np.isfinite(self.neuron_poses[:, 0]), :2]
        return int(np.unique(np.round(p * 1000.0), axis=0).shape[0]) if p.size else 0

    @property
    def landmarks(self) -> int:
        """Number of keypoints with a triangulated landmark."""
        return int(np.isfinite(self.kp_points[:, 0]).sum())

    def keyframe_camera(self, i: int) -> CameraInfo:
        """The camera model of keyframe ``i``."""
        w, h, hf, vf, idx = self.keyframe_cameras[i]
        return CameraInfo(int(w), int(h), float(hf), float(vf), int(idx))

    def extractor(self) -> FeatureExtractor:
        """The feature extractor the map was built with (created once)."""
        if self._extractor is None:
            p = self.feature_params
            self._extractor = FeatureExtractor(
                p["kind"], int(p.get("max_features", 0)), float(p.get("akaze_threshold", 0.001))
            )
        return self._extractor

    def extract(self, queries: Sequence[Keyframe]) -> list[Features]:
        """Features of query images with the map's extractor."""
        ex = self.extractor()
        return [ex.extract(q.gray()) for q in queries]

    def localize(self, queries: Sequence[Keyframe], mode: str = "verified") -> Estimate:
        """Estimate the robot pose when the last query was taken (Algorithm 5 and beyond).

        Args:
            queries: One or more images; their ``pose`` is odometry in any fixed frame (only
                relative poses between queries are used); head angles at capture.
            mode: ``verified`` (default) or ``paper``.

        Returns:
            The estimate in the map frame; confidence 0 when no query has features.

        Raises:
            NaolocError: On an unknown mode or no queries.
        """
        return self.localize_features(self.extract(queries), queries, mode)

    def localize_features(
        self, feats: Sequence[Features], queries: Sequence[Keyframe], mode: str = "verified"
    ) -> Estimate:
        """Like :meth:`localize` with the query features already extracted."""
        if mode not in MODES:
            raise NaolocError(f"unknown localize mode {mode!r}; valid: {', '.join(MODES)}")
        if not queries or len(feats) != len(queries):
            raise NaolocError("localize needs at least one query image and one feature set each")
        if mode == "paper":
            return localize_paper(self, feats, queries)
        return localize_verified(self, feats, queries)

    def save(self, path: str | Path) -> None:
        """Write the map to one ``.npz`` file (see naoloc.mapping.mapfile)."""
        from naoloc.mapping.mapfile import save_map

        save_map(self, path)


def _neuron_poses(
    winners: np.ndarray, poses: np.ndarray, views: np.ndarray, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """Algorithm 4, line 7: each neuron's pose is the mean pose of the images it wins."""
    out = np.full((k, 3), np.nan)
    view = np.full(k, np.nan)
    for n in np.unique(winners).tolist():
        sel = winners == n
        out[n, :2] = poses[sel, :2].mean(axis=0)
        out[n, 2] = math.atan2(np.sin(poses[sel, 2]).sum(), np.cos(poses[sel, 2]).sum())
        view[n] = math.atan2(np.sin(views[sel]).sum(), np.cos(views[sel]).sum())
    return out, view


def _cameras(poses: np.ndarray, heads: np.ndarray, cam_index: Sequence[int]) -> np.ndarray:
    """``(N, 4, 4)`` ``T_map_cam`` of keyframes with robot poses ``poses`` (map frame)."""
    return np.stack(
        [
            camera_matrix_in_map(poses[i], heads[i, 0], heads[i, 1], cam_index[i])
            for i in range(poses.shape[0])
        ]
    )


def build_map(
    keyframes: Sequence[Keyframe],
    cfg: MapConfig,
    *,
    meta: dict[str, Any] | None = None,
    progress: ProgressFn | None = None,
) -> VisualMap:
    """Algorithm 4: features -> vocabulary -> histograms -> GCS -> neuron poses; landmarks.

    Args:
        keyframes: Survey images; ``pose`` is the odometry pose in the map frame, head angles
            and camera give the view.
        cfg: Feature kind, GCS size, epochs, seed, vocabulary size.
        meta: JSON-able metadata stored in the map file.
        progress: Called as ``progress(stage, done, total)``.

    Returns:
        The map.

    Raises:
        DatasetError: When there are no keyframes.
    """
    if not keyframes:
        raise DatasetError("no keyframes to build a map from")
    report = progress or (lambda _s, _d, _t: None)
    n = len(keyframes)
    t0 = time.perf_counter()
    extractor = FeatureExtractor(cfg.features, akaze_threshold=cfg.akaze_threshold)
    feats: list[Features] = []
    for i, kf in enumerate(keyframes):
        feats.append(extractor.extract(kf.gray()))
        report("features", i + 1, n)
    t1 = time.perf_counter()
    vocab = train_vocabulary(
        [f.descriptors for f in feats], cfg.vocabulary_size, extractor.binary, cfg.seed
    )
    hists = np.stack([vocab.histogram(f.descriptors) for f in feats])
    report("vocabulary", 1, 1)
    t2 = time.perf_counter()
    gcs = train_gcs(hists, cfg.neurons, cfg.epochs, cfg.seed)
    report("gcs", 1, 1)
    t3 = time.perf_counter()
    poses = np.array([[kf.pose.x, kf.pose.y, kf.pose.theta] for kf in keyframes], np.float64)
    heads = np.array([[kf.head_yaw, kf.head_pitch] for kf in keyframes], np.float64)
    cams_info = [query_camera(kf) for kf in keyframes]
    cameras = np.array(
        [[c.width, c.height, c.hfov, c.vfov, c.index] for c in cams_info], np.float64
    )
    winners = gcs.winners(hists)
    neuron_poses, neuron_views = _neuron_poses(winners, poses, poses[:, 2] + heads[:, 0], gcs.size)
    xys, descs = [f.xy for f in feats], [f.descriptors for f in feats]
    kmats = [c.matrix() for c in cams_info]
    cam_index = [c.index for c in cams_info]
    refined = refine_poses(poses, heads, xys, descs, kmats, cam_index, hists, extractor.binary)
    report("poses", 1, 1)
    # Landmarks from the pose-graph poses link keypoints into tracks; bundle adjustment
    # refines the poses with them; the landmarks are then triangulated from those poses.
    lm = triangulate(xys, descs, _cameras(refined.poses, heads, cam_index), kmats, extractor.binary)
    kp_xy = np.concatenate(xys)
    kp_frame = np.repeat(np.arange(n), [len(f) for f in feats])
    tracks = tracks_from_links(kp_xy.shape[0], lm.matches)
    odometry = [e for e in refined.edges if e.odometry]
    args = (refined.poses, heads, cam_index, kmats, kp_xy, kp_frame, tracks, lm.points)
    # Odometry edges only: the loop closures' relative poses carry the errors of their
    # odometry-triangulated landmarks (measured: they make the result worse), and tracks
    # seen from both laps (spanning half the loop-closure gap) tie the laps. Without
    # enough such tracks the loops are kept.
    loop_gaps = [abs(e.b - e.a) for e in refined.edges if not e.odometry]
    gap = int(np.median(loop_gaps)) // 2 if loop_gaps else n
    adjusted = bundle_adjust(*args, odometry, refined.heading_bias, long_gap=gap)
    if adjusted.long_tracks < MIN_LONG_TRACKS and loop_gaps:
        adjusted = bundle_adjust(*args, list(refined.edges), refined.heading_bias, long_gap=gap)
    final_poses = adjusted.poses
    lm = triangulate(xys, descs, _cameras(final_poses, heads, cam_index), kmats, extractor.binary)
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
    return VisualMap(
        config=cfg,
        meta={
            **dict(meta or {}),
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
        _extractor=extractor,
    )
