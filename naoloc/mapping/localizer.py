"""Algorithm 5 (``paper``) and a geometrically verified localizer (``verified``).

``paper``: histogram of each query -> winning GCS neuron (among neurons that carry a
pose) -> the mean of those neurons' poses, exactly as the paper. Heading (which the
paper does not estimate) is the winning neurons' mean camera heading minus the query's
head yaw.

``verified``: TF-IDF retrieval of candidate keyframes (DBoW2 L1 score) plus the
keyframes of the query's GCS winner; ratio-tested descriptor matches from the query to
each candidate's triangulated landmarks; ``solvePnPRansac`` per query; then a joint
3-DoF (x, y, theta) refinement of the last query's robot pose over all queries, tied
together by their relative odometry. When PnP fails it falls back to an inlier-weighted
mean of candidate keyframe poses with the heading from the image-space rotation.

All poses are robot (FRAME_ROBOT origin) poses in the map frame when the LAST query was
taken (metres, radians).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from naoloc.config import LocalizeMode, LocalizerTuning, LocalizeStrategy
from naoloc.errors import NaolocError
from naoloc.geometry import Pose2D, circular_mean, modulo2PI, relative_pose
from naoloc.mapping.data import MapData
from naoloc.mapping.landmarks import (
    DescriptorMatcher,
    hamming_matcher,
    planar_pose,
    query_camera,
    ratio_matches,
    robot_matrix,
)
from naoloc.mapping.planar import solve_planar
from naoloc.mapping.planar_ransac import planar_hypotheses
from naoloc.mapping.vocabulary import dbow_scores
from naoloc.perception.features import FeatureExtractor, Features
from naoloc.robot.keyframe import Keyframe, camera_in_robot

__all__ = [
    "CONFIDENT",
    "Estimate",
    "LocalizeMode",
    "LocalizeStrategy",
    "MatchMemo",
    "localize_features",
    "localize_paper",
    "localize_verified",
    "map_extractor",
    "query_camera",
]

#: The map type the localizer reads (plain data; naoloc.mapping.VisualMap is one).
VisualMap = MapData


#: Defaults of ``MapConfig.tuning.localizer`` (the map's own config is what is used).
DEFAULTS = LocalizerTuning()
# Planar RANSAC hypotheses verified by reprojection, best first.
PLANAR_KEEP = 5
#: Another hypothesis at least AMBIGUOUS_M from the estimate with at least AMBIGUOUS_SHARE
#: of the best one's inliers is reported as an alternative (``details["alternatives"]``):
#: two copies of a print 0.5 m apart give two poses with 26/25 and 37/37 inliers.
AMBIGUOUS_M = 0.25
AMBIGUOUS_SHARE = 0.8
#: A PnP estimate with at least this confidence (40 inliers) is "confident": behaviours may
#: stop looking. Unverified fallbacks never reach it (capped at FALLBACK_MAX_CONFIDENCE).
CONFIDENT = 1.0 - math.exp(-DEFAULTS.confident_inliers / DEFAULTS.confidence_scale)
#: An estimate with alternatives is capped below CONFIDENT, so a scan turns and looks more.
AMBIGUOUS_CONFIDENCE = 0.9 * CONFIDENT
# naoloc.mapping.support.pose_support: nearest landmark descriptors per query feature, and
# the reprojection radius.
SUPPORT_NEIGHBOURS = 3
SUPPORT_RADIUS_PX = 12.0
FALLBACK_MAX_CONFIDENCE = DEFAULTS.fallback_max_confidence
#: Plausibility of a pose: no more than CLEARANCE_MAX_LANDMARKS landmarks (between the floor
#: and 3 m up) closer than the clearance radius to the robot's centre.
CLEARANCE_MAX_LANDMARKS = DEFAULTS.clearance_max_landmarks


@dataclass(frozen=True)
class Estimate:
    """A robot pose estimate in the map frame.

    Attributes:
        x: Forward coordinate in metres (map frame).
        y: Left coordinate in metres (map frame).
        theta: Heading in radians, in (-pi, pi] (map frame).
        confidence: In [0, 1]; 0 when the queries had no usable features.
        mode: ``verified`` or ``paper``.
        details: JSON-able extras (candidates, inliers, method).
    """

    x: float
    y: float
    theta: float
    confidence: float
    mode: str
    details: dict[str, Any] = field(default_factory=dict)

    def pose(self) -> Pose2D:
        """The estimate as a :class:`Pose2D`."""
        return Pose2D(self.x, self.y, self.theta)

    @property
    def found(self) -> bool:
        """False when nothing was recognised: then x, y and theta are NaN, never a guess."""
        return self.method != "none" and math.isfinite(self.x) and math.isfinite(self.y)

    @property
    def method(self) -> str:
        """How the pose was found: ``pnp``, ``floorlines``, ``keyframes``, ``paper``, ``filter``
        or ``none``."""
        return str(self.details.get("method", self.mode))


def map_extractor(vmap: MapData) -> FeatureExtractor:
    """A feature extractor with the parameters the map was built with."""
    p = vmap.feature_params
    return FeatureExtractor(
        p["kind"],
        int(p.get("max_features", 0)),
        float(p.get("akaze_threshold", 0.001)),
        int(p.get("min_keypoints", 0)),  # maps from before the adaptive threshold: 0
    )


def localize_features(
    vmap: MapData,
    feats: Sequence[Features],
    queries: Sequence[Keyframe],
    mode: LocalizeMode | str = LocalizeMode.VERIFIED,
    memo: MatchMemo | None = None,
) -> Estimate:
    """Estimate the pose at the last query from the queries' features (see module doc).

    Args:
        vmap: The map.
        feats: Features of each query, extracted with the map's extractor.
        queries: The query images (odometry poses and head angles).
        mode: ``verified`` (default) or ``paper``.
        memo: Keeps each picture's work across calls on a growing scan (verified mode;
            :class:`MatchMemo`); the answer is the same without it.

    Raises:
        NaolocError: On an unknown mode or no queries.
    """
    try:
        chosen = LocalizeMode(mode)
    except ValueError:
        valid = ", ".join(m.value for m in LocalizeMode)
        raise NaolocError(f"unknown localize mode {mode!r}; valid: {valid}") from None
    if not queries or len(feats) != len(queries):
        raise NaolocError("localize needs at least one query image and one feature set each")
    if chosen is LocalizeMode.PAPER:
        return localize_paper(vmap, feats, queries)
    return localize_verified(vmap, feats, queries, memo=memo)


def turn_scale_of(vmap: MapData) -> float:
    """The survey's odometry turn per true turn (``meta.wall_poses.turn_scale``), else 1."""
    walls = vmap.meta.get("wall_poses")
    scale = walls.get("turn_scale") if isinstance(walls, dict) else None
    return float(scale) if isinstance(scale, (int, float)) and scale > 0 else 1.0


def robot_to_last(queries: Sequence[Keyframe], turn_scale: float = 1.0) -> list[np.ndarray]:
    """Per query, ``T_robotq_robotlast`` from the queries' odometry poses.

    The turn from each query to the last is the sum of the turns between consecutive
    queries (so three quarter turns are 4.7 rad, not -1.6), divided by ``turn_scale``: the
    robot's odometry reads its turns that much too large, as the survey's corners measured
    against the walls (:func:`turn_scale_of`). A NAO's 5 % turn error had put combined
    estimates 15-17 deg off after three quarter turns, and kept pictures from different
    sweeps from agreeing.
    """
    last = queries[-1].pose
    turn = 0.0
    out = [robot_matrix(0.0, 0.0, 0.0)]
    for a, b in itertools.pairwise(reversed(queries)):  # last to first
        turn += modulo2PI(a.pose.theta - b.pose.theta)
        rel = relative_pose(b.pose, last)
        out.append(robot_matrix(rel.x, rel.y, turn / turn_scale))
    return out[::-1]


def no_estimate(mode: str, reason: str, details: dict[str, Any] | None = None) -> Estimate:
    """The answer when nothing was recognised: no pose at all (NaN), confidence 0.

    Args:
        mode: ``verified`` or ``paper``.
        reason: A few words on why (``no features``, ``no verified match``...).
        details: Extras to keep (candidates...).
    """
    nan = float("nan")
    extras = {**(details or {}), "method": "none", "reason": reason}
    return Estimate(nan, nan, nan, 0.0, mode, extras)


def featured_neuron_poses(vmap: VisualMap) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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


def localize_paper(
    vmap: VisualMap, feats: Sequence[Features], queries: Sequence[Keyframe]
) -> Estimate:
    """Algorithm 5: mean pose of the winning neurons of the query histograms.

    Only neurons that win keyframes with keypoints take part (:func:`featured_neuron_poses`).
    """
    posed, neuron_poses, neuron_views = featured_neuron_poses(vmap)
    usable = [i for i, f in enumerate(feats) if len(f) > 0]
    if not usable or posed.size == 0:
        return no_estimate("paper", "no features" if not usable else "no posed neuron")
    to_last = robot_to_last(queries, turn_scale_of(vmap))
    xs, ys, headings, closeness, winners = [], [], [], [], []
    weights = vmap.gcs.weights[posed]
    for i in usable:
        hist = vmap.vocabulary.histogram(feats[i].descriptors)
        d2 = np.sum((weights - hist[None, :]) ** 2, axis=1)
        j = int(np.argmin(d2))
        winners.append(int(posed[j]))
        xs.append(neuron_poses[j, 0])
        ys.append(neuron_poses[j, 1])
        theta_q = neuron_views[j] - queries[i].head_yaw
        headings.append(theta_q + math.atan2(to_last[i][1, 0], to_last[i][0, 0]))
        closeness.append(max(0.0, 1.0 - math.sqrt(float(d2[j])) / math.sqrt(2.0)))
    conf = len(usable) / len(feats) * float(np.mean(closeness))
    theta = circular_mean(np.asarray(headings), np.ones(len(headings)))
    return Estimate(
        float(np.mean(xs)),
        float(np.mean(ys)),
        modulo2PI(theta),
        float(np.clip(conf, 0.0, 1.0)),
        "paper",
        {"method": "gcs", "neurons": winners},
    )


@dataclass
class _Correspondences:
    points: list[np.ndarray] = field(default_factory=list)  # (n, 3) map frame
    pixels: list[np.ndarray] = field(default_factory=list)  # (n, 2)
    query: list[np.ndarray] = field(default_factory=list)  # (n,) query index


@dataclass(frozen=True)
class _PictureMatches:
    """One query picture's retrieval and landmark matches: they do not depend on the other
    pictures of a scan.

    Attributes:
        cands: Retrieved keyframes.
        votes: ``(keyframe, weight, matches)`` per candidate with matches.
        q_idx: The picture's features matched to a landmark, (n,).
        obj: Their landmarks, (n, 3), map frame, m.
    """

    cands: list[int]
    votes: list[tuple[int, float, np.ndarray]]
    q_idx: np.ndarray
    obj: np.ndarray


class MatchMemo:
    """The verified localizer's per-picture work, kept across calls on a growing scan.

    A scan that turns in place and sweeps again asks the map with every picture so far
    (:func:`naoloc.behaviours.localize.localize`); a picture's retrieval, landmark matches
    and PnP camera do not depend on the other pictures, so with one memo they are computed
    once per picture instead of once per call. Entries are keyed by the picture's
    :class:`Features` and :class:`Keyframe` objects (held, so their ids are not reused) and
    the retrieval depth; a PnP result also by the picture's index in the call (its RANSAC
    seed), so answers are the same with or without a memo.
    """

    def __init__(self) -> None:
        self._matches: dict[tuple[int, int, int], tuple[Any, Any, _PictureMatches]] = {}
        self._pnp: dict[tuple[int, int], tuple[Any, np.ndarray | None]] = {}

    def matches(
        self, f: Features, q: Keyframe, top_k: int, compute: Callable[[], _PictureMatches]
    ) -> _PictureMatches:
        """The picture's matches, computed by ``compute`` the first time."""
        key = (id(f), id(q), top_k)
        held = self._matches.get(key)
        if held is None:
            held = (f, q, compute())
            self._matches[key] = held
        return held[2]

    def pnp(
        self, matches: _PictureMatches, qi: int, compute: Callable[[], np.ndarray | None]
    ) -> np.ndarray | None:
        """The picture's PnP camera pose (``T_map_cam``; None: no plausible pose) at index
        ``qi`` of a call, computed by ``compute`` the first time."""
        key = (id(matches), qi)
        held = self._pnp.get(key)
        if held is None:
            held = (matches, compute())
            self._pnp[key] = held
        return held[1]


def _candidates(vmap: VisualMap, hist: np.ndarray, top_k: int) -> list[int]:
    scores = dbow_scores(hist, vmap.histograms)
    order = np.argsort(-scores, kind="stable")[:top_k].tolist()
    winner = int(vmap.gcs.winners(hist)[0])
    extra = np.flatnonzero(vmap.winners == winner)[:2].tolist()
    return list(dict.fromkeys(order + extra))


def _project(
    pose: np.ndarray, mats: np.ndarray, points: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Pixels and depths of map points for a last-robot pose; ``mats`` (n, 3, 4)."""
    t_inv = np.linalg.inv(robot_matrix(*pose))
    pr = points @ t_inv[:3, :3].T + t_inv[:3, 3]
    h = np.einsum("nij,nj->ni", mats[:, :, :3], pr) + mats[:, :, 3]
    z = h[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        uv = h[:, :2] / z[:, None]
    return uv, z


def pixel_residuals(
    pose: np.ndarray, mats: np.ndarray, pts: np.ndarray, px: np.ndarray
) -> np.ndarray:
    """Each match's reprojection error from robot pose ``pose`` (pixels; inf behind the
    camera or not finite).

    Args:
        pose: ``(x, y, theta)`` of the robot when the last query was taken, map frame.
        mats: Per match, map point in the last query's robot frame -> pixels, (n, 3, 4).
        pts: The matched landmarks, (n, 3), map frame, m.
        px: The matched features' pixels, (n, 2).
    """
    uv, z = _project(pose, mats, pts)
    err = np.linalg.norm(uv - px, axis=1)
    err[~(z > 0.05) | ~np.isfinite(err)] = np.inf
    return err


def _refine(pose: np.ndarray, mats: np.ndarray, pts: np.ndarray, px: np.ndarray) -> np.ndarray:
    """Gauss-Newton on (x, y, theta) over the given correspondences (naoloc.mapping.planar)."""

    def at(p: np.ndarray) -> np.ndarray:
        return (_project(p, mats, pts)[0] - px).ravel()

    def linearise(p: np.ndarray) -> tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]:
        return at(p), at

    fit = solve_planar(
        linearise, pose, iterations=6, fd_step=1e-4, tol=1e-6, stop_on_nonfinite=True
    )
    assert fit is not None  # linearise never gives up
    return fit.x


def crowded_landmarks(vmap: VisualMap, x: float, y: float) -> int:
    """Landmarks (0.05-3 m above the floor) closer than the clearance radius to ``(x, y)``.

    A robot stands in free space: a pose with many landmarks within its body is a wrong one
    (e.g. PnP on a repeated poster that puts the robot in a wall).
    """
    p = vmap.kp_points
    r = vmap.config.tuning.localizer.clearance_m
    near = (np.abs(p[:, 0] - x) < r) & (np.abs(p[:, 1] - y) < r)
    q = p[near]
    ok = (np.hypot(q[:, 0] - x, q[:, 1] - y) < r) & (q[:, 2] > 0.05) & (q[:, 2] < 3.0)
    return int(ok.sum())


def _best_plausible(
    vmap: VisualMap,
    hypotheses: list[np.ndarray],
    mm: np.ndarray,
    pts: np.ndarray,
    px: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, int, list[list[float]]] | None:
    """Refine hypotheses by inlier count, best first; the first plausible one wins.

    Returns:
        The refined last-robot pose, its inlier mask over all correspondences, the number
        of implausible hypotheses passed over and the alternatives (other plausible poses,
        each at least :data:`AMBIGUOUS_M` from it and from each other, with at least
        :data:`AMBIGUOUS_SHARE` of the best hypothesis' inliers: ``[x, y, theta, inliers]``);
        None when no hypothesis reaches ``min_pnp_inliers`` at a plausible pose.
    """
    tun = vmap.config.tuning.localizer
    scored = []
    for h in hypotheses:
        inl = pixel_residuals(h, mm, pts, px) < tun.pnp_reprojection_px
        scored.append((int(inl.sum()), h, inl))
    scored.sort(key=lambda t: -t[0])
    rejected = 0
    tried: list[np.ndarray] = []
    for _n, pose, inl in scored:
        if any(np.hypot(*(pose[:2] - t[:2])) < 0.05 for t in tried):
            continue  # the same pose again (several queries agreeing)
        tried.append(pose)
        for _ in range(3):
            if inl.sum() < 4:
                break
            pose = _refine(pose, mm[inl], pts[inl], px[inl])
            inl = pixel_residuals(pose, mm, pts, px) < tun.pnp_reprojection_px
        if int(inl.sum()) < tun.min_pnp_inliers:
            continue
        if crowded_landmarks(vmap, float(pose[0]), float(pose[1])) > tun.clearance_max_landmarks:
            rejected += 1
            continue
        return pose, inl, rejected, _alternatives(vmap, scored, pose)
    return None


def _alternatives(
    vmap: VisualMap, scored: list[tuple[int, np.ndarray, np.ndarray]], pose: np.ndarray
) -> list[list[float]]:
    """Other plausible hypotheses nearly as well supported as the best (see caller)."""
    tun = vmap.config.tuning.localizer
    floor = AMBIGUOUS_SHARE * scored[0][0]
    kept: list[np.ndarray] = [pose]
    out: list[list[float]] = []
    for n, h, _inl in scored:
        if n < max(floor, tun.min_pnp_inliers):
            break
        if any(np.hypot(*(h[:2] - k[:2])) < AMBIGUOUS_M for k in kept):
            continue
        if crowded_landmarks(vmap, float(h[0]), float(h[1])) > tun.clearance_max_landmarks:
            continue
        kept.append(h)
        out.append([round(float(h[0]), 4), round(float(h[1]), 4), round(float(h[2]), 4), n])
    return out


def query_projection(kmat: np.ndarray, c_q: np.ndarray, to_last: np.ndarray) -> np.ndarray:
    """The 3 x 4 map from a point in the last query's robot frame to a query's pixels
    (homogeneous): its intrinsics ``kmat``, its camera pose in its robot frame ``c_q`` and
    its robot pose relative to the last query's ``to_last``."""
    return kmat @ np.linalg.inv(c_q)[:3, :] @ to_last


def _correspond(
    vmap: VisualMap,
    feats: Sequence[Features],
    queries: Sequence[Keyframe],
    usable: Sequence[int],
    to_last: list[np.ndarray],
    top_k: int,
    memo: MatchMemo | None = None,
) -> tuple[
    _Correspondences,
    list[np.ndarray],
    list[np.ndarray],
    list[tuple[int, int, float, np.ndarray]],
    list[list[int]],
]:
    """Each usable query's retrieval candidates, landmark matches and PnP pose.

    Returns:
        The 2D-3D correspondences, their projection matrices (map point to pixel for a
        last-robot pose), the PnP hypotheses (last-robot poses, map frame), the per-keyframe
        match votes and every query's candidates. ``memo`` keeps each picture's work for
        the next call (:class:`MatchMemo`).
    """
    tun = vmap.config.tuning.localizer
    memo = memo if memo is not None else MatchMemo()
    matcher = hamming_matcher(vmap.vocabulary.binary)
    corr = _Correspondences()
    mats: list[np.ndarray] = []
    hypotheses: list[np.ndarray] = []
    kf_votes: list[tuple[int, int, float, np.ndarray]] = []  # query, keyframe, weight, matches
    cand_all: list[list[int]] = []
    for qi in usable:
        q, f = queries[qi], feats[qi]
        pm = memo.matches(f, q, top_k, functools.partial(_picture_matches, vmap, matcher, f, top_k))
        cand_all.append(pm.cands)
        kf_votes += [(qi, c, w, m) for c, w, m in pm.votes]
        if len(pm.q_idx) < 6:
            continue
        img = f.xy[pm.q_idx].astype(np.float64)
        c_q = q.camera_matrix()  # the robot's own kinematics at capture
        kmat = query_camera(q).matrix()
        m_q = query_projection(kmat, c_q, to_last[qi])
        corr.points.append(pm.obj)
        corr.pixels.append(img)
        corr.query.append(np.full(len(pm.q_idx), qi))
        mats.append(np.repeat(m_q[None], len(pm.q_idx), axis=0))
        t_map_cam = memo.pnp(pm, qi, functools.partial(_pnp, vmap, kmat, pm, img, qi))
        if t_map_cam is None:
            continue
        if abs(t_map_cam[2, 3] - c_q[2, 3]) > tun.camera_height_tolerance_m:
            continue
        t_map_robot_last = t_map_cam @ np.linalg.inv(c_q) @ to_last[qi]
        hypotheses.append(np.array(planar_pose(t_map_robot_last)))
    return corr, mats, hypotheses, kf_votes, cand_all


def _picture_matches(
    vmap: VisualMap, matcher: DescriptorMatcher, f: Features, top_k: int
) -> _PictureMatches:
    """One picture's retrieval candidates and ratio-tested landmark matches."""
    cands = _candidates(vmap, vmap.vocabulary.histogram(f.descriptors), top_k)
    votes: list[tuple[int, float, np.ndarray]] = []
    best: dict[int, np.ndarray] = {}
    for c in cands:
        lo, hi = int(vmap.kp_offsets[c]), int(vmap.kp_offsets[c + 1])
        m = ratio_matches(matcher, f.descriptors, vmap.kp_desc[lo:hi])
        if m.shape[0] == 0:
            continue
        votes.append((c, float(m.shape[0]), m))
        pts = vmap.kp_points[lo + m[:, 1]]
        for (a, _b), p in zip(m.tolist(), pts, strict=True):
            if np.isfinite(p[0]) and a not in best:
                best[a] = p
    q_idx = np.fromiter(best.keys(), np.int64, len(best))
    obj = np.stack([best[a] for a in q_idx.tolist()]) if best else np.zeros((0, 3))
    return _PictureMatches(cands, votes, q_idx, obj)


def _pnp(
    vmap: VisualMap, kmat: np.ndarray, pm: _PictureMatches, img: np.ndarray, qi: int
) -> np.ndarray | None:
    """``T_map_cam`` of the picture (intrinsics ``kmat``) by PnP RANSAC on its matches
    (None: no pose); ``qi`` seeds OpenCV's RANSAC."""
    import cv2

    tun = vmap.config.tuning.localizer
    try:
        # OpenCV's RANSAC draws from a process-wide RNG: seed it per call so a query gives
        # the same answer whatever ran before it (in-process, served, or in a worker).
        cv2.setRNGSeed(int(vmap.config.seed) + qi)
        ok, rvec, tvec, inl = cv2.solvePnPRansac(
            pm.obj,
            img,
            kmat,
            None,
            iterationsCount=tun.pnp_iterations,
            reprojectionError=tun.pnp_reprojection_px,
            confidence=0.99,
            flags=cv2.SOLVEPNP_AP3P,
        )
    except cv2.error:
        return None
    if not ok or inl is None or len(inl) < 6:
        return None
    rot, _ = cv2.Rodrigues(rvec)
    t_cam_map = np.eye(4)
    t_cam_map[:3, :3], t_cam_map[:3, 3] = rot, tvec.ravel()
    return np.linalg.inv(t_cam_map)


def localize_verified(
    vmap: VisualMap,
    feats: Sequence[Features],
    queries: Sequence[Keyframe],
    top_k: int | None = None,
    memo: MatchMemo | None = None,
) -> Estimate:
    """Retrieval + landmark matching + PnP + joint 3-DoF refinement (see module doc).

    ``top_k`` retrieval candidates per query (default: the map's tuning); ``memo`` keeps
    each picture's work across calls (:class:`MatchMemo`).
    """

    tun = vmap.config.tuning.localizer
    top_k = tun.candidates if top_k is None else top_k
    usable = [i for i, f in enumerate(feats) if len(f) > 0]
    if not usable:
        return no_estimate("verified", "no features")
    to_last = robot_to_last(queries, turn_scale_of(vmap))
    corr, mats, hypotheses, kf_votes, cand_all = _correspond(
        vmap, feats, queries, usable, to_last, top_k, memo
    )
    details: dict[str, Any] = {"candidates": cand_all}
    if corr.points and tun.planar_samples > 0:
        planar = planar_hypotheses(
            np.concatenate(mats),
            np.concatenate(corr.points),
            np.concatenate(corr.pixels),
            bearing_tol_rad=tun.pnp_reprojection_px / query_camera(queries[usable[0]]).fx,
            samples=tun.planar_samples,
            keep=PLANAR_KEEP,
            seed=int(vmap.config.seed),
        )
        details["planar_best"] = planar[0][0] if planar else 0
        hypotheses.extend(pose for _n, pose in planar)
    if hypotheses:
        pts = np.concatenate(corr.points)
        px = np.concatenate(corr.pixels)
        mm = np.concatenate(mats)
        found = _best_plausible(vmap, hypotheses, mm, pts, px)
        if found is not None:
            pose, inl, rejected, alternatives = found
            n_inl = int(inl.sum())
            qs = np.concatenate(corr.query)
            details.update(
                method="pnp",
                inliers=n_inl,
                correspondences=int(pts.shape[0]),
                inliers_per_query=[int((inl & (qs == qi)).sum()) for qi in usable],
                implausible_rejected=rejected,
                alternatives=alternatives,
            )
            conf = 1.0 - math.exp(-n_inl / tun.confidence_scale)
            if alternatives:  # not confident while another place fits nearly as well
                conf = min(conf, AMBIGUOUS_CONFIDENCE)
            return Estimate(
                float(pose[0]), float(pose[1]), modulo2PI(float(pose[2])), conf, "verified", details
            )
        details["implausible_rejected"] = len(hypotheses)
    return _fallback(vmap, feats, queries, kf_votes, to_last, details)


def _fallback(
    vmap: VisualMap,
    feats: Sequence[Features],
    queries: Sequence[Keyframe],
    votes: list[tuple[int, int, float, np.ndarray]],
    to_last: list[np.ndarray],
    details: dict[str, Any],
) -> Estimate:
    """Inlier-weighted mean of candidate keyframe poses; heading from image rotation."""
    import cv2

    tun = vmap.config.tuning.localizer
    xs, ys, ths, ws = [], [], [], []
    for qi, c, _n, m in votes:
        if m.shape[0] < 8:
            continue
        lo = int(vmap.kp_offsets[c])
        a = feats[qi].xy[m[:, 0]].astype(np.float64)
        b = vmap.kp_xy[lo + m[:, 1]].astype(np.float64)
        mask: Any = None
        try:
            cv2.setRNGSeed(int(vmap.config.seed) + qi)
            _f, mask = cv2.findFundamentalMat(a, b, cv2.FM_RANSAC, tun.fallback_epipolar_px, 0.99)
        except cv2.error:
            mask = None
        if mask is None or mask.size != len(a):
            continue
        inl = np.asarray(mask).ravel().astype(bool)
        if inl.sum() < 8:
            continue
        q = queries[qi]
        cam_q = query_camera(q)
        cam_k = vmap.keyframe_camera(c)
        bear_q = np.arctan((cam_q.width / 2.0 - a[inl, 0]) / cam_q.fx)
        bear_k = np.arctan((cam_k.width / 2.0 - b[inl, 0]) / cam_k.fx)
        yaw_k = vmap.refined_poses[c, 2] + vmap.keyframe_heads[c, 0]
        yaw_q = yaw_k + float(np.median(bear_k - bear_q))
        theta_q = yaw_q - q.head_yaw
        # The query camera is taken to be where the keyframe's camera was.
        t_map_cam_k = robot_matrix(*vmap.refined_poses[c]) @ camera_in_robot(
            float(vmap.keyframe_heads[c, 0]), float(vmap.keyframe_heads[c, 1]), cam_k.index
        )
        off = q.camera_matrix()[:2, 3]
        ct, st = math.cos(theta_q), math.sin(theta_q)
        rx = t_map_cam_k[0, 3] - (ct * off[0] - st * off[1])
        ry = t_map_cam_k[1, 3] - (st * off[0] + ct * off[1])
        last = robot_matrix(rx, ry, theta_q) @ to_last[qi]
        x, y, th = planar_pose(last)
        xs.append(x)
        ys.append(y)
        ths.append(th)
        ws.append(float(inl.sum()))
    if not ws:
        return no_estimate("verified", "no verified match", details)
    w = np.asarray(ws)
    details.update(method="keyframes", inliers=int(w.sum()))
    cap, scale = tun.fallback_max_confidence, tun.confidence_scale
    conf = cap * (1.0 - math.exp(-float(w.max()) / scale))
    return Estimate(
        float(np.average(xs, weights=w)),
        float(np.average(ys, weights=w)),
        modulo2PI(circular_mean(np.asarray(ths), w)),
        conf,
        "verified",
        details,
    )
