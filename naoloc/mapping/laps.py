"""Do the survey's laps agree picture by picture? The figure of build-map's ``laps_agree``.

The wall poses (:mod:`naoloc.mapping.wall_poses`) assume that every lap walked the same
rectangle: each side from its corner to the next, placed by the floor lines. A lap that
turned early at a piece of furniture, or started off its corner, is put where the
rectangle says and not where it was, and nothing in the lines contradicts it (its side
lines see the furniture at the offset). Its pictures do: a picture of lap 2 sees the
same wall as lap 1's pictures taken where the map says it stood. The first lap's
landmarks, triangulated from its own keyframes alone, place each later picture by PnP;
where the map is right that place is the map's pose, to the PnP's few centimetres.

Figure: for each side of each later lap, the median distance between its pictures' map
poses and where lap 1's landmarks put them (m); the check takes the largest.

Frames: map frame (m, rad), as the keyframes' poses.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from naoloc.config import LandmarkTuning, MapCheckTuning
from naoloc.geometry import robot_matrix
from naoloc.mapping.landmarks import (
    camera_poses,
    hamming_matcher,
    query_camera,
    ratio_matches,
    triangulate,
)
from naoloc.perception.features import Features
from naoloc.robot.keyframe import Keyframe, camera_in_robot

__all__ = ["LapAgreement", "lap_agreement"]

NEAREST_VIEWS = 4  # lap-1 pictures a later picture is matched with (nearest first)
RANSAC_ITERATIONS = 200  # the PnP RANSAC that picks the matches that agree
FIT_ITERATIONS = 15  # Gauss-Newton steps of the planar fit
FD_STEP = 1e-5  # its finite-difference step (m, rad)


@dataclass(frozen=True, slots=True)
class LapAgreement:
    """How far lap 1's landmarks put the later laps' pictures from their map poses.

    Attributes:
        frames: Per later picture that PnP placed: (keyframe index, side index, distance m).
        sides: Per later side with at least ``min_frames`` placed pictures: (side index,
            median distance m).
        tried: Later pictures tried (placed or not).
    """

    frames: list[tuple[int, int, float]]
    sides: list[tuple[int, float]]
    tried: int

    @property
    def worst(self) -> tuple[int, float] | None:
        """The side with the largest median distance, or None when no side has one."""
        return max(self.sides, key=lambda s: s[1]) if self.sides else None


def lap_agreement(
    keyframes: Sequence[Keyframe],
    features: Sequence[Features],
    sides_of: Sequence[int],
    binary: bool,
    tuning: MapCheckTuning,
    landmarks: LandmarkTuning,
    sides_per_lap: int = 4,
) -> LapAgreement:
    """Place each later lap's picture by PnP on the first lap's landmarks.

    Args:
        keyframes: The survey's wall pictures with their map poses (the wall poses).
        features: Their features, pinhole pixels of each keyframe's camera
            (:func:`naoloc.mapping.builder.pinhole_features`).
        sides_of: Each keyframe's side index (0, 1, ... in walking order).
        binary: Whether the descriptors are binary.
        tuning: ``map.tuning.checks`` (``lap_view_radius_m``, ``lap_pnp_inliers``,
            ``lap_min_frames``).
        landmarks: ``map.tuning.landmarks`` (the map's own triangulation).
        sides_per_lap: Sides of one lap (4: a rectangle).

    Returns:
        The distances; empty when the survey walked one lap.
    """
    n = len(keyframes)
    lap = [s // sides_per_lap for s in sides_of]
    ref = [i for i in range(n) if lap[i] == 0]
    later = [i for i in range(n) if lap[i] > 0]
    if len(ref) < 2 or not later:
        return LapAgreement([], [], 0)
    cams_info = [query_camera(kf) for kf in keyframes]
    kmats = [c.matrix() for c in cams_info]
    poses = np.array([[kf.pose.x, kf.pose.y, kf.pose.theta] for kf in keyframes])
    heads = np.array([[kf.head_yaw, kf.head_pitch] for kf in keyframes])
    cams = camera_poses(poses, heads, [c.index for c in cams_info])
    lm = triangulate(
        [features[i].xy for i in ref], [features[i].descriptors for i in ref], cams[ref],
        [kmats[i] for i in ref], binary, tuning=landmarks,
    )  # fmt: skip
    offsets = np.concatenate([[0], np.cumsum([len(features[i]) for i in ref])])
    centres, views = cams[:, :3, 3], cams[:, :3, 2]
    ref_arr = np.asarray(ref)
    matcher = hamming_matcher(binary)
    cos_view = math.cos(math.radians(tuning.lap_view_angle_deg))
    frames: list[tuple[int, int, float]] = []
    for j in later:
        dist = np.linalg.norm(centres[ref_arr] - centres[j], axis=1)
        ok = (dist <= tuning.lap_view_radius_m) & (views[ref_arr] @ views[j] >= cos_view)
        near = np.flatnonzero(ok)[np.argsort(dist[ok], kind="stable")][:NEAREST_VIEWS]
        best: dict[int, np.ndarray] = {}
        for r in near.tolist():
            lo, hi = int(offsets[r]), int(offsets[r + 1])
            pts = lm.points[lo:hi]
            known = np.flatnonzero(np.isfinite(pts[:, 0]))
            if known.size < 2:
                continue
            m = ratio_matches(matcher, features[j].descriptors, features[ref[r]].descriptors[known])
            for a, b in m.tolist():
                best.setdefault(a, pts[known[b]])
        if len(best) < tuning.lap_pnp_inliers:
            continue
        idx = np.fromiter(best.keys(), np.int64, len(best))
        obj = np.stack([best[a] for a in idx.tolist()])
        c_r = camera_in_robot(keyframes[j].head_yaw, keyframes[j].head_pitch, cams_info[j].index)
        pixels = features[j].xy[idx].astype(np.float64)
        pose = _place(obj, pixels, kmats[j], c_r, tuning, j, poses[j])
        if pose is None:
            continue
        frames.append((j, int(sides_of[j]), float(math.hypot(*(pose[:2] - poses[j, :2])))))
    by_side: dict[int, list[float]] = {}
    for _, side, d in frames:
        by_side.setdefault(side, []).append(d)
    sides = [
        (side, float(np.median(v)))
        for side, v in sorted(by_side.items())
        if len(v) >= tuning.lap_min_frames
    ]
    return LapAgreement(frames, sides, len(later))


def _place(
    points: np.ndarray,
    pixels: np.ndarray,
    kmat: np.ndarray,
    cam_in_robot: np.ndarray,
    tuning: MapCheckTuning,
    seed: int,
    start: np.ndarray,
) -> np.ndarray | None:
    """The robot pose (x, y, theta) that sees ``points`` at ``pixels``, or None.

    A PnP RANSAC picks the matches that agree with one view; the pose is then fitted in
    the plane (the camera's height, pitch and roll are the head's) from ``start``. The full
    6-DOF pose of one wall's landmarks, all in one plane seen through a narrow view, is
    ambiguous: it trades a shift along the wall and a camera 0.4 m too high for a turn
    (measured: 0.1-0.4 m off at 2 px RMS), which the planar fit cannot.
    """
    import cv2

    if points.shape[0] < tuning.lap_pnp_inliers:
        return None
    try:
        cv2.setRNGSeed(seed)  # OpenCV's RANSAC draws from a process-wide RNG
        ok, _, _, inl = cv2.solvePnPRansac(
            points, pixels, kmat, None, iterationsCount=RANSAC_ITERATIONS,
            reprojectionError=tuning.lap_pnp_px, confidence=0.99, flags=cv2.SOLVEPNP_AP3P,
        )  # fmt: skip
    except cv2.error:
        return None
    if not ok or inl is None or len(inl) < tuning.lap_pnp_inliers:
        return None
    keep = inl.ravel()
    pose = _planar_fit(start, points[keep], pixels[keep], kmat, cam_in_robot, tuning.lap_pnp_px)
    seen = _reprojection(pose, points, kmat, cam_in_robot)
    near = np.linalg.norm(seen - pixels, axis=1) < tuning.lap_pnp_px
    if int(near.sum()) < tuning.lap_pnp_inliers:
        return None
    return _planar_fit(pose, points[near], pixels[near], kmat, cam_in_robot, tuning.lap_pnp_px)


def _reprojection(
    pose: np.ndarray, points: np.ndarray, kmat: np.ndarray, cam_in_robot: np.ndarray
) -> np.ndarray:
    """Pixels of ``points`` (map frame) seen from robot ``pose`` (pinhole ``kmat``)."""
    t_cam_map = np.linalg.inv(robot_matrix(*pose) @ cam_in_robot)
    pc = points @ t_cam_map[:3, :3].T + t_cam_map[:3, 3]
    uv = pc[:, :2] / np.maximum(pc[:, 2:3], 1e-6)
    return uv @ kmat[:2, :2].T + kmat[:2, 2]


def _planar_fit(
    pose: np.ndarray,
    points: np.ndarray,
    pixels: np.ndarray,
    kmat: np.ndarray,
    cam_in_robot: np.ndarray,
    huber_px: float,
) -> np.ndarray:
    """Gauss-Newton on (x, y, theta) with a Huber weight, from ``pose`` (finite-difference
    Jacobian: three parameters, a few dozen points)."""
    x = np.asarray(pose, np.float64).copy()
    for _ in range(FIT_ITERATIONS):
        r = (_reprojection(x, points, kmat, cam_in_robot) - pixels).ravel()
        jac = np.empty((r.size, 3))
        for k in range(3):
            dx = np.zeros(3)
            dx[k] = FD_STEP
            moved = _reprojection(x + dx, points, kmat, cam_in_robot) - pixels
            jac[:, k] = (moved.ravel() - r) / FD_STEP
        a = np.abs(r)
        w = np.where(a <= huber_px, 1.0, huber_px / np.maximum(a, 1e-12))
        step = np.linalg.solve(jac.T @ (jac * w[:, None]) + 1e-9 * np.eye(3), -(jac.T @ (w * r)))
        x += step
        if np.abs(step).max() < 1e-6:
            break
    return x
