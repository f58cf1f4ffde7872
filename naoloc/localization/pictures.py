"""The picture sensor model: landmark matches and their reprojection, and place retrieval.

A picture's features are matched to the map's landmarks once, whatever the pose: the
keyframes retrieval ranks first (bag of words, TF-IDF, and the GCS winner: the paper's
place recognition) give candidate landmarks, and Lowe's ratio test keeps a feature's
nearest one. The pose then only decides which matches are right: each match's
reprojection error from a pose is Gaussian (``pixel_sigma_px``) when the match is right
and uniform over the image when it is wrong (``match_outlier_share``), and a picture's
matches share the map's errors, so each carries ``match_weight`` of a match's evidence.

Retrieval and PnP also *propose* poses: a picture whose matches a PnP RANSAC fits with
``min_pnp_inliers`` proposes the robot pose at capture for a new hypothesis (global
localization, recovery after the robot was carried).

Frames: landmarks and poses in the map frame (m, rad); pixels of the map's pinhole model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from naoloc.config import FilterTuning
from naoloc.geometry import planar_pose
from naoloc.mapping.data import MapData
from naoloc.mapping.landmarks import DescriptorMatcher, hamming_matcher, query_camera, ratio_matches
from naoloc.mapping.vocabulary import dbow_scores, pad_packed
from naoloc.perception.features import Features
from naoloc.robot.keyframe import Keyframe

__all__ = [
    "LandmarkIndex",
    "PictureMatches",
    "distinct_only",
    "landmarks_in_view",
    "match_picture",
    "mixture",
    "picture_log_ratio",
    "reprojection",
]


@dataclass(frozen=True, eq=False)
class PictureMatches:
    """A picture's landmark matches, independent of the pose.

    Attributes:
        points: ``(n, 3)`` candidate landmarks of the picture's features (each feature's
            nearest landmark descriptors over the whole map), map frame, m.
        pixels: ``(n, 2)`` the features' pixels (the map's pinhole model), one per candidate.
        group: ``(n,)`` the feature each candidate belongs to (0 .. ``features - 1``).
        per_feature: Candidates per feature (the prior of each is ``1 / per_feature``).
        matched: ``(m, 3)`` landmarks of the retrieval's ratio-tested matches (one per
            feature; the PnP's and the pooled proposals' input).
        matched_pixels: ``(m, 2)`` their pixels.
        projection: ``(3, 4)`` a point in FRAME_ROBOT at capture to homogeneous pixels.
        area_px: The image's area, px^2 (the density of a wrong match's pixel).
        features: How many features the picture had.
        retrieved: The keyframes retrieval ranked first.
        proposal: The robot pose at capture a PnP RANSAC fits (map frame), or None.
        proposal_inliers: That fit's inliers (0 without one).
        distinct: ``(d, 3)`` the nearest landmark of each feature that passes Lowe's ratio
            test over the whole map (:meth:`LandmarkIndex.candidates`).
        distinct_pixels: ``(d, 2)`` those features' pixels.
        size_px: The image's width and height, px (the map's pinhole model).
    """

    points: np.ndarray
    pixels: np.ndarray
    group: np.ndarray
    per_feature: int
    matched: np.ndarray
    matched_pixels: np.ndarray
    projection: np.ndarray
    area_px: float
    features: int
    retrieved: tuple[int, ...]
    proposal: np.ndarray | None
    proposal_inliers: int
    distinct: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    distinct_pixels: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    size_px: tuple[int, int] = (0, 0)

    def __len__(self) -> int:
        """Features with landmark candidates."""
        return int(np.unique(self.group).size) if self.group.size else 0


def retrieve(vmap: MapData, descriptors: np.ndarray, top_k: int) -> list[int]:
    """Keyframes whose bag of words scores highest (DBoW2's L1 score), and the GCS winner's."""
    hist = vmap.vocabulary.histogram(descriptors)
    scores = dbow_scores(hist, vmap.histograms)
    order = np.argsort(-scores, kind="stable")[:top_k].tolist()
    winner = int(vmap.gcs.winners(hist)[0])
    extra = np.flatnonzero(vmap.winners == winner)[:2].tolist()
    return list(dict.fromkeys(order + extra))


def _landmark_matches(
    vmap: MapData, matcher: DescriptorMatcher, feats: Features, cands: list[int]
) -> tuple[np.ndarray, np.ndarray]:
    """Ratio-tested matches to the candidates' landmarks: feature indices, landmarks."""
    best: dict[int, np.ndarray] = {}
    for c in cands:
        lo, hi = int(vmap.kp_offsets[c]), int(vmap.kp_offsets[c + 1])
        m = ratio_matches(matcher, feats.descriptors, vmap.kp_desc[lo:hi])
        if m.shape[0] == 0:
            continue
        pts = vmap.kp_points[lo + m[:, 1]]
        for (a, _b), p in zip(m.tolist(), pts, strict=True):
            if np.isfinite(p[0]) and a not in best:
                best[a] = p
    idx = np.fromiter(best.keys(), np.int64, len(best))
    obj = np.stack([best[a] for a in idx.tolist()]) if best else np.zeros((0, 3))
    return idx, obj


def _pnp_pose(
    points: np.ndarray,
    pixels: np.ndarray,
    kmat: np.ndarray,
    camera_in_robot: np.ndarray,
    tun: FilterTuning,
    seed: int,
) -> tuple[np.ndarray | None, int]:
    """The robot pose at capture from a PnP RANSAC (None: none plausible) and its inliers."""
    import cv2

    try:
        cv2.setRNGSeed(seed)  # OpenCV's RANSAC draws from a process-wide RNG
        ok, rvec, tvec, inl = cv2.solvePnPRansac(
            points, pixels, kmat, None, iterationsCount=tun.pnp_iterations,
            reprojectionError=tun.pnp_reprojection_px, confidence=0.99, flags=cv2.SOLVEPNP_AP3P,
        )  # fmt: skip
    except cv2.error:
        return None, 0
    if not ok or inl is None or len(inl) < tun.min_pnp_inliers:
        return None, 0
    rot, _ = cv2.Rodrigues(rvec)
    t_cam_map = np.eye(4)
    t_cam_map[:3, :3], t_cam_map[:3, 3] = rot, tvec.ravel()
    t_map_cam = np.linalg.inv(t_cam_map)
    if abs(t_map_cam[2, 3] - camera_in_robot[2, 3]) > tun.camera_height_tolerance_m:
        return None, 0  # a camera under the floor or at the ceiling: a wrong fit
    pose = np.array(planar_pose(t_map_cam @ np.linalg.inv(camera_in_robot)))
    return pose, len(inl)


def match_picture(
    vmap: MapData,
    landmarks: LandmarkIndex,
    feats: Features,
    keyframe: Keyframe,
    tun: FilterTuning,
    seed: int = 0,
) -> PictureMatches:
    """A picture's landmark candidates and the pose its PnP proposes.

    Args:
        vmap: The map.
        landmarks: The map's landmarks for nearest-descriptor search.
        feats: The picture's features (the map's extractor, the map's pinhole).
        keyframe: The picture (camera pose in FRAME_ROBOT and size).
        tun: The filter's tuning.
        seed: Seeds PnP's RANSAC, so the same picture gives the same proposal.
    """
    cam = query_camera(keyframe)
    kmat = cam.matrix()
    c_q = keyframe.camera_matrix()
    projection = kmat @ np.linalg.inv(c_q)[:3, :]
    area = float(cam.width * cam.height)
    none3, none2, none1 = np.zeros((0, 3)), np.zeros((0, 2)), np.zeros(0, np.int64)
    if len(feats) == 0:
        return PictureMatches(
            none3, none2, none1, 1, none3, none2, projection, area, 0, (), None, 0,
            size_px=(cam.width, cam.height),
        )  # fmt: skip
    cands = retrieve(vmap, feats.descriptors, tun.candidates)
    idx, obj = _landmark_matches(vmap, hamming_matcher(vmap.vocabulary.binary), feats, cands)
    pixels = feats.xy[idx].astype(np.float64)
    proposal, inliers = None, 0
    if idx.size >= tun.min_pnp_inliers:
        proposal, inliers = _pnp_pose(obj, pixels, kmat, c_q, tun, seed)
    points, px, group, distinct = landmarks.candidates(feats, tun.neighbours, tun.distinct_ratio)
    first = np.flatnonzero(distinct) * tun.neighbours  # each distinctive feature's nearest
    return PictureMatches(
        points, px, group, tun.neighbours, obj, pixels, projection, area, len(feats),
        tuple(cands), proposal, inliers, points[first], px[first], (cam.width, cam.height),
    )  # fmt: skip


class LandmarkIndex:
    """The map's triangulated landmarks, ready for nearest-descriptor search.

    Args:
        vmap: The map.
    """

    def __init__(self, vmap: MapData) -> None:
        points = np.asarray(vmap.kp_points, np.float64)
        known = np.flatnonzero(np.isfinite(points).all(axis=1))
        self.points = points[known]
        desc = np.ascontiguousarray(vmap.kp_desc[known])
        self.binary = bool(vmap.vocabulary.binary)
        self.desc = pad_packed(desc) if self.binary else desc
        self.matcher = hamming_matcher(self.binary)

    def candidates(
        self, feats: Features, k: int, ratio: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Each feature's ``k`` nearest landmark descriptors, and which features are
        distinctive.

        Returns:
            The candidates' points and pixels, their feature index, and per feature whether
            its nearest landmark is ``ratio`` times nearer in descriptor space than the
            nearest *other* landmark (one 0.1 m away or more: the same point triangulated
            from two pairs of keyframes is one landmark), Lowe's test over the whole map.
        """
        if len(feats) == 0 or self.points.shape[0] == 0:
            return np.zeros((0, 3)), np.zeros((0, 2)), np.zeros(0, np.int64), np.zeros(0, bool)
        query = pad_packed(feats.descriptors) if self.binary else feats.descriptors
        dist, nearest = self.matcher.knn(query, self.desc, k)
        pts = self.points[nearest]  # (n, k, 3)
        other = np.linalg.norm(pts - pts[:, :1], axis=2) > 0.1
        second = np.where(other, dist, np.inf).min(axis=1)
        distinct = dist[:, 0] < ratio * second
        group = np.repeat(np.arange(len(feats)), nearest.shape[1])
        return pts.reshape(-1, 3), feats.xy[group].astype(np.float64), group, distinct


def _to_camera(
    points: np.ndarray, projection: np.ndarray, pose: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Map-frame points in FRAME_ROBOT at ``pose`` (``(n, 3)``, m) and their homogeneous
    pixels through ``projection`` (``(n, 3)``)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy = points[:, 0] - pose[0], points[:, 1] - pose[1]
    pr = np.column_stack([c * dx + s * dy, -s * dx + c * dy, points[:, 2]])
    return pr, pr @ projection[:, :3].T + projection[:, 3]


def reprojection(
    m: PictureMatches, pose: np.ndarray, jacobian: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Each match's pixel residual from a robot pose at capture.

    Args:
        m: The picture's matches.
        pose: ``(x, y, theta)`` of the robot at capture, map frame.
        jacobian: Also return d residual / d pose.

    Returns:
        ``(n, 2)`` residuals (projected minus measured, px), ``(n,)`` whether the landmark is
        in front of the camera, and ``(n, 2, 3)`` Jacobians (or None).
    """
    c, s = math.cos(pose[2]), math.sin(pose[2])
    pr, h = _to_camera(m.points, m.projection, pose)
    z = h[:, 2]
    front = z > 0.05
    zs = np.where(front, z, 1.0)
    uv = h[:, :2] / zs[:, None]
    res = uv - m.pixels
    if not jacobian:
        return res, front, None
    # d pr / d (x, y, theta)
    dpr = np.zeros((m.points.shape[0], 3, 3))
    dpr[:, 0, 0], dpr[:, 1, 0] = -c, s
    dpr[:, 0, 1], dpr[:, 1, 1] = -s, -c
    dpr[:, 0, 2], dpr[:, 1, 2] = pr[:, 1], -pr[:, 0]
    mp = m.projection[:, :3]
    # d uv / d pr = (M[:2] z - h[:2] M[2]) / z^2
    duv = (mp[None, :2, :] * zs[:, None, None] - h[:, :2, None] * mp[None, 2:3, :]) / (
        zs[:, None, None] ** 2
    )
    return res, front, duv @ dpr


def mixture(
    m: PictureMatches, res: np.ndarray, front: np.ndarray, cov: np.ndarray, tun: FilterTuning
) -> tuple[np.ndarray, np.ndarray]:
    """Each candidate's responsibility and each feature's log ratio over 'wrong'.

    A feature is right with probability ``1 - match_outlier_share`` (then one of its
    candidates, each equally likely a priori, is its landmark, with Gaussian pixel error of
    covariance ``cov``) or wrong (uniform over the image).

    Args:
        m: The picture's candidates.
        res: ``(n, 2)`` residuals, px.
        front: ``(n,)`` whether each landmark is in front of the camera.
        cov: ``(n, 2, 2)`` or ``(2, 2)`` pixel covariance of each candidate.
        tun: The filter's tuning.

    Returns:
        ``(n,)`` responsibilities (the posterior that the candidate is the feature's
        landmark) and ``(features,)`` per-feature log ratios, nats.
    """
    e = tun.match_outlier_share
    wrong = e / m.area_px
    cov = np.broadcast_to(cov, (res.shape[0], 2, 2))
    a, b, d = cov[:, 0, 0], cov[:, 0, 1], cov[:, 1, 1]
    det = a * d - b * b
    rx, ry = res[:, 0], res[:, 1]
    m2 = (d * rx * rx - 2.0 * b * rx * ry + a * ry * ry) / det  # 2 x 2 inverse in closed form
    prior = (1.0 - e) / m.per_feature
    hit = np.where(
        front, prior * np.exp(-0.5 * np.minimum(m2, 700.0)) / (2 * math.pi * np.sqrt(det)), 0.0
    )
    per = np.bincount(m.group, weights=hit, minlength=m.features)
    resp = hit / (per[m.group] + wrong)
    return resp, np.log((per + wrong) / wrong)


def distinct_only(m: PictureMatches) -> PictureMatches:
    """The picture's distinctive matches alone (each feature whose nearest landmark passes
    Lowe's ratio test over the whole map).

    Any pose finds a few of the many nearest-descriptor candidates by chance; distinctive
    matches agree with a pose only where the picture and the map show the same place, so
    they alone weigh whether this is the mapped room at all.
    """
    n = m.distinct.shape[0]
    return PictureMatches(
        m.distinct, m.distinct_pixels, np.arange(n), 1, m.matched, m.matched_pixels,
        m.projection, m.area_px, n, m.retrieved, m.proposal, m.proposal_inliers,
        m.distinct, m.distinct_pixels, m.size_px,
    )  # fmt: skip


@dataclass
class RoomObjects:
    """The objects whose distinctive matches spoke for the mapped room at one place.

    An object is a cluster of landmarks (``identity_object_m``: a picture on the wall); each
    holds at most ``identity_cap_nats`` of the place's room evidence at a time, and forgets
    as that evidence does. Seeing it again tells nothing new of which room this is: its
    twin may hang in another room (rooms share prints).

    Attributes:
        centres: ``(k, 3)`` each object's first landmark, map frame, m.
        credit: ``(k,)`` the evidence each holds now, nats.
    """

    centres: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    credit: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def forget(self, kept: float) -> None:
        """Keep a share ``kept`` of every object's credit."""
        self.credit = self.credit * kept


def identity_evidence(
    m: PictureMatches, pose: np.ndarray, tun: FilterTuning, objects: RoomObjects
) -> float:
    """What a picture's distinctive matches at ``pose`` say for the mapped room (nats), each
    object's part topped up to ``identity_cap_nats`` at most, and the picture's too
    (``objects`` is updated).

    Each feature's log ratio (times ``match_weight``) goes to the object of its landmark:
    the nearest object within ``identity_object_m``, else a new one there.
    """
    d = distinct_only(m)
    ratios = feature_log_ratios(d, pose, tun)
    cap = tun.identity_cap_nats
    total = 0.0
    added: list[tuple[int, float]] = []
    for k in np.argsort(-ratios):  # the strongest matches found the objects
        r = float(ratios[k])
        if r <= 1e-6:
            break
        p = d.points[k]
        dist = np.linalg.norm(objects.centres - p, axis=1)
        j = int(np.argmin(dist)) if dist.size else -1
        if j < 0 or dist[j] > tun.identity_object_m:
            objects.centres = np.vstack([objects.centres, p[None, :]])
            objects.credit = np.append(objects.credit, 0.0)
            j = objects.centres.shape[0] - 1
        add = min(r, max(0.0, cap - float(objects.credit[j])))
        objects.credit[j] += add
        added.append((j, add))
        total += add
    if total > cap:  # one picture's matches share its view: at most identity_cap_nats
        for j, add in added:
            objects.credit[j] -= add * (1.0 - cap / total)
        total = cap
    return total


def feature_log_ratios(m: PictureMatches, pose: np.ndarray, tun: FilterTuning) -> np.ndarray:
    """Each feature's log ratio over 'wrong' at ``pose`` (:func:`mixture`) times
    ``match_weight``, nats; ``(features,)``, empty without candidates."""
    if m.points.shape[0] == 0:
        return np.zeros(0)
    res, front, _ = reprojection(m, pose)
    _, ratios = mixture(m, res, front, tun.pixel_sigma_px**2 * np.eye(2), tun)
    return tun.match_weight * ratios


def picture_log_ratio(m: PictureMatches, pose: np.ndarray, tun: FilterTuning) -> float:
    """Evidence the picture gives for ``pose`` over 'its features are all wrong' (nats),
    each feature's log ratio times ``match_weight``, at most ``picture_evidence_cap_nats``."""
    return min(tun.picture_evidence_cap_nats, float(feature_log_ratios(m, pose, tun).sum()))


def landmarks_in_view(
    points: np.ndarray, m: PictureMatches, pose: np.ndarray, range_m: float
) -> int:
    """How many of the map's landmarks the picture would show from ``pose``: within
    ``range_m`` of the robot, in front of the camera and inside the image.

    Where the map expects many, a picture that matches none of them speaks against the pose
    (negative information); where it expects few (an unmapped view), it says nothing.

    Args:
        points: ``(n, 3)`` the map's landmarks (map frame, m).
        m: The picture (its projection and size; the matches are not used).
        pose: ``(x, y, theta)`` of the robot at capture, map frame.
        range_m: The farthest landmark counted (m).
    """
    width, height = m.size_px
    if points.shape[0] == 0 or width <= 0 or height <= 0:
        return 0
    dx, dy = points[:, 0] - pose[0], points[:, 1] - pose[1]
    near = dx * dx + dy * dy < range_m * range_m
    if not near.any():
        return 0
    _, h = _to_camera(points[near], m.projection, pose)
    z = h[:, 2]
    front = z > 0.1
    zs = np.where(front, z, 1.0)
    u, v = h[:, 0] / zs, h[:, 1] / zs
    inside = front & (u >= 0) & (u < width) & (v >= 0) & (v < height)
    return int(np.count_nonzero(inside))
