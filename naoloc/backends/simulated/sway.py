"""The torso's sway and bob while a NAO walks (``world.sim.camera_sway``), for both simulators.

NAO's walk is a linear-inverted-pendulum ZMP controller: the centre of mass shifts over the
support foot at every step, so the torso (and the head and cameras on it) swings side to
side once per stride (two steps, about 1 s at NAO's 2 steps/s), rolls with it, and bobs
up and down and pitches a little at every step. The head moves about +-2 cm sideways
(a LIPM estimate for NAO's step width and CoM height). Here: +-8 mm of lateral torso shift
and +-1.5 deg of roll about the feet in phase (together about +-21 mm at the top camera,
0.5 m above the floor), 4 mm of bob and +-0.6 deg of pitch at the step frequency. The sway fades in
within about a step when walking starts and settles within about 0.5 s after it stops;
``moveTo`` returns once it has (a NAO's walk ends with the feet together, body still).

Pure arithmetic: :class:`WalkSway` is stepped once per ALMotion cycle and gives the torso's
extra motion as a 4x4 transform in FRAME_ROBOT (see :func:`naoloc.robot.kinematics.transform`).
"""

from __future__ import annotations

import math

import numpy as np

from naoloc.robot.kinematics import homogeneous, rot_x, rot_y

STRIDE_HZ = 1.0  # side-to-side cycles per second (two steps per second)
LATERAL_M = 0.008  # torso shift amplitude, m
ROLL_RAD = math.radians(1.5)  # roll amplitude about the feet, rad
BOB_M = 0.004  # torso bob (peak to peak), m
PITCH_RAD = math.radians(0.6)  # torso pitch amplitude at the step frequency, rad
RISE_S = 0.25  # time constant of the sway's growth when walking starts, s
SETTLE_S = 0.1  # time constant of its decay after stopping, s
SETTLE_TIME_S = SETTLE_S * math.log(100.0)  # from full sway to settled (1 %), s


class WalkSway:
    """The sway state of one robot: phase and envelope, stepped once per cycle.

    Args:
        enabled: False keeps the torso still (``world.sim.camera_sway: false``).
    """

    def __init__(self, enabled: bool = True) -> None:
        self.enabled = enabled
        self.phase = 0.0
        self.envelope = 0.0

    def step(self, walking: bool, dt: float) -> None:
        """Advance by one cycle of ``dt`` seconds; ``walking`` while a walk command is non-zero."""
        if not self.enabled:
            return
        tau = RISE_S if walking else SETTLE_S
        target = 1.0 if walking else 0.0
        self.envelope += (target - self.envelope) * (1.0 - math.exp(-dt / tau))
        if walking or self.envelope > 1e-4:
            self.phase = (self.phase + 2.0 * math.pi * STRIDE_HZ * dt) % (2.0 * math.pi)
        else:
            self.envelope, self.phase = 0.0, 0.0

    @property
    def settled(self) -> bool:
        """True when the sway has (all but) died out: at most 1 % of its walking amplitude."""
        return self.envelope <= 0.01

    def offsets(self) -> tuple[float, float, float, float]:
        """``(lateral m, bob m, roll rad, pitch rad)`` of the torso now (FRAME_ROBOT)."""
        a = self.envelope
        if a == 0.0:
            return (0.0, 0.0, 0.0, 0.0)
        s = math.sin(self.phase)
        step = math.cos(2.0 * self.phase)  # twice per stride: at every step
        # Positive roll tips the head toward -y: roll against the shift so the head swings wider.
        return (
            a * LATERAL_M * s,
            -a * BOB_M * (1.0 - step) / 2.0,
            -a * ROLL_RAD * s,
            a * PITCH_RAD * step,
        )

    def torso_offset(self) -> np.ndarray | None:
        """The torso's extra motion as a 4x4 transform in FRAME_ROBOT, or None when still.

        Roll and pitch turn about a point on the floor below the torso (the pendulum's foot),
        then the torso shifts sideways and bobs.
        """
        lateral, bob, roll, pitch = self.offsets()
        if lateral == 0.0 and bob == 0.0 and roll == 0.0 and pitch == 0.0:
            return None
        turn = homogeneous(rot_x(roll) @ rot_y(pitch))
        return homogeneous(None, (0.0, lateral, bob)) @ turn
