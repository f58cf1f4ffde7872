"""Odometry and visual fixes fused by a particle filter (Monte Carlo localization).

The paper's first item of future work: fuse the robot's odometry with what its camera
recognises. The filter keeps ``N`` weighted pose hypotheses in the map frame (metres,
radians). Between pictures it moves every particle by the odometry step, with noise at a
real NAO's magnitudes (see :class:`MotionNoise`); a visual fix (a pose from the map with its
uncertainty) re-weights them with a Gaussian likelihood mixed with an outlier floor, so one
wrong fix (a look-alike picture) does not destroy the belief. When two fixes in a row disagree
with every particle but agree with each other over the odometry between them (a kidnapped
robot, or a wrong start), it injects particles drawn around the fix and over the whole floor,
as augmented MCL does (Thrun, Burgard and Fox, *Probabilistic Robotics*, ch. 8.3.5), and
weighs them by that fix, so it recovers in that update.

Everything random takes a seed; the same seed and inputs give the same belief.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from naoloc.geometry import Pose2D, modulo2PI, wrap_angles

# Fixes in a row the belief does not explain (and that agree with each other) before the
# belief is drawn afresh: MISSES_TO_RECOVER when the robot walked at least RECOVER_WALK_M
# between the first and the last of them, else MISSES_STILL. From one spot a look-alike
# (two copies of a print 0.5 m apart) answers the same wrong way every time; a wrong belief
# shows over a walk.
MISSES_TO_RECOVER = 2
MISSES_STILL = 4
RECOVER_WALK_M = 0.3
# Gate of a fix, in standard deviations (position and heading together).
GATE_SIGMAS = 4.0
# A fix explains the belief when at least this share of its weight lies within the gate;
# less is a disagreement. A belief that drifted off (room 1995159885's go-home: spread
# 0.6-1.4 m, 0.8-1.0 m from fixes that agreed with each other and with the truth to 0.1 m)
# kept 0.1-0.5 % of its weight near them: such a fix re-weighted it a little, did not move
# it, and reset the count of disagreements, so it never recovered.
EXPLAINED_MIN = 0.05
# The belief's pose is the mean of the particles within this radius (m) of the densest place,
# so particles elsewhere (injected, or on a look-alike place) do not drag it between modes.
MODE_RADIUS_M = 0.5
MODE_CELL_M = 0.25  # grid cell of the density search, m
# A fix without PnP inliers (the keyframe fallback) errs 0.7-4.5 m and 0.1-1.7 rad (median
# 1.5 m, 0.7 rad: go-home rounds in rooms 913 and 2718, and the anywhere protocol); its
# uncertainty says so, so it nudges a lost belief but cannot drag a tracked one.
FALLBACK_SIGMA_M = 1.5
FALLBACK_SIGMA_RAD = 1.0
# A pose from the floor-wall lines (method floorlines): the lines place a wall to 1-4 cm, but
# the candidate chosen may be a wrong one.
FLOOR_SIGMA_M = 0.2
FLOOR_SIGMA_RAD = 0.1
# A floor-line pose that won its vote clearly (support at least FLOOR_SURE_SUPPORT and
# FLOOR_SURE_MARGIN times its best distinct rival, both coordinates from lines). Over 184
# floor-line poses of the twelfth step's runs (21 rooms, fresh, dim, one-art, lab-sized,
# random): 142 such, median 0.024 m, p90 0.048 m, 2 beyond 0.15 m (0.16, 0.80 m); the 42
# others median 0.029 m, p90 0.14 m, 4 beyond 0.15 m (up to 4.7 m).
FLOOR_SURE_SIGMA_M = 0.06
FLOOR_SURE_SIGMA_RAD = 0.05
FLOOR_SURE_SUPPORT = 40
FLOOR_SURE_MARGIN = 4.0

FreeTest = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""``free(xs, ys) -> bool array``: which map-frame positions (m) are free floor."""


@dataclass(frozen=True)
class MotionNoise:
    """Odometry noise of a walking NAO per step (standard deviations).

    Defaults follow the magnitudes practitioners budget for a NAO's odometry (Hornung's
    humanoid_navigation NAO config: about 0.15 per metre in x/y and 0.8 rad per metre in
    yaw as variances; B-Human's self-locator: 20 % of translation, 30 % of rotation). We take
    values between those budgets.

    Attributes:
        trans_per_m: Translation noise, fraction of the distance walked.
        trans_per_sqrt_m: Translation noise growing with sqrt(distance), m/sqrt(m).
        rot_per_rad: Rotation noise, fraction of the angle turned.
        rot_per_m: Rotation noise per metre walked, rad/m.
        floor_m: Translation noise of any step, however short, m.
        floor_rad: Rotation noise of any step, rad.
        stall_share: Share of particles that take a walk to have been blocked (a NAO pushing
            against a chair keeps counting steps it never makes): they move only a random
            part of the step, up to ``stall_progress``. Then fixes that show the robot stuck
            are explained, and the belief follows them.
        stall_progress: Largest share of a blocked step that is made.
    """

    trans_per_m: float = 0.12
    trans_per_sqrt_m: float = 0.05
    rot_per_rad: float = 0.2
    rot_per_m: float = 0.1
    floor_m: float = 0.002
    floor_rad: float = 0.002
    stall_share: float = 0.1
    stall_progress: float = 0.3


@dataclass(frozen=True)
class Fix:
    """A visual pose fix in the map frame with its uncertainty.

    Attributes:
        pose: The pose the map gives (m, m, rad).
        sigma_xy_m: Standard deviation of the position, m.
        sigma_theta_rad: Standard deviation of the heading, rad.
        alternatives: Other poses the same pictures support nearly as well (a repeated
            print); the fix is then a mixture, and the odometry picks the mode.
        verified: The floor-wall lines confirmed it (a PnP pose one of the lines' poses
            is near, and no alternative): two independent measurements agree.
    """

    pose: Pose2D
    sigma_xy_m: float
    sigma_theta_rad: float
    alternatives: tuple[Pose2D, ...] = ()
    verified: bool = False

    def modes(self) -> tuple[Pose2D, ...]:
        """The pose and its alternatives."""
        return (self.pose, *self.alternatives)


@dataclass(frozen=True)
class Belief:
    """The filter's summary: mean pose, covariance and how concentrated it is.

    Attributes:
        pose: Weighted mean (circular mean for the heading), map frame.
        covariance: 3 x 3 covariance of (x, y, theta) in m^2, m rad, rad^2.
        effective_particles: ``1 / sum(w^2)``; small after a sharp update.
        spread_m: sqrt of the larger positional eigenvalue, m.
    """

    pose: Pose2D
    covariance: np.ndarray
    effective_particles: float
    spread_m: float

    def to_json(self) -> dict[str, object]:
        """JSON-able fields: covariance as nested lists, rounded."""
        return {
            "covariance": [[round(float(v), 6) for v in row] for row in self.covariance],
            "spread_m": round(self.spread_m, 4),
        }


def fix_from_confidence(pose: Pose2D, confidence: float, inliers: int | None = None) -> Fix:
    """A visual fix's uncertainty from the map's confidence (and PnP inliers when known).

    A PnP pose over many inliers is good to a few centimetres, and its standard deviation
    shrinks with the square root of the inliers. A keyframe-only fallback is good to a metre
    or two (:data:`FALLBACK_SIGMA_M`, a little more at low confidence).

    Args:
        pose: The estimate, map frame.
        confidence: The map's confidence in [0, 1].
        inliers: PnP inliers behind the estimate, when it came from PnP.
    """
    if inliers is not None and inliers > 0:
        sigma = max(0.02, 0.4 / math.sqrt(inliers))
        return Fix(pose, sigma, max(0.02, 0.5 / math.sqrt(inliers)))
    c = min(max(confidence, 1e-3), 1.0)
    unsure = 1.0 + 0.5 * (1.0 - c)
    return Fix(pose, FALLBACK_SIGMA_M * unsure, FALLBACK_SIGMA_RAD * unsure)


def fix_from_estimate(estimate: Any) -> Fix:
    """The fix a map estimate gives (:func:`fix_from_confidence`; PnP inliers when it has them;
    :data:`FLOOR_SIGMA_M`, or :data:`FLOOR_SURE_SIGMA_M` after a clear vote, for a pose from
    the floor lines).

    Args:
        estimate: A found :class:`naoloc.mapping.Estimate` (map frame).
    """
    if estimate.method == "floorlines":
        return Fix(estimate.pose(), *_floor_sigmas(estimate.details))
    inliers = estimate.details.get("inliers") if estimate.method == "pnp" else None
    fix = fix_from_confidence(estimate.pose(), estimate.confidence, inliers)
    others = (estimate.details.get("alternatives") or []) if inliers is not None else []
    alternatives = tuple(Pose2D(float(a[0]), float(a[1]), float(a[2])) for a in others)
    if alternatives:
        return replace(fix, alternatives=alternatives)
    if inliers is not None and estimate.details.get("floor_confirmed"):
        return replace(fix, verified=True)
    return fix


def _floor_sigmas(details: dict[str, Any]) -> tuple[float, float]:
    """A floor-line pose's standard deviations (m, rad): :data:`FLOOR_SURE_SIGMA_M` when its
    vote was clear (:data:`FLOOR_SURE_SUPPORT`, :data:`FLOOR_SURE_MARGIN`, no coordinate from
    the landmarks' bearings), else :data:`FLOOR_SIGMA_M`."""
    support = int(details.get("floor_support") or 0)
    rival = int(details.get("floor_rival") or 0)
    sure = (
        support >= FLOOR_SURE_SUPPORT
        and support >= FLOOR_SURE_MARGIN * max(rival, 1)
        and details.get("floor_axis_from") is None
    )
    return (FLOOR_SURE_SIGMA_M, FLOOR_SURE_SIGMA_RAD) if sure else (FLOOR_SIGMA_M, FLOOR_SIGMA_RAD)


class ParticleFilter:
    """Monte Carlo localization over odometry steps and visual fixes (map frame).

    Args:
        particles: Number of particles.
        seed: Seed of every random draw.
        bounds: ``(xmin, ymin, xmax, ymax)`` of the floor, map frame (m); used to draw
            particles anywhere when the robot is lost.
        free: Optional test of free floor (furniture, walls): particles that land off it after
            a step lose their weight, and injected ones are drawn on it.
        noise: Odometry noise model.
        outlier: Probability that a fix is unrelated to the true pose (look-alike places).
    """

    def __init__(
        self,
        particles: int = 2000,
        *,
        seed: int = 0,
        bounds: tuple[float, float, float, float] = (-5.0, -5.0, 5.0, 5.0),
        free: FreeTest | None = None,
        noise: MotionNoise = MotionNoise(),
        outlier: float = 0.1,
    ) -> None:
        """A filter with every particle drawn uniformly over ``bounds`` (a global start)."""
        if particles < 10:
            raise ValueError(f"a particle filter needs at least 10 particles, got {particles}")
        self._rng = np.random.default_rng(np.random.SeedSequence([seed, 0xF11]))
        self._n = particles
        self._bounds = bounds
        self._free = free
        self._noise = noise
        self._outlier = outlier
        self.misses = 0
        # The last fix the belief did not explain, carried by odometry since, and its sigmas.
        self._missed: tuple[Pose2D, float, float] | None = None
        self._walked_since_miss = 0.0  # odometry distance since the first of those fixes, m
        self.states = self._uniform(particles)
        self.weights = np.full(particles, 1.0 / particles)
        self.fixes = 0

    # ------------------------------------------------------------------ set-up
    def _uniform(self, n: int) -> np.ndarray:
        x0, y0, x1, y1 = self._bounds
        out = np.empty((0, 3))
        for _ in range(50):  # rejection sampling on the free floor
            cand = np.column_stack(
                [
                    self._rng.uniform(x0, x1, 2 * n),
                    self._rng.uniform(y0, y1, 2 * n),
                    self._rng.uniform(-math.pi, math.pi, 2 * n),
                ]
            )
            if self._free is not None:
                cand = cand[self._free(cand[:, 0], cand[:, 1])]
            out = np.vstack([out, cand])
            if len(out) >= n:
                return out[:n]
        raise ValueError("the filter's bounds hold almost no free floor")

    def reset_to(self, fix: Fix) -> None:
        """Forget the belief and draw every particle around a fix (a known start).

        A fix with alternatives shares the particles among its modes.
        """
        modes = fix.modes()
        counts = [self._n // len(modes)] * len(modes)
        counts[0] += self._n - sum(counts)
        parts = zip(modes, counts, strict=True)
        self.states = np.vstack([self._around(replace(fix, pose=m), k) for m, k in parts])
        self.weights = np.full(self._n, 1.0 / self._n)

    def _around(self, fix: Fix, n: int) -> np.ndarray:
        s = np.column_stack(
            [
                self._rng.normal(fix.pose.x, fix.sigma_xy_m, n),
                self._rng.normal(fix.pose.y, fix.sigma_xy_m, n),
                self._rng.normal(fix.pose.theta, fix.sigma_theta_rad, n),
            ]
        )
        s[:, 2] = wrap_angles(s[:, 2])
        return s

    # ------------------------------------------------------------------ motion
    def predict(self, step: Pose2D) -> None:
        """Move every particle by an odometry step (expressed in the robot frame).

        Args:
            step: ``pose2DInverse(odo_before) * odo_after``, FRAME_ROBOT of the step start.
        """
        d = math.hypot(step.x, step.y)
        nz = self._noise
        s_t = nz.floor_m + nz.trans_per_m * d + nz.trans_per_sqrt_m * math.sqrt(d)
        s_r = nz.floor_rad + nz.rot_per_rad * abs(step.theta) + nz.rot_per_m * d
        n = self._n
        # Each particle's own odometry error: a distance scale, a lateral slip and a turn.
        dx = step.x + self._rng.normal(0.0, s_t, n) * (step.x / d if d > 0 else 1.0)
        dy = step.y + self._rng.normal(0.0, s_t, n) * (step.y / d if d > 0 else 1.0)
        dx += self._rng.normal(0.0, 0.5 * s_t, n) * (-step.y / d if d > 0 else 0.0)
        dy += self._rng.normal(0.0, 0.5 * s_t, n) * (step.x / d if d > 0 else 0.0)
        dth = step.theta + self._rng.normal(0.0, s_r, n)
        if nz.stall_share > 0 and d > 0:
            stalled = self._rng.random(n) < nz.stall_share
            part = np.where(stalled, self._rng.uniform(0.0, nz.stall_progress, n), 1.0)
            dx, dy = dx * part, dy * part
        if self._missed is not None:
            pose, sxy, sth = self._missed
            self._missed = (pose * step, math.hypot(sxy, s_t), math.hypot(sth, s_r))
            self._walked_since_miss += d
        th = self.states[:, 2]
        c, s = np.cos(th), np.sin(th)
        self.states[:, 0] += c * dx - s * dy
        self.states[:, 1] += s * dx + c * dy
        self.states[:, 2] = wrap_angles(th + dth)
        if self._free is not None:
            ok = self._free(self.states[:, 0], self.states[:, 1])
            if ok.any():
                self.weights = np.where(ok, self.weights, 0.0)
                self.weights /= self.weights.sum()

    # ------------------------------------------------------------------ vision
    def _likelihood(self, fix: Fix) -> np.ndarray:
        g = np.exp(
            -0.5 * self._sq_sigmas(fix, self.states[:, 0], self.states[:, 1], self.states[:, 2])
        )
        return np.asarray((1.0 - self._outlier) * g + self._outlier * 1e-3)

    def update(self, fix: Fix) -> None:
        """Weigh the particles by a visual fix, then resample (with recovery injection).

        A fix the belief does not explain (less than :data:`EXPLAINED_MIN` of its weight
        within a :data:`GATE_SIGMAS` gate of it) is a disagreement; one alone is taken for a
        look-alike place and only re-weights.
        When :data:`MISSES_TO_RECOVER` disagreements in a row agree with each other (the
        earlier one carried by the odometry since, its uncertainty grown by the motion
        noise) and the robot walked :data:`RECOVER_WALK_M` between them (else
        :data:`MISSES_STILL` of them), or at once when the fix was verified by the floor
        lines, the belief is taken to be wrong (a kidnapped robot, a wrong start): half the
        particles are drawn afresh, around the fix and over the whole floor, and all are
        weighed by the fix, so the belief moves to it in this update.

        Args:
            fix: The map's pose and its uncertainty, map frame.
        """
        gate = self._gate(fix, self.states[:, 0], self.states[:, 1], self.states[:, 2])
        explained = float(np.sum(self.weights * gate))
        self.fixes += 1
        recover = False
        if explained >= EXPLAINED_MIN:
            self.misses, self._missed = 0, None
        else:
            agrees = self._missed is None or self._agrees(fix, self._missed)
            self.misses = self.misses + 1 if agrees else 1
            if self.misses == 1:
                self._walked_since_miss = 0.0
            self._missed = (fix.pose, fix.sigma_xy_m, fix.sigma_theta_rad)
            walked = self._walked_since_miss >= RECOVER_WALK_M
            needed = MISSES_TO_RECOVER if walked else MISSES_STILL
            # A fix the floor lines verified recovers at once: the lines and the landmarks
            # agree on it, which a look-alike print alone does not make happen (of 420
            # anywhere localizations, 2 verified poses were wrong). Room 1995159885's
            # go-home: beliefs 0.4-0.6 m off after a walk ignored verified fixes 1-10 cm
            # from the truth, declared the robot home 0.42 m from it, or ran out of walks.
            if fix.verified or self.misses >= needed:
                recover = True
                self.misses, self._missed = 0, None
        like = self._likelihood(fix)
        if not recover and float(np.sum(self.weights * like)) <= 0:
            recover = True
        if recover:  # the prior becomes the old belief and fresh draws, then weighed by the fix
            self._resample(0.5, fix)
        w = self.weights * (self._likelihood(fix) if recover else like)
        total = float(w.sum())
        self.weights = w / total if total > 0 else np.full(self._n, 1.0 / self._n)
        self._resample(0.0, fix)

    @staticmethod
    def _sq_sigmas(fix: Fix, x: Any, y: Any, theta: Any) -> Any:
        """Squared distance (in the fix's sigmas, position and heading) to its nearest mode."""
        out = np.full(np.shape(x), np.inf)
        for mode in fix.modes():
            d2 = (x - mode.x) ** 2 + (y - mode.y) ** 2
            dth = wrap_angles(np.asarray(theta) - mode.theta)
            out = np.minimum(out, d2 / fix.sigma_xy_m**2 + dth**2 / fix.sigma_theta_rad**2)
        return out

    @staticmethod
    def _gate(fix: Fix, x: Any, y: Any, theta: Any) -> Any:
        return ParticleFilter._sq_sigmas(fix, x, y, theta) < GATE_SIGMAS**2

    @staticmethod
    def _agrees(fix: Fix, missed: tuple[Pose2D, float, float]) -> bool:
        """Whether a fix agrees with an earlier one carried by odometry (their sigmas summed)."""
        pose, sxy, sth = missed
        both = Fix(pose, math.hypot(sxy, fix.sigma_xy_m), math.hypot(sth, fix.sigma_theta_rad))
        return bool(ParticleFilter._gate(both, fix.pose.x, fix.pose.y, fix.pose.theta))

    def _resample(self, inject: float, fix: Fix) -> None:
        n = self._n
        fresh = round(inject * n)
        keep = n - fresh
        # Low-variance (systematic) resampling of the kept share.
        positions = (self._rng.random() + np.arange(keep)) / keep
        idx = np.minimum(np.searchsorted(np.cumsum(self.weights), positions), n - 1)
        parts = [self.states[idx]]
        if fresh:
            near = fresh // 2
            parts.append(
                self._around(Fix(fix.pose, 2 * fix.sigma_xy_m, 2 * fix.sigma_theta_rad), near)
            )
            parts.append(self._uniform(fresh - near))
        self.states = np.vstack(parts)
        self.weights = np.full(n, 1.0 / n)

    # ------------------------------------------------------------------ output
    def belief(self) -> Belief:
        """The pose of the densest place, the covariance about it and the particle spread.

        The pose is the weighted mean (circular for the heading) of the particles within
        :data:`MODE_RADIUS_M` of the densest :data:`MODE_CELL_M` cell, so a belief split
        between two places reports one of them, not a point between them. The covariance
        and the spread are taken about that pose over every particle, so such a split shows
        as a large spread.
        """
        w, st = self.weights, self.states
        x0, y0 = float(np.min(st[:, 0])), float(np.min(st[:, 1]))
        ix = ((st[:, 0] - x0) / MODE_CELL_M).astype(np.int64)
        iy = ((st[:, 1] - y0) / MODE_CELL_M).astype(np.int64)
        cells = np.zeros((int(ix.max()) + 1, int(iy.max()) + 1))
        np.add.at(cells, (ix, iy), w)
        bx, by = np.unravel_index(int(np.argmax(cells)), cells.shape)
        cx = x0 + (float(bx) + 0.5) * MODE_CELL_M
        cy = y0 + (float(by) + 0.5) * MODE_CELL_M
        for _ in range(2):  # two mean-shift steps from the densest cell's centre
            near = np.hypot(st[:, 0] - cx, st[:, 1] - cy) <= MODE_RADIUS_M
            wn = w * near
            if float(wn.sum()) <= 0:
                break
            cx = float(np.sum(wn * st[:, 0]) / wn.sum())
            cy = float(np.sum(wn * st[:, 1]) / wn.sum())
        near = np.hypot(st[:, 0] - cx, st[:, 1] - cy) <= MODE_RADIUS_M
        wn = w * near if float(np.sum(w * near)) > 0 else w
        th = math.atan2(float(np.sum(wn * np.sin(st[:, 2]))), float(np.sum(wn * np.cos(st[:, 2]))))
        dev = np.column_stack([st[:, 0] - cx, st[:, 1] - cy, wrap_angles(st[:, 2] - th)])
        cov = (dev * w[:, None]).T @ dev
        spread = math.sqrt(max(0.0, float(np.linalg.eigvalsh(cov[:2, :2]).max())))
        return Belief(Pose2D(cx, cy, modulo2PI(th)), cov, 1.0 / float(np.sum(w**2)), spread)
