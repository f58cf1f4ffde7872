"""How a NAO's walk strays from its odometry: one model for the fake and mujoco backends.

A NAO walks its footstep plan open-loop on its own odometry (ALMotion integrates the
leg joints' measured motion as if the feet never slipped), so the odometry reaches the
target and the body does not. This module turns each cycle's odometry increment (what
the legs did, in FRAME_ROBOT at the start of the cycle) into the true increment of the
body, and adds the small joint-sensor noise that separates ``getRobotPosition(True)``
(sensors) from ``getRobotPosition(False)`` (commands).

Error terms, for an odometry increment of ``ds`` metres and ``dtheta`` radians:

- distance scale: odometry reads ``1 + scale_error`` times the true distance;
- turn scale: odometry reads ``1 + turn_scale_error`` times the true turn;
- heading bias: the true heading turns ``-heading_bias_rad_per_m * ds`` against the odometry;
- position random walk: ``N(0, random_walk_m_per_sqrt_m**2 * ds + turn_slip**2 * |dtheta|)``
  on x and y (the second part: the feet slip when turning);
- heading random walk: ``N(0, heading_rw_m**2 * ds + heading_rw_rad**2 * |dtheta|)``.

Profile ``nao`` (the default) draws the three systematic terms once per run from
``world.odometry.seed`` as zero-mean Gaussians truncated at 2 std; the random terms are
fixed magnitudes.
Sources, all practitioners' published NAO figures (none of them a calibration of one
robot; where they disagree the middle is taken, not the kindest):

- Hornung et al., ``humanoid_navigation`` (humanoid_localization), NAO config: motion noise
  0.15 per metre in x/y (about 5 cm/sqrt(m)) and 0.8 per metre in yaw (about
  14 deg/sqrt(m)).
- B-Human's self-locator budgets 20 % of the translation and 30 % of the rotation.
- Aldebaran's ALVisualCompass documentation: odometry is wrong when the feet slip while
  the robot turns.
- UNSW's RoboCup visual compass cut an uncalibrated NAO's odometric uncertainty by 73 %:
  the heading is the dominant error.

Chosen (std): distance scale 10 % per run (between a calibrated walk's few per cent and
the filters' 15-20 % budgets, which include their random parts), position random walk
5 cm/sqrt(m) (Hornung's), turn scale 6 % per run plus slip 0.05 rad/sqrt(rad) turned and
2 cm/sqrt(rad) of position slip (together about 8 % of a quarter turn: between a good
walk and B-Human's 30 %), heading bias 0.02 rad/m per run and heading random walk
0.04 rad/sqrt(m) (2.3 deg/sqrt(m): Hornung's 14 deg/sqrt(m) is a filter's budget for an
unmodelled bias, which the bias term models here). Over a 2 m square walked with
``moveTo`` this gives a median end error of about 0.5 m and 15 deg (tools/odometry_square.py).

Profile ``ideal`` is exact. Every key set in :class:`naoloc.config.OdometryConfig`
overrides the profile; ``level`` multiplies every magnitude.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from naoloc.config import OdometryConfig
from naoloc.geometry import Pose2D

TRUNCATE_SIGMAS = 2.0  # per-run draws are truncated at this many std (no freak runs)


@dataclass(frozen=True, slots=True)
class ProfileMagnitudes:
    """Error magnitudes of a profile: std of the per-run terms, the random walks.

    Attributes:
        scale_error_std: Std of the per-run distance scale error (relative).
        turn_scale_error_std: Std of the per-run turn scale error (relative).
        heading_bias_std_rad_per_m: Std of the per-run heading bias, rad per metre.
        random_walk_m_per_sqrt_m: Position noise std per sqrt(metre).
        heading_random_walk_rad_per_sqrt_m: Heading noise std per sqrt(metre).
        heading_random_walk_rad_per_sqrt_rad: Heading noise std per sqrt(radian turned).
        turn_slip_m_per_sqrt_rad: Position noise std per sqrt(radian turned).
        sensor_noise_per_sqrt_m: Joint-sensor noise (m/sqrt(m) and rad/sqrt(m)) between the
            sensor odometry and the integrated commands.
    """

    scale_error_std: float
    turn_scale_error_std: float
    heading_bias_std_rad_per_m: float
    random_walk_m_per_sqrt_m: float
    heading_random_walk_rad_per_sqrt_m: float
    heading_random_walk_rad_per_sqrt_rad: float
    turn_slip_m_per_sqrt_rad: float
    sensor_noise_per_sqrt_m: float


PROFILES: dict[str, ProfileMagnitudes] = {
    "nao": ProfileMagnitudes(0.10, 0.06, 0.02, 0.05, 0.04, 0.05, 0.02, 0.002),
    "ideal": ProfileMagnitudes(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
}


@dataclass(frozen=True, slots=True)
class OdometryErrors:
    """The resolved errors of one run (the systematic terms already drawn).

    Attributes:
        scale_error: Odometry reads ``1 + scale_error`` times the true distance.
        turn_scale_error: Odometry reads ``1 + turn_scale_error`` times the true turn.
        heading_bias_rad_per_m: Odometry heading gained per metre walked, rad/m.
        random_walk_m_per_sqrt_m: Position noise std per sqrt(metre).
        heading_random_walk_rad_per_sqrt_m: Heading noise std per sqrt(metre).
        heading_random_walk_rad_per_sqrt_rad: Heading noise std per sqrt(radian turned).
        turn_slip_m_per_sqrt_rad: Position noise std per sqrt(radian turned).
        sensor_noise_per_sqrt_m: Sensor-versus-command noise std per sqrt(metre or radian).
    """

    scale_error: float
    turn_scale_error: float
    heading_bias_rad_per_m: float
    random_walk_m_per_sqrt_m: float
    heading_random_walk_rad_per_sqrt_m: float
    heading_random_walk_rad_per_sqrt_rad: float
    turn_slip_m_per_sqrt_rad: float
    sensor_noise_per_sqrt_m: float

    @property
    def exact(self) -> bool:
        """True when every term is zero (the true walk equals the odometry)."""
        return all(v == 0.0 for v in (getattr(self, f) for f in self.__slots__))


def resolve(cfg: OdometryConfig) -> OdometryErrors:
    """The errors of one run: explicit keys, else the profile's (systematic ones drawn).

    The three systematic draws always come from ``seed`` in the same order, so setting one
    key does not change the others.

    Args:
        cfg: ``world.odometry``.

    Returns:
        The run's errors, each already multiplied by ``cfg.level``.
    """
    prof = PROFILES[cfg.profile]
    draws = np.random.default_rng([cfg.seed, 0x0D0]).standard_normal(3)
    k = cfg.level

    def pick(explicit: float | None, drawn: float) -> float:
        return k * (explicit if explicit is not None else drawn)

    z = np.clip(draws, -TRUNCATE_SIGMAS, TRUNCATE_SIGMAS)
    return OdometryErrors(
        scale_error=pick(cfg.scale_error, prof.scale_error_std * float(z[0])),
        turn_scale_error=pick(cfg.turn_scale_error, prof.turn_scale_error_std * float(z[1])),
        heading_bias_rad_per_m=pick(
            cfg.heading_bias_rad_per_m, prof.heading_bias_std_rad_per_m * float(z[2])
        ),
        random_walk_m_per_sqrt_m=pick(cfg.random_walk_m_per_sqrt_m, prof.random_walk_m_per_sqrt_m),
        heading_random_walk_rad_per_sqrt_m=pick(
            cfg.heading_random_walk_rad_per_sqrt_m, prof.heading_random_walk_rad_per_sqrt_m
        ),
        heading_random_walk_rad_per_sqrt_rad=pick(
            cfg.heading_random_walk_rad_per_sqrt_rad, prof.heading_random_walk_rad_per_sqrt_rad
        ),
        turn_slip_m_per_sqrt_rad=pick(cfg.turn_slip_m_per_sqrt_rad, prof.turn_slip_m_per_sqrt_rad),
        sensor_noise_per_sqrt_m=k * prof.sensor_noise_per_sqrt_m,
    )


class OdometryModel:
    """One run's odometry: commanded and sensor odometry, and the true body increments.

    Feed it every cycle's odometry increment (what the walk did by its own account) with
    :meth:`walk`; it integrates ``command`` (``getRobotPosition(False)``) and ``sensor``
    (``getRobotPosition(True)``, both FRAME_WORLD) and returns the body's true increment,
    which the backend applies to the ground truth (MuJoCo: as the base velocity, so walls
    still stop the body while the odometry keeps counting, as slipping feet do).

    Args:
        cfg: ``world.odometry``.
    """

    def __init__(self, cfg: OdometryConfig) -> None:
        self.errors = resolve(cfg)
        self._rng = np.random.default_rng([cfg.seed, 0x0D1])
        self.command = Pose2D()
        self.sensor = Pose2D()

    def true_increment(self, step: Pose2D) -> Pose2D:
        """The body's true motion for an odometry increment (FRAME_ROBOT, m and rad)."""
        e = self.errors
        ds = math.hypot(step.x, step.y)
        turn = abs(step.theta)
        noise = self._rng.standard_normal(3)  # always three draws: the same stream
        if e.exact:
            return step
        sd_pos = math.sqrt(
            e.random_walk_m_per_sqrt_m**2 * ds + e.turn_slip_m_per_sqrt_rad**2 * turn
        )
        sd_th = math.sqrt(
            e.heading_random_walk_rad_per_sqrt_m**2 * ds
            + e.heading_random_walk_rad_per_sqrt_rad**2 * turn
        )
        k = 1.0 / (1.0 + e.scale_error)
        return Pose2D(
            step.x * k + sd_pos * float(noise[0]),
            step.y * k + sd_pos * float(noise[1]),
            step.theta / (1.0 + e.turn_scale_error)
            - e.heading_bias_rad_per_m * ds
            + sd_th * float(noise[2]),
        )

    def walk(self, step: Pose2D) -> Pose2D:
        """Integrate one cycle's odometry increment; return the body's true increment.

        Args:
            step: The walk's increment by its own account (FRAME_ROBOT at the start of
                the cycle), metres and radians.

        Returns:
            The true increment of the body in the same frame.
        """
        self.command = (self.command * step).normalized()
        sd = self.errors.sensor_noise_per_sqrt_m
        noise = self._rng.standard_normal(3)
        if sd > 0.0:
            amount = math.sqrt(math.hypot(step.x, step.y) + abs(step.theta))
            step_read = Pose2D(
                step.x + sd * amount * float(noise[0]),
                step.y + sd * amount * float(noise[1]),
                step.theta + sd * amount * float(noise[2]),
            )
        else:
            step_read = step
        self.sensor = (self.sensor * step_read).normalized()
        return self.true_increment(step)
