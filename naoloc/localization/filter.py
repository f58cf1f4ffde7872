"""The belief: a few Gaussian hypotheses, ranked by the evidence of recent observations.

The filter keeps up to ``max_hypotheses`` :class:`~naoloc.localization.hypothesis.Hypothesis`
(B-Human's multi-hypothesis self-locator, with nav2 AMCL's mixture sensor models):

- every observation moves every hypothesis by the odometry since the last one, corrects
  it, and adds the evidence it gives (nats over "clutter") to the hypothesis' score, which
  forgets a share ``forget_per_observation`` of its past at each observation (so the old
  place of a robot that was carried fades);
- a picture whose PnP proposes a pose that no hypothesis explains starts a new
  hypothesis there (global localization, recovery). It is replayed through the recent
  observations, so that its score counts the same observations as the others';
- hypotheses far below the best are dropped, close ones merged.

The belief's answer (:meth:`MultiHypothesisFilter.belief`) weighs each hypothesis by
``exp(score)`` against the prior that the observations come from somewhere the map does
not show (``exp(null_nats)``). "Not the mapped room" is that alternative winning. What
speaks for the mapped room is the pictures' distinctive matches (floor lines fit some
corner of any room); what speaks against it is those matches failing, and floor lines
seen beyond the map's walls, where the mapped room shows nothing.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from naoloc.config import FilterTuning
from naoloc.geometry import Pose2D, relative_pose, robot_matrix
from naoloc.localization.hypothesis import (
    Hypothesis,
    motion_step,
)
from naoloc.localization.line_poses import line_poses
from naoloc.localization.pictures import (
    PictureMatches,
    RoomObjects,
    identity_evidence,
    landmarks_in_view,
    picture_log_ratio,
)
from naoloc.localization.walls import WallMap, fit_line
from naoloc.mapping.planar_ransac import planar_hypotheses
from naoloc.perception.floorline import WallLine

__all__ = ["Belief", "Evidence", "MultiHypothesisFilter", "WalkingLines"]


CHI2_3DOF_99 = 11.345
"""The 99 % quantile of the chi-square distribution with 3 degrees of freedom (x, y, theta):
a pose's 99 % region is where its squared Mahalanobis distance is below it."""


class WalkingLines(tuple[WallLine, ...]):
    """A scan's floor lines taken while the robot walked (its odometry moved since the
    previous observation): weighed at the walking noise (``walk_line_sigma_*``), since the
    camera sways with the gait."""

    __slots__ = ()


Evidence = PictureMatches | tuple[WallLine, ...] | None
"""What one observation gives the filter: a picture's matches, a scan's lines (a
:class:`WalkingLines` when taken walking), or nothing."""


@dataclass(frozen=True)
class Belief:
    """The filter's answer.

    Attributes:
        pose: The best hypothesis' pose, map frame (None: no hypothesis).
        cov: Its covariance (3 x 3: x, y m; theta rad).
        probability: The weight, among the hypotheses and the other-room alternative, of
            the hypotheses inside the belief's 99 % region about the best pose (``cov``
            covers them): how concentrated the belief is.
        other_room: The other-room alternative's weight.
        hypotheses: How many hypotheses the filter holds.
        support: Pictures the best hypothesis explained.
        score: The best hypothesis' evidence, nats over the other-room alternative's 0.
        seen_score: Its pictures' part, which alone weighs against the other room.
        pictures: Pictures with features seen so far.
        contradicted: Whether the latest pictures were explained far better elsewhere than
            by the leading hypothesis (the robot was carried, or the leader is wrong).
        room_seen: The most evidence that this is the mapped room a probable place has
            given so far (nats, forgotten as the places' is): a robot that recognised the
            room and then lost its place (it was carried) is still in the room.
    """

    pose: np.ndarray | None
    cov: np.ndarray | None
    probability: float
    other_room: float
    hypotheses: int
    support: int
    score: float
    seen_score: float
    pictures: int
    contradicted: bool
    room_seen: float = 0.0


class MultiHypothesisFilter:
    """The belief over the robot's pose in one map.

    Args:
        walls: The map's walls (None: the floor lines are not used).
        tun: The filter's tuning.
        turn_scale: The robot's odometry turn per true turn, as the survey measured it.
        map_floor_m: The map's own position error (std, m), added to the reported
            covariance; None: ``tun.map_floor_m``. The larger of the two is used.
        landmarks: ``(n, 3)`` the map's landmarks (map frame, m): a picture taken where
            the map puts many of them in view judges a place even when it matches none
            (None: only pictures the map explains somewhere judge).
    """

    def __init__(
        self,
        walls: WallMap | None,
        tun: FilterTuning,
        turn_scale: float = 1.0,
        map_floor_m: float | None = None,
        landmarks: np.ndarray | None = None,
    ) -> None:
        self.walls = walls
        self.landmarks = np.zeros((0, 3)) if landmarks is None else landmarks
        self.tun = tun
        self.map_floor_m = max(tun.map_floor_m, map_floor_m or 0.0)
        self.turn_scale = turn_scale if turn_scale > 0 else 1.0
        self.hypotheses: list[Hypothesis] = []
        self.window: deque[tuple[Evidence, Pose2D]] = deque(maxlen=tun.window)
        self.odometry: Pose2D | None = None
        self.pictures = 0
        self.contradicted = False
        self._behind = 0  # pictures in a row the leader explained far worse than another
        self.room_seen = 0.0  # see Belief.room_seen
        m, r = tun.proposal_sigma
        self._proposal_cov = np.diag([m**2, m**2, r**2])
        m, r = tun.line_proposal_sigma
        self._line_cov = np.diag([m**2, m**2, r**2])
        # Lines taken walking are weighed at the walking noise.
        self._walk_tun = tun.model_copy(
            update={
                "line_sigma_m": tun.walk_line_sigma_m,
                "line_sigma_per_m": tun.walk_line_sigma_per_m,
                "line_sigma_rad": tun.walk_line_sigma_rad,
            }
        )

    def step_of(self, a: Pose2D, b: Pose2D) -> np.ndarray:
        """The odometry step from ``a`` to ``b`` in FRAME_ROBOT at ``a``, turn de-scaled."""
        rel = relative_pose(a, b)
        return np.array([rel.x, rel.y, rel.theta / self.turn_scale])

    def observe(self, evidence: Evidence, odometry: Pose2D) -> None:
        """Move the belief to ``odometry`` and correct it with ``evidence``."""
        if self.odometry is not None:
            step = self.step_of(self.odometry, odometry)
            for h in self.hypotheses:
                h.predict(step, self.tun)
            walked = math.hypot(step[0], step[1]) > self.tun.walking_step_m
            if walked and isinstance(evidence, tuple) and evidence:
                evidence = WalkingLines(evidence)
        self.odometry = odometry
        if evidence is not None:
            self.window.append((evidence, odometry))
        # Odometry alone says nothing of where the robot is: only evidence ages the scores.
        keep = 1.0 - self.tun.forget_per_observation if evidence is not None else 1.0
        # Only a picture with distinctive matches ages the evidence of which room this is
        # (a blank wall or a blurred view says nothing of it).
        distinctive = isinstance(evidence, PictureMatches) and evidence.distinct.shape[0] > 0
        kept = 1.0 - self.tun.identity_forget_per_picture if distinctive else 1.0
        leader = max(self.hypotheses, key=lambda h: h.score) if self.hypotheses else None
        gains = {}
        for h in self.hypotheses:
            gains[id(h)], against = self._update(h, evidence)
            h.score = keep * h.score + gains[id(h)]
            if isinstance(evidence, PictureMatches):
                h.objects.forget(kept)
                h.seen_score = kept * h.seen_score + self._identity(h, evidence)
            else:  # lines fit some corner of any room; beyond the walls, they speak against it
                h.seen_score += against
        if isinstance(evidence, PictureMatches):
            if evidence.features > 0:
                self.pictures += 1
            self._propose(evidence)
            if leader is not None:
                self._watch(leader, evidence, gains)
        elif evidence and self.walls is not None:
            self._shift_to_lines(evidence)
            for z in self._line_poses():
                self._add(z, None, self._line_cov)
            self._explore(at_rest=not isinstance(evidence, WalkingLines))
        self._prune()
        if distinctive:
            b = self.belief()
            self.room_seen *= kept
            if b.pose is not None and b.probability >= self.tun.confident:
                self.room_seen = max(self.room_seen, b.seen_score)

    def _add(
        self,
        z: np.ndarray,
        anchor: PictureMatches | None,
        cov: np.ndarray | None,
        beside: Hypothesis | None = None,
    ) -> bool:
        """Spawn a hypothesis at ``z`` unless one explains it already; whether it was.

        ``beside``: the hypothesis ``z`` was explored from, which does not count as
        explaining it (its own pictures favour ``z``; pruning keeps the better of the two).
        """
        if any(
            h.mahalanobis(z, self._proposal_cov * 0.1) < self.tun.gate_mahalanobis
            for h in self.hypotheses
            if h is not beside
        ):
            return False
        if anchor is None and self.hypotheses:
            # Not worth a replay when the pictures say far less for it than for the best.
            best = max(self.hypotheses, key=lambda g: g.score)
            if self._quick_score(z) < self._quick_score(best.pose) - self.tun.prune_nats:
                return False
        h = self._spawn(z, anchor, cov)
        if h is None:
            return False
        self.hypotheses.append(h)
        return True

    def _carried_lines(self) -> list[WallLine]:
        """The window's floor lines taken near here, carried into FRAME_ROBOT now."""
        assert self.odometry is not None
        out: list[WallLine] = []
        for evidence, odo in self.window:
            if not isinstance(evidence, tuple) or not evidence:
                continue
            step = self.step_of(self.odometry, odo)  # that frame's pose in the frame now
            if math.hypot(step[0], step[1]) > self.tun.pool_m:
                continue
            for line in evidence:
                normal = line.normal + step[2]
                shift = math.cos(normal) * step[0] + math.sin(normal) * step[1]
                out.append(dataclasses.replace(
                    line, distance=line.distance + shift,
                    normal=math.atan2(math.sin(normal), math.cos(normal)),
                ))  # fmt: skip
        return out

    def _line_poses(self, near: np.ndarray | None = None) -> list[np.ndarray]:
        """The poses the pooled floor lines allow (every wall and furniture coordinate),
        the ``line_proposals`` the pictures support best.

        Args:
            near: Only poses at this pose's quarter turn within :data:`NEAR_PROPOSAL_M` and
                :data:`NEAR_PROPOSAL_RAD` of it; None: every quarter turn.
        """
        if self.walls is None:
            return []
        lines = self._carried_lines()
        if len(lines) < 2:
            return []
        heading = None if near is None else float(near[2])
        poses = line_poses(lines, self.walls, self.tun, heading)
        if near is not None:
            poses = [
                z for z in poses
                if math.hypot(*(z[:2] - near[:2])) < self.tun.near_proposal_m
                and abs(math.remainder(z[2] - near[2], 2 * math.pi)) < self.tun.near_proposal_rad
            ]  # fmt: skip
        if not poses:
            return []
        scored = [(self._quick_score(z), i, z) for i, z in enumerate(poses)]
        scored.sort(key=lambda t: (-t[0], t[1]))
        return [z for _s, _i, z in scored[: self.tun.line_proposals]]

    def _quick_score(self, z: np.ndarray) -> float:
        """The latest pictures' evidence for pose ``z`` now, without correcting it."""
        assert self.odometry is not None
        total = 0.0
        pictures = [
            (e, o) for e, o in self.window if isinstance(e, PictureMatches) and e.points.shape[0]
        ]
        for evidence, odo in pictures[-self.tun.quick_pictures :]:
            step = self.step_of(self.odometry, odo)
            pose, _ = motion_step(z, np.zeros((3, 3)), step, self.tun)
            total += picture_log_ratio(evidence, pose, self.tun)
        return total

    def _watch(self, leader: Hypothesis, m: PictureMatches, gains: dict[int, float]) -> None:
        """Whether the leading hypothesis still explains what the robot sees (nav2 AMCL
        watches its likelihood's short- against its long-term average the same way).

        The leader is contradicted (the robot was carried, or the leader is wrong) when two
        pictures in a row with ``informative_features`` are explained clearly (``2 *
        contradiction_nats``) and ``contradiction_nats`` better by another hypothesis, or a
        new one a picture proposed; or when the evidence its informative pictures gave
        lately (``recent_rate``'s fast average) fell below ``fade_share`` of what they
        usually gave (``usual_rate``'s slow average, which stops following while the fast
        one is below ``usual_hold_share`` of it). A picture is informative when it has
        ``informative_features`` and the map could explain it somewhere (its PnP found a
        pose, or it has ``min_inliers`` distinctive matches); and, whatever its features,
        for a place from which the map puts ``expected_landmarks`` of its landmarks in the
        picture's view (negative information: the place should have shown them, even a view
        with no features). A blurred or unmapped view, seen from a place that expects
        little, says nothing. When the leader fades, so do the places this picture did not
        explain better: their past, too, no longer speaks for them.
        While contradicted, the window keeps only the latest observations: what was seen
        before may be of another place (a carried robot's odometry did not move).
        """
        tun = self.tun
        gain = gains.get(id(leader), 0.0)
        fresh = [picture_log_ratio(m, h.pose, tun) for h in self.hypotheses if id(h) not in gains]
        best = max([*gains.values(), *fresh], default=0.0)
        rich = m.features >= tun.informative_features
        behind = best > 2 * tun.contradiction_nats and best - gain > tun.contradiction_nats
        if rich:
            self._behind = self._behind + 1 if behind else 0
        explained = rich and (m.proposal is not None or m.distinct.shape[0] >= tun.min_inliers)
        for h in self.hypotheses:
            if id(h) not in gains:
                continue
            # The more distinctive matches (or its own PnP pose), the more a picture says
            # on its own: recent_rate at min_pnp_inliers of them, all at once at
            # min_pnp_inliers / recent_rate; a picture the map explains nowhere, recent_rate
            # where the map expects its landmarks in view.
            if m.proposal is not None:
                rate = 1.0
            elif explained:
                rate = min(1.0, tun.recent_rate * m.distinct.shape[0] / tun.min_pnp_inliers)
            elif self._expects(h, m):
                rate = tun.recent_rate
            else:
                continue
            h.recent += rate * (gains[id(h)] - h.recent)
            if h.recent >= tun.usual_hold_share * h.usual:  # not while it is fading
                h.usual += tun.usual_rate * (gains[id(h)] - h.usual)
        faded = (
            leader.usual > tun.contradiction_nats and leader.recent < tun.fade_share * leader.usual
        )
        if faded:
            # Its past no longer speaks for it, nor for the places that explain what is seen
            # now no better: they compete on what is seen now (places this picture proposed
            # have no past).
            low = tun.fade_share * leader.usual
            for h in self.hypotheses:
                if h is leader or (id(h) in gains and h.recent < low):
                    h.score = min(h.score, 0.0)
        self.contradicted = self._behind >= 2 or faded
        if self.contradicted:
            while len(self.window) > 2:
                self.window.popleft()

    def _expects(self, h: Hypothesis, m: PictureMatches) -> bool:
        """Whether the map puts ``expected_landmarks`` of its landmarks in the picture's
        view from ``h`` (so that a picture matching none of them speaks against it)."""
        need = self.tun.expected_landmarks
        if need <= 0:
            return False
        return landmarks_in_view(self.landmarks, m, h.pose, self.tun.expect_range_m) >= need

    def _shift_to_lines(self, lines: tuple[WallLine, ...]) -> None:
        """Siblings of the leading hypotheses moved so that a line they leave unexplained
        is a wall's foot (B-Human resets a hypothesis where percepts agree on another pose).

        Only lines whose direction agrees with a wall's (within ``gate_mahalanobis`` of the
        line's and the hypothesis' heading noise) and shifts up to ``shift_max_m``.
        """
        assert self.walls is not None
        leaders = sorted(self.hypotheses, key=lambda h: -h.score)[: self.tun.shift_from]
        fresh: list[Hypothesis] = []
        tun = self._line_tun(lines)
        for h in leaders:
            for line in lines:
                fit = fit_line(self.walls, line, h.pose, tun, h.cov)
                if fit.wall >= 0 and fit.log_ratio > self.tun.shift_explained_nats:
                    continue  # this hypothesis explains the line already
                dist, direction = self.walls.expected(h.pose)
                turn = np.angle(np.exp(1j * (line.normal - direction)))
                sig_a = math.hypot(tun.line_sigma_rad, math.sqrt(h.cov[2, 2]))
                for k in np.flatnonzero(np.abs(turn) < self.tun.gate_mahalanobis * sig_a):
                    shift = dist[k] - line.distance
                    if abs(shift) > self.tun.shift_max_m or abs(shift) < self.tun.shift_min_m:
                        continue
                    n = np.array([math.cos(self.walls.normals[k]), math.sin(self.walls.normals[k])])
                    z = np.array([*(h.pose[:2] + shift * n), h.pose[2] - turn[k]])
                    if any(
                        g.mahalanobis(z) < self.tun.merge_mahalanobis
                        for g in [*self.hypotheses, *fresh]
                    ):
                        continue
                    sibling = self._spawn(z, None, h.cov)
                    if sibling is not None:
                        fresh.append(sibling)
        self.hypotheses += fresh

    def _update(self, h: Hypothesis, evidence: Evidence) -> tuple[float, float]:
        """Correct ``h`` with ``evidence``: the evidence it gave ``h`` (nats) and what it
        said against the mapped room at ``h`` (nats, <= 0; lines beyond the walls)."""
        if isinstance(evidence, PictureMatches):
            return h.update_picture(evidence, self.tun).evidence, 0.0
        if evidence and self.walls is not None:
            return h.update_lines(self.walls, evidence, self._line_tun(evidence))
        return 0.0, 0.0

    def _line_tun(self, lines: tuple[WallLine, ...]) -> FilterTuning:
        """The tuning a scan's lines are weighed with: walking or at rest."""
        return self._walk_tun if isinstance(lines, WalkingLines) else self.tun

    def _identity(
        self, h: Hypothesis, evidence: Evidence, objects: RoomObjects | None = None
    ) -> float:
        """What a picture says of the map's room being the robot's at ``h``: its
        distinctive matches at its pose (:func:`distinct_only`), each object's at most
        ``identity_cap_nats`` (:func:`identity_evidence`; ``objects``: whose, default
        ``h``'s), as the picture's. A scan's lines speak only against it
        (:meth:`Hypothesis.update_lines`)."""
        if not isinstance(evidence, PictureMatches) or evidence.distinct.shape[0] == 0:
            return 0.0
        return identity_evidence(
            evidence, h.pose, self.tun, h.objects if objects is None else objects
        )

    def _propose(self, m: PictureMatches) -> None:
        """New hypotheses where the pictures put the robot, unless one explains them.

        The picture's own PnP proposes; while no hypothesis is probable, so do the pooled
        matches of the recent pictures taken near here (a two-point planar RANSAC,
        :func:`naoloc.mapping.planar_ransac.planar_hypotheses`), which finds a pose no
        single picture has enough matches for.
        """
        proposals: list[np.ndarray] = []
        if m.proposal is not None:
            proposals.append(m.proposal)
        proposals += self._pooled()
        for i, z in enumerate(proposals):
            anchor = m if i == 0 and m.proposal is not None else None
            self._add(z, anchor, None)
            # The walls place the robot better than the landmarks: the poses the lines
            # allow near this one, at its heading, stand beside it.
            for w in self._line_poses(near=z):
                self._add(w, None, self._line_cov)

    def _explore(self, at_rest: bool = True) -> None:
        """Neighbours of the leading hypotheses along the walls' axes, where the pictures
        agree better (a line of furniture in front of a wall, taken for the wall, puts a
        hypothesis a bench's depth off; its landmarks then fit better a step away).

        Each leader's pose is shifted by :data:`self.tun.explore_steps_m` along the wall frame's x
        and y; a shift whose pictures' evidence beats the leader's own by
        ``explore_margin_nats`` becomes a hypothesis. At rest (``at_rest``), even where the
        leader's spread covers it: the leader cannot walk there itself, as its pictures'
        matches are the robust model's outliers where it stands (pruning keeps the better
        of the two). While walking, only outside it: the window's pictures were taken
        along the walk, their quick score carries its odometry error, and a neighbour the
        leader covers handed a carried robot's lead to a wrong place (RESULTS, stop 54).
        """
        if self.walls is None:
            return
        ux = np.array([math.cos(self.walls.frame.theta), math.sin(self.walls.frame.theta)])
        axes = (ux, np.array([-ux[1], ux[0]]))
        for h in sorted(self.hypotheses, key=lambda h: -h.score)[: self.tun.explore_from]:
            own = self._quick_score(h.pose)
            best, best_z = own + self.tun.explore_margin_nats, None
            for axis in axes:
                for step in self.tun.explore_steps_m:
                    z = h.pose.copy()
                    z[:2] += step * axis
                    score = self._quick_score(z)
                    if score > best:
                        best, best_z = score, z
            if best_z is not None:
                self._add(best_z, None, self._line_cov, beside=h if at_rest else None)

    def _probable(self) -> bool:
        """Whether the best hypothesis outweighs the others and the other room."""
        b = self.belief()
        return b.pose is not None and b.probability >= self.tun.confident

    def _pooled(self) -> list[np.ndarray]:
        """Poses the pooled matches of the window's pictures taken near here agree on."""
        assert self.odometry is not None
        mats, pts, px = [], [], []
        for evidence, odo in self.window:
            if not isinstance(evidence, PictureMatches) or evidence.matched.shape[0] == 0:
                continue
            step = self.step_of(self.odometry, odo)
            if math.hypot(step[0], step[1]) > self.tun.pool_m:
                continue
            to_pic = np.linalg.inv(robot_matrix(*step))  # now-frame point -> picture's frame
            mat = evidence.projection @ to_pic
            mats.append(np.repeat(mat[None], evidence.matched.shape[0], axis=0))
            pts.append(evidence.matched)
            px.append(evidence.matched_pixels)
        if not mats or sum(len(p) for p in pts) < self.tun.min_pnp_inliers:
            return []
        found = planar_hypotheses(
            np.concatenate(mats), np.concatenate(pts), np.concatenate(px),
            bearing_tol_rad=self.tun.pool_bearing_rad, samples=self.tun.pool_samples,
            keep=self.tun.pool_keep,
            seed=len(self.window),
        )  # fmt: skip
        return [pose for count, pose in found if count >= self.tun.min_pnp_inliers]

    def _spawn(
        self, z: np.ndarray, anchor: PictureMatches | None, cov: np.ndarray | None = None
    ) -> Hypothesis | None:
        """A hypothesis at ``z`` (now), scored on the window so that its score counts the
        same observations as the others' (with the same forgetting).

        ``anchor`` (the picture that proposed it, the window's latest) corrects it first;
        then every earlier observation taken from (nearly) here corrects it too, and those
        taken elsewhere only score it, at the pose the odometry carries it back to. None
        when no observation supports it.
        """
        assert self.odometry is not None
        h = Hypothesis(z, self._proposal_cov if cov is None else cov, self.tun)
        keep = 1.0 - self.tun.forget_per_observation
        kept = 1.0 - self.tun.identity_forget_per_picture
        events = list(self.window)
        score = seen = 0.0
        shown = 0  # pictures scored so far (the identity ages by pictures only)
        if anchor is not None:
            score = h.update_picture(anchor, self.tun).evidence
            seen = self._identity(h, anchor)
            shown = 1
            events = events[:-1]
        for age, (evidence, odo) in enumerate(reversed(events), start=1 if anchor else 0):
            step = self.step_of(self.odometry, odo)
            near = (
                math.hypot(step[0], step[1]) < self.tun.near_m and abs(step[2]) < self.tun.near_rad
            )
            probe = h if near else Hypothesis(*motion_step(h.pose, h.cov, step, self.tun), self.tun)
            gain, against = self._update(probe, evidence)
            score += keep**age * gain
            if isinstance(evidence, PictureMatches):
                seen += kept**shown * self._identity(probe, evidence, h.objects)
                shown += 1
            else:
                seen += kept**shown * against
        if h.support + h.line_support == 0:
            return None
        h.score, h.seen_score = score, seen
        return h

    def _prune(self) -> None:
        hs = sorted(self.hypotheses, key=lambda h: -h.score)
        kept: list[Hypothesis] = []
        for h in hs:
            if kept and h.score < kept[0].score - self.tun.prune_nats:
                continue
            same = [k for k in kept if k.mahalanobis(h.pose, h.cov) < self.tun.merge_mahalanobis]
            if same:
                # The same place as a better hypothesis: what the pictures showed of the
                # room there stays with it (a hypothesis spawned from the window knows less).
                if h.seen_score > same[0].seen_score:
                    same[0].seen_score, same[0].objects = h.seen_score, h.objects
                continue
            kept.append(h)
            if len(kept) >= self.tun.max_hypotheses:
                break
        self.hypotheses = kept

    def belief(self) -> Belief:
        """The best hypothesis and how much the evidence favours it."""
        null = self.tun.null_nats
        if not self.hypotheses:
            return Belief(
                None, None, 0.0, 1.0, 0, 0, 0.0, 0.0, self.pictures, self.contradicted,
                self.room_seen,
            )  # fmt: skip
        # Which place of the map: every observation's evidence. Whether the map's room at
        # all: the pictures', and lines only against it (any room's walls give floor lines
        # a corner can fit; only the mapped room's keep them inside its walls).
        scores = np.array([h.score for h in self.hypotheses])
        weights = np.exp(scores - scores.max())
        weights /= weights.sum()
        best = int(np.argmax(scores))
        # The room's evidence is the places' by their weight (log of the weighted mean of
        # exp(seen)): a new place the window spawned knows less of the room than an old one.
        # What probable places showed of the room before (room_seen) still speaks for it: a
        # robot that lost its place, or was carried, is still in the room it recognised
        # (decide still wants the place's own pictures to have shown it).
        seens = np.array([h.seen_score for h in self.hypotheses])
        top = float(seens.max())
        seen = top + math.log(max(1e-300, float(np.sum(weights * np.exp(seens - top)))))
        seen = max(seen, self.room_seen)
        other = 1.0 / (1.0 + math.exp(min(700.0, max(-700.0, seen - null))))
        weights = np.append(weights * (1.0 - other), other)
        h = self.hypotheses[best]
        # Each hypothesis' pose less the best's, heading wrapped.
        deltas = []
        for g in self.hypotheses:
            d = g.pose - h.pose
            d[2] = math.remainder(float(d[2]), 2 * math.pi)
            deltas.append(d)
        # The belief's spread about the best pose: its own covariance, the hypotheses near
        # it by their weight (moment matching), and the map's irreducible error.
        cov = h.cov.copy()
        near = 0.0
        spread = np.zeros((3, 3))
        for w, g, d in zip(weights[:-1], self.hypotheses, deltas, strict=True):
            if g is h or w < 1e-6:
                continue
            spread += w * (g.cov + np.outer(d, d))
            near += w
        if near > 0:
            cov = (weights[best] * cov + spread) / (weights[best] + near)
        cov = cov + np.diag([self.map_floor_m**2] * 2 + [self.tun.map_floor_rad**2])
        # How concentrated the belief is: the weight of the places inside its own 99 %
        # region about the best pose (the reported spread covers them), not the best
        # hypothesis' alone: two hypotheses a centimetre apart are one place.
        inv = np.linalg.inv(cov)
        mass = 0.0
        for w, g, d in zip(weights[:-1], self.hypotheses, deltas, strict=True):
            if g is h or float(d @ inv @ d) <= CHI2_3DOF_99:
                mass += float(w)
        return Belief(
            h.pose.copy(),
            cov,
            mass,
            float(weights[-1]),
            len(self.hypotheses),
            h.support,
            h.score,
            h.seen_score,
            self.pictures,
            self.contradicted,
            self.room_seen,
        )

    def set_pose(self, pose: np.ndarray, cov: np.ndarray, score: float) -> None:
        """Start from a known pose (e.g. the survey's start), with ``score`` nats behind it."""
        self.hypotheses = [Hypothesis(pose, cov, self.tun, score)]

    @staticmethod
    def sigma(cov: np.ndarray) -> tuple[float, float]:
        """Position std (m, the larger axis) and heading std (rad) of a covariance."""
        pos = float(np.sqrt(max(np.linalg.eigvalsh(cov[:2, :2]).max(), 0.0)))
        return pos, math.sqrt(max(float(cov[2, 2]), 0.0))
