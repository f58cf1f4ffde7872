"""One hypothesis of the filter: a Gaussian pose tracked by an extended Kalman filter.

As in B-Human's self-locator, each hypothesis is a pose ``(x, y, theta)`` (map frame, m
and rad) with a covariance, moved by the odometry and corrected by each observation it
explains:

- floor-wall lines: each line is associated with the wall that explains it best
  (Mahalanobis gate) and corrects the pose like a range-bearing measurement;
- a picture: its landmark candidates are fitted by iteratively reweighted Gauss-Newton
  started at the hypothesis (a candidate's weight is the posterior probability that it is
  the feature's landmark, :func:`naoloc.localization.pictures.mixture`), so a wrong match
  or a wrong hypothesis simply finds no support.

The map's landmarks are off by a few centimetres where they stand (the survey's
triangulation), and every picture of the same place shares that error: ten pictures are
not ten times better than one. The state therefore carries that shared error as well, a
bias ``b = (bx, by, btheta)`` of where the landmarks put the robot (prior
``landmark_sigma_*``, fading as the robot walks on to other landmarks): pictures see
``pose + b``, lines see ``pose``. Only the lines (the walls, placed to 1-4 cm) can then
make a pose better than the landmarks' own error, and the covariance says so.

Each update also returns the evidence (nats over clutter) the observation gives the
hypothesis before it corrects it; the filter ranks hypotheses by it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from naoloc.config import FilterTuning
from naoloc.localization.pictures import (
    PictureMatches,
    RoomObjects,
    mixture,
    reprojection,
)
from naoloc.localization.walls import WallMap, fit_line
from naoloc.perception.floorline import WallLine

__all__ = ["Hypothesis", "PictureFit", "motion_step", "predictive_evidence", "wrap"]


def wrap(angle: float) -> float:
    """``angle`` wrapped to (-pi, pi]."""
    return math.atan2(math.sin(angle), math.cos(angle))


def _step_matrices(
    pose: np.ndarray, step: np.ndarray, tun: FilterTuning
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """The moved pose, the Jacobian F, the noise Q of an odometry step, and its extent."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy, dt = (float(v) for v in step)
    new = np.array([pose[0] + c * dx - s * dy, pose[1] + s * dx + c * dy, wrap(pose[2] + dt)])
    dist = math.hypot(dx, dy)
    f = np.array([[1.0, 0.0, -s * dx - c * dy], [0.0, 1.0, c * dx - s * dy], [0.0, 0.0, 1.0]])
    if dist < 1e-5 and abs(dt) < 1e-5:
        return new, f, np.zeros((3, 3)), 0.0
    # The distance's error, and the feet's slip while turning (a random walk per radian).
    st = math.sqrt((tun.trans_per_m * dist + tun.floor_m) ** 2 + tun.slip_per_sqrt_rad**2 * abs(dt))
    sr = tun.rot_per_rad * abs(dt) + tun.rot_per_m * dist + tun.floor_rad
    g = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    q = g @ np.diag([st**2, st**2, sr**2]) @ g.T
    return new, f, q, dist + abs(dt) / math.pi


def motion_step(
    pose: np.ndarray, cov: np.ndarray, step: np.ndarray, tun: FilterTuning
) -> tuple[np.ndarray, np.ndarray]:
    """A pose and its 3 x 3 covariance moved by an odometry step (FRAME_ROBOT: dx, dy m,
    dtheta rad).

    The step's noise grows with the distance and the turn (a NAO's odometry: about 12 %
    of the distance, 20 % of the turn, 0.1 rad per metre of heading, and 2 cm of position
    per square root of a radian turned: the feet slip, in place too); a step of no motion
    adds none.
    """
    new, f, q, _ = _step_matrices(pose, step, tun)
    return new, f @ cov @ f.T + q


def _delta(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a - b`` with the heading difference (index 2) wrapped."""
    d = a - b
    d[2] = wrap(float(d[2]))
    return d


def bias_prior(tun: FilterTuning) -> np.ndarray:
    """The 3 x 3 prior covariance of the landmarks' shared error (m, m, rad)."""
    return np.diag([tun.landmark_sigma_m**2, tun.landmark_sigma_m**2, tun.landmark_sigma_rad**2])


def predictive_evidence(
    m: PictureMatches, pose: np.ndarray, cov: np.ndarray, tun: FilterTuning
) -> float:
    """A picture's evidence (nats over 'all wrong') for a pose known to ``cov`` (3 x 3,
    the landmarks' error included), without correcting it."""
    if m.points.shape[0] == 0:
        return 0.0
    res, front, jac = reprojection(m, pose, jacobian=True)
    assert jac is not None
    s = jac @ cov @ jac.transpose(0, 2, 1) + tun.pixel_sigma_px**2 * np.eye(2)
    _, ratios = mixture(m, res, front, s, tun)
    return min(tun.picture_evidence_cap_nats, tun.match_weight * float(ratios.sum()))


@dataclass
class PictureFit:
    """What one picture said about one hypothesis.

    Attributes:
        inliers: Features the corrected pose explains (posterior weight above one half).
        evidence: Nats over clutter the picture gives the hypothesis before it corrects
            it (each feature's predictive density, widened by the pose's uncertainty;
            capped).
        updated: Whether the picture corrected the hypothesis.
    """

    inliers: int
    evidence: float
    updated: bool


class Hypothesis:
    """A Gaussian pose hypothesis with the landmarks' shared error.

    Args:
        pose: ``(x, y, theta)``, map frame (m, rad).
        cov: ``(3, 3)`` covariance of the pose.
        tun: The filter's tuning (the landmarks' error prior).
        score: Evidence so far, nats over clutter (discounted, see the filter).
    """

    def __init__(
        self, pose: np.ndarray, cov: np.ndarray, tun: FilterTuning, score: float = 0.0
    ) -> None:
        self.state = np.zeros(6)
        self.state[:3] = np.asarray(pose, np.float64)
        self.full = np.zeros((6, 6))
        self.full[:3, :3] = np.asarray(cov, np.float64)
        self.full[3:, 3:] = bias_prior(tun)
        self.score = float(score)
        self.support = 0  # pictures that corrected it
        self.line_support = 0  # floor lines that corrected it
        self.last_inliers = 0
        self.seen_score = 0.0  # the pictures' part of the score (nats)
        self.objects = RoomObjects()  # the objects that gave it (one at most cap each)
        self.usual = 0.0  # slow average of its evidence per informative picture (nats)
        self.recent = 0.0  # fast average of the same (nats)

    @property
    def pose(self) -> np.ndarray:
        """``(x, y, theta)``, map frame."""
        return self.state[:3]

    @property
    def cov(self) -> np.ndarray:
        """The pose's 3 x 3 covariance."""
        return self.full[:3, :3]

    def seen_cov(self) -> np.ndarray:
        """Covariance of where the landmarks put the robot (pose plus their error)."""
        a = np.hstack([np.eye(3), np.eye(3)])
        return a @ self.full @ a.T

    def predict(self, step: np.ndarray, tun: FilterTuning) -> None:
        """Move by an odometry step (FRAME_ROBOT at the previous pose).

        The landmarks' error decorrelates as the robot walks or turns on to other ones: a
        metre (or half a turn) makes it new.
        """
        new, f, q, extent = _step_matrices(self.pose, step, tun)
        f6 = np.eye(6)
        f6[:3, :3] = f
        q6 = np.zeros((6, 6))
        q6[:3, :3] = q
        keep = max(0.0, 1.0 - min(1.0, extent))
        f6[3:, 3:] *= math.sqrt(keep)
        q6[3:, 3:] = (1.0 - keep) * bias_prior(tun)
        self.state[:3] = new
        self.state[3:] *= math.sqrt(keep)
        self.full = f6 @ self.full @ f6.T + q6

    def mahalanobis(self, pose: np.ndarray, cov: np.ndarray | None = None) -> float:
        """Mahalanobis distance of ``pose`` from this hypothesis' pose (with ``cov`` added)."""
        d = _delta(np.asarray(pose, np.float64).copy(), self.pose)
        s = self.cov + (cov if cov is not None else 0.0)
        return math.sqrt(max(0.0, float(d @ np.linalg.solve(s, d))))

    def update_lines(
        self, walls: WallMap, lines: tuple[WallLine, ...], tun: FilterTuning
    ) -> tuple[float, float]:
        """Correct the pose with floor-wall lines.

        Returns:
            The evidence (nats over clutter) the lines give the hypothesis *before* they
            correct it: each line's predictive density, widened by the pose's own
            uncertainty, so a vague hypothesis that could slide to fit gains less; at most
            ``line_evidence_cap_nats`` (one scan's lines share the walls' errors). And
            what they say against the mapped room at this pose (nats, <= 0: lines beyond
            its walls, :attr:`LineFit.log_beyond`), at most ``identity_floor_nats``.
        """
        gate = tun.gate_mahalanobis**2
        floor = np.array([tun.wall_sigma_m, tun.wall_sigma_rad]) ** 2
        evidence = 0.0
        against = 0.0
        for line in lines:
            fit = fit_line(walls, line, self.pose, tun, self.cov)
            evidence += fit.log_ratio
            against += fit.log_beyond
            if fit.wall < 0:
                continue
            r = np.diag(fit.sigma**2 + floor)
            jac = np.hstack([fit.jacobian, np.zeros((2, 3))])
            s = jac @ self.full @ jac.T + r
            innov = -fit.residual
            if float(innov @ np.linalg.solve(s, innov)) > gate:
                continue
            k = self.full @ jac.T @ np.linalg.inv(s)
            self.state = self.state + k @ innov
            self.state[2] = wrap(float(self.state[2]))
            ikh = np.eye(6) - k @ jac
            self.full = ikh @ self.full @ ikh.T + k @ r @ k.T  # Joseph form
            self.line_support += 1
        return min(tun.line_evidence_cap_nats, evidence), max(-tun.identity_floor_nats, against)

    def update_picture(self, m: PictureMatches, tun: FilterTuning) -> PictureFit:
        """Correct the pose (and the landmarks' error) with a picture's landmark candidates.

        Iteratively reweighted Gauss-Newton on the 6-D state from the hypothesis: each
        candidate's weight is its responsibility under the picture model, with the pixel
        noise widened by the state's uncertainty; the information is tempered by
        ``match_weight`` (a picture's features share its blur and lighting).
        """
        if m.points.shape[0] == 0:
            return PictureFit(0, 0.0, False)
        mu, p = self.state, self.full
        p_inv = np.linalg.inv(p)
        x = mu.copy()
        sig2 = tun.pixel_sigma_px**2
        cur = p
        h = np.zeros((6, 6))
        resp = np.zeros(m.points.shape[0])
        predictive = None
        a = np.hstack([np.eye(3), np.eye(3)])  # pose + bias: where the landmarks see it
        for _ in range(10):
            seen = a @ x
            res, front, jac3 = reprojection(m, seen, jacobian=True)
            assert jac3 is not None
            jac = np.concatenate([jac3, jac3], axis=2)
            s = jac @ cur @ jac.transpose(0, 2, 1) + sig2 * np.eye(2)
            resp, ratios = mixture(m, res, front, s, tun)
            if predictive is None:  # the evidence before the picture moves the pose
                predictive = min(
                    tun.picture_evidence_cap_nats, tun.match_weight * float(ratios.sum())
                )
            wk = tun.match_weight * resp / sig2
            h = np.einsum("n,nij,nik->jk", wk, jac, jac)
            g = np.einsum("n,nij,ni->j", wk, jac, res)
            info = p_inv + h
            step = -np.linalg.solve(info, g + p_inv @ _delta(x, mu))
            x = x + step
            x[2] = wrap(float(x[2]))
            cur = np.linalg.inv(info)
            if np.abs(step[[0, 1, 3, 4]]).sum() < 1e-5 and abs(step[2]) + abs(step[5]) < 1e-6:
                break
        per = np.bincount(m.group, weights=resp, minlength=m.features)
        inliers = int(np.sum(per > 0.5))
        evidence = float(predictive or 0.0)
        if inliers < tun.min_inliers:
            return PictureFit(inliers, evidence, False)
        self.state = x
        self.full = 0.5 * (cur + cur.T)
        self.support += 1
        self.last_inliers = inliers
        return PictureFit(inliers, evidence, True)
