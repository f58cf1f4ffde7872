"""The map's data: a plain data class, with no building, localizing or file code.

Frames: keyframe poses, neuron poses and landmarks are in the map frame (the odometry frame
at the start of the survey: x forward, y left, theta counter-clockwise; landmarks add z up
from the floor), metres and radians.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from naoloc.config import MapConfig
from naoloc.mapping.gcs import GCSNetwork
from naoloc.mapping.vocabulary import Vocabulary
from naoloc.robot.keyframe import CameraInfo


@dataclass(eq=False)
class MapData:
    """A learned room: vocabulary, GCS network, neuron poses, keyframes and landmarks.

    Plain data: building (naoloc.mapping.builder), localizing (naoloc.localization)
    and the file format (naoloc.mapping.mapfile) are functions of it elsewhere;
    :class:`naoloc.mapping.VisualMap` adds them as methods.

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

    @property
    def images(self) -> int:
        """Number of keyframes the map was built from."""
        return int(self.keyframe_poses.shape[0])

    @property
    def far_images(self) -> int:
        """Number of the survey's far pictures (meta ``far_pictures``): the last keyframes."""
        far = self.meta.get("far_pictures", 0)
        return far if isinstance(far, int) and 0 <= far < self.images else 0

    @property
    def wall_images(self) -> int:
        """Number of wall pictures: the first keyframes, the paper's training images."""
        return self.images - self.far_images

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
