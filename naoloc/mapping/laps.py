"""Do the survey's laps agree picture by picture? The figure of build-map's ``laps_agree``.

The wall poses (:mod:`naoloc.mapping.wall_poses`) assume that every lap walked the same
rectangle: each side from its corner to the next, placed by the floor lines. A lap that
turned early at a piece of furniture, or started off its corner, is put where the
rectangle says and not where it was, and nothing in the lines contradicts it (its side
lines see the furniture at the offset). Its pictures do: a picture of lap 2 sees the
same wall as lap 1's pictures taken where the map says it stood. The first lap's
landmarks, triangulated from its own keyframes alone, place each later picture by PnP;
where the map is right that place is the map's pose, to the PnP's few centimetres.

Figure: for each side of each later lap, how far lap 1's landmarks put its pictures from
their map poses: the mean of the offsets (vectors), each weighted by its precision (the
planar fit's covariance at ``lap_pixel_sigma_px``, plus the landmarks' own error
``lap_floor_m``), and its length (m); the check takes the largest. A side's pictures share
its error, while a picture placed poorly (few matches, a corner's two walls) is weighed
little: a median of distances read 0.11 m on a short side whose pictures are 0.03 m off.

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

__all__ = ["LapAgreement", "PlacedPicture", "SideAgreement", "lap_agreement", "side_agreement"]

NEAREST_VIEWS = 4  # lap-1 pictures a later picture is matched with (nearest first)
RANSAC_ITERATIONS = 200  # the PnP RANSAC that picks the matches that agree
FIT_ITERATIONS = 15  # Gauss-Newton steps of the planar fit
FD_STEP = 1e-5  # its finite-difference step (m, rad)
MIN_SIGMA_PICTURES = 10  # placed pictures the keyframes' error is estimated from


@dataclass(frozen=True, slots=True)
class PlacedPicture:
    """A later lap's picture, placed on the first lap's landmarks.

    Attributes:
        index: Its keyframe index.
        side: Its side index (0, 1, ... in walking order).
        offset: Where the landmarks put it less its map pose (dx, dy, m, map frame).
        sigma_m: The placement's position error (std per axis, m) from the fit.
    """

    index: int
    side: int
    offset: tuple[float, float]
    sigma_m: float

    @property
    def distance(self) -> float:
        """How far from its map pose, m."""
        return math.hypot(*self.offset)


@dataclass(frozen=True, slots=True)
class SideAgreement:
    """One later side: how far its pictures stand from where the map has them.

    Attributes:
        side: The side index.
        pictures: Its placed pictures.
        offset_m: Length of the precision-weighted mean offset, m.
        sigma_m: That mean's error (std per axis), m.
    """

    side: int
    pictures: int
    offset_m: float
    sigma_m: float


@dataclass(frozen=True, slots=True)
class LapAgreement:
    """How far lap 1's landmarks put the later laps' pictures from their map poses.

    Attributes:
        frames: The later pictures the landmarks placed.
        sides: Per later side with at least ``lap_min_frames`` placed pictures.
        tried: Later pictures tried (placed or not).
    """

    frames: list[PlacedPicture]
    sides: list[SideAgreement]
    tried: int

    @property
    def keyframe_sigma_m(self) -> float | None:
        """The keyframes' own position error (std per axis, m), from how the laps disagree.

        A placed picture's offset is its keyframe's error less the first lap's there, plus
        its placement's error: per axis ``2 s_k^2 + s_p^2``, so over the pictures
        ``s_k^2 = (mean |offset|^2 - 2 mean s_p^2) / 4``. None with fewer than
        :data:`MIN_SIGMA_PICTURES` placed pictures. It misses what every lap shares (a map
        frame turned as a whole).
        """
        if len(self.frames) < MIN_SIGMA_PICTURES:
            return None
        sq = float(np.mean([f.offset[0] ** 2 + f.offset[1] ** 2 for f in self.frames]))
        placement = float(np.mean([f.sigma_m**2 for f in self.frames]))
        return math.sqrt(max(0.0, sq - 2.0 * placement) / 4.0)

    @property
    def worst(self) -> SideAgreement | None:
        """The side that stands farthest from its map poses, or None when no side has
        enough placed pictures."""
        return max(self.sides, key=lambda s: s.offset_m) if self.sides else None


def side_agreement(
    frames: Sequence[PlacedPicture], floor_m: float, min_frames: int
) -> list[SideAgreement]:
    """Each side's precision-weighted mean offset (sides with ``min_frames`` pictures).

    Args:
        frames: Placed pictures.
        floor_m: Error every placement carries besides its fit's (the first lap's
            landmarks' own), std, m.
        min_frames: Fewest placed pictures a side needs.
    """
    by_side: dict[int, list[PlacedPicture]] = {}
    for f in frames:
        by_side.setdefault(f.side, []).append(f)
    out = []
    for side, pics in sorted(by_side.items()):
        if len(pics) < min_frames:
            continue
        w = np.array([1.0 / (p.sigma_m**2 + floor_m**2) for p in pics])
        mean = (w[:, None] * np.array([p.offset for p in pics])).sum(axis=0) / w.sum()
        out.append(SideAgreement(side, len(pics), float(np.hypot(*mean)),
                                 float(math.sqrt(1.0 / w.sum()))))  # fmt: skip
    return out


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
        tuning: ``map.tuning.checks`` (the ``lap_*`` fields).
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
    frames: list[PlacedPicture] = []
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
        placed = _place(obj, pixels, kmats[j], c_r, tuning, j, poses[j])
        if placed is None:
            continue
        pose, sigma = placed
        dx, dy = (float(v) for v in pose[:2] - poses[j, :2])
        frames.append(PlacedPicture(j, int(sides_of[j]), (dx, dy), sigma))
    sides = side_agreement(frames, tuning.lap_floor_m, tuning.lap_min_frames)
    return LapAgreement(frames, sides, len(later))


def _place(
    points: np.ndarray,
    pixels: np.ndarray,
    kmat: np.ndarray,
    cam_in_robot: np.ndarray,
    tuning: MapCheckTuning,
    seed: int,
    start: np.ndarray,
) -> tuple[np.ndarray, float] | None:
    """The robot pose (x, y, theta) that sees ``points`` at ``pixels`` and its position
    error (std per axis, m: the fit's covariance at ``tuning.lap_pixel_sigma_px``), or None.

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
    pts, px = points[near], pixels[near]
    pose = _planar_fit(pose, pts, px, kmat, cam_in_robot, tuning.lap_pnp_px)
    jac = _jacobian(pose, pts, kmat, cam_in_robot)
    cov = np.linalg.inv(jac.T @ jac + 1e-12 * np.eye(3)) * tuning.lap_pixel_sigma_px**2
    return pose, float(math.sqrt(max(0.0, (cov[0, 0] + cov[1, 1]) / 2)))


def _reprojection(
    pose: np.ndarray, points: np.ndarray, kmat: np.ndarray, cam_in_robot: np.ndarray
) -> np.ndarray:
    """Pixels of ``points`` (map frame) seen from robot ``pose`` (pinhole ``kmat``)."""
    t_cam_map = np.linalg.inv(robot_matrix(*pose) @ cam_in_robot)
    pc = points @ t_cam_map[:3, :3].T + t_cam_map[:3, 3]
    uv = pc[:, :2] / np.maximum(pc[:, 2:3], 1e-6)
    return uv @ kmat[:2, :2].T + kmat[:2, 2]


def _jacobian(
    pose: np.ndarray, points: np.ndarray, kmat: np.ndarray, cam_in_robot: np.ndarray
) -> np.ndarray:
    """``d pixels / d (x, y, theta)`` at ``pose``, ``(2n, 3)`` (finite differences: three
    parameters, a few dozen points)."""
    base = _reprojection(pose, points, kmat, cam_in_robot).ravel()
    jac = np.empty((base.size, 3))
    for k in range(3):
        dx = np.zeros(3)
        dx[k] = FD_STEP
        jac[:, k] = (_reprojection(pose + dx, points, kmat, cam_in_robot).ravel() - base) / FD_STEP
    return jac


def _planar_fit(
    pose: np.ndarray,
    points: np.ndarray,
    pixels: np.ndarray,
    kmat: np.ndarray,
    cam_in_robot: np.ndarray,
    huber_px: float,
) -> np.ndarray:
    """Gauss-Newton on (x, y, theta) with a Huber weight, from ``pose``."""
    x = np.asarray(pose, np.float64).copy()
    for _ in range(FIT_ITERATIONS):
        r = (_reprojection(x, points, kmat, cam_in_robot) - pixels).ravel()
        jac = _jacobian(x, points, kmat, cam_in_robot)
        a = np.abs(r)
        w = np.where(a <= huber_px, 1.0, huber_px / np.maximum(a, 1e-12))
        step = np.linalg.solve(jac.T @ (jac * w[:, None]) + 1e-9 * np.eye(3), -(jac.T @ (w * r)))
        x += step
        if np.abs(step).max() < 1e-6:
            break
    return x
