"""The fake robot's state and simulated clock, shared by its NAOqi services.

There are no threads and no wall clock: :meth:`FakeWorld.tick` advances time by whole
ALMotion cycles (20 ms). Services call ``tick(1)`` on every non-blocking call, and
blocking calls run cycles until their task is done. Every cycle moves the joints toward
their targets and the body along the current walk task.

Frames: the ground truth ``true_pose`` is the FRAME_ROBOT origin in the room frame;
``command`` (``getRobotPosition(False)``) and ``sensor`` (``getRobotPosition(True)``) are
FRAME_WORLD poses, both ``[0, 0, 0]`` at the start pose.

Walking is open-loop on odometry, as on a NAO: a walk task plans on the commanded
odometry, and the body moves by what :class:`naoloc.backends.simulated.odometry.OdometryModel`
makes of each increment (``world.odometry``: profile ``nao`` drifts, ``ideal`` is exact).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from naoloc.backends.fake.joints import STANDING, joint_limits, posture_angles
from naoloc.backends.fake.walk import PathWalk, SpeedLimits, VelocityWalk
from naoloc.backends.simulated.odometry import OdometryModel
from naoloc.backends.simulated.sway import WalkSway
from naoloc.config import Config
from naoloc.constants import (
    FRAME_ROBOT,
    JOINT_NAMES,
    MOTION_CYCLE_S,
    WALK_SPEED,
    WALK_SPEED_THETA,
    WALK_SPEED_Y,
)
from naoloc.errors import MotionError, RobotError
from naoloc.geometry import Pose2D, modulo2PI
from naoloc.robot import kinematics

ROBOT_RADIUS_M = 0.15  # the robot's footprint, a disc, for wall collisions
LEG_JOINTS = tuple(j for j in JOINT_NAMES if "Hip" in j or "Knee" in j or "Ankle" in j)
DEFAULT_LIMITS = SpeedLimits(WALK_SPEED, WALK_SPEED_Y, WALK_SPEED_THETA)
MAX_BLOCKING_S = 3600.0  # a blocking call that would take longer than this is refused


class FakeWorld:
    """State of one fake robot in its room.

    Args:
        cfg: The configuration (room, start pose, odometry drift).

    Attributes:
        dt: ALMotion cycle, seconds.
        time_s: Simulated seconds since creation.
        true_pose: Ground truth, room frame.
        odometry: Commanded and sensor odometry (FRAME_WORLD) and the walk's error model.
        task: The running walk task, or None.
        velocity: Body velocity of the last cycle ``(vx, vy, wz)``, FRAME_ROBOT.
        posture: Name of the last posture reached ("Unknown" after joint commands to legs).
        stiffness: Joint name -> stiffness in [0, 1].
        joint_cmd: Joint name -> commanded angle (rad), interpolated toward ``joint_target``.
        joint_actual: Joint name -> measured angle (rad); follows the command while stiff.
        joint_target: Joint name -> target angle (rad).
        joint_speed: Joint name -> speed (rad/s) of the current interpolation.
        closed: True once the robot was closed.
    """

    def __init__(self, cfg: Config) -> None:
        self.cfg = cfg
        self.dt = MOTION_CYCLE_S
        self.size = (float(cfg.world.room.size_m[0]), float(cfg.world.room.size_m[1]))
        self.time_s = 0.0
        self._cycles = 0
        self.true_pose = Pose2D(*cfg.start_pose())
        self.odometry = OdometryModel(cfg.world.odometry)
        self.sway = WalkSway(cfg.world.sim.camera_sway)
        self.task: PathWalk | VelocityWalk | None = None
        self.last_move_failed = False
        self.velocity = (0.0, 0.0, 0.0)
        awake = cfg.world.sim.start_awake
        self.posture = "StandInit" if awake else "Crouch"
        self.stiffness = dict.fromkeys(JOINT_NAMES, 1.0 if awake else 0.0)
        self.joint_cmd = posture_angles(self.posture)
        self.joint_actual = dict(self.joint_cmd)
        self.joint_target = dict(self.joint_cmd)
        self.joint_speed = dict.fromkeys(JOINT_NAMES, 0.0)
        self.closed = False
        self.clock: Any = (
            None  # a naoloc.backends.naoqi.emulation.loop.SimClock when served in real time
        )

    # -- clock ---------------------------------------------------------------------------

    def check_open(self) -> None:
        """Raise if the robot was closed.

        Raises:
            RobotError: "robot is closed".
        """
        if self.closed:
            raise RobotError("robot is closed")

    def tick(self, cycles: int = 1) -> None:
        """Check the robot is open and advance simulated time by whole ALMotion cycles."""
        self.check_open()
        if self.clock is not None:
            self.clock.advance(cycles)
            return
        for _ in range(cycles):
            self._cycle()

    def run_until(self, done: Callable[[], bool], what: str) -> None:
        """Run cycles until ``done()`` holds (a blocking call).

        Raises:
            MotionError: If it would take more than an hour of simulated time.
        """
        self.check_open()
        limit = self._cycles + int(MAX_BLOCKING_S / self.dt)
        while not done():
            if self._cycles >= limit:
                raise MotionError(f"{what} did not finish within {MAX_BLOCKING_S:.0f} s")
            if self.clock is not None:
                self.clock.advance(1)
                self.check_open()
            else:
                self._cycle()

    def attach_clock(self, clock: Any) -> tuple[Callable[[], None], float]:
        """Let ``clock`` drive time (None = deterministic); returns the cycle and its length (s)."""
        self.clock = clock
        return self._cycle, self.dt

    def _cycle(self) -> None:
        self._step_joints()
        self._step_walk()
        self.sway.step(self.task is not None and self.awake, self.dt)
        self._cycles += 1
        self.time_s = self._cycles * self.dt

    # -- body ----------------------------------------------------------------------------

    @property
    def awake(self) -> bool:
        """True when every leg joint is stiff (stiffness >= 0.5)."""
        return all(self.stiffness[j] >= 0.5 for j in LEG_JOINTS)

    @property
    def command(self) -> Pose2D:
        """Commanded odometry (``getRobotPosition(False)``), FRAME_WORLD."""
        return self.odometry.command

    @property
    def sensor(self) -> Pose2D:
        """Sensor odometry (``getRobotPosition(True)``), FRAME_WORLD."""
        return self.odometry.sensor

    def is_free(self, x: float, y: float, clearance: float = ROBOT_RADIUS_M) -> bool:
        """True when a disc of ``clearance`` m at room-frame ``(x, y)`` touches no wall."""
        sx, sy = self.size
        return clearance <= x <= sx - clearance and clearance <= y <= sy - clearance

    def start_walk(self, task: PathWalk | VelocityWalk) -> None:
        """Replace the current walk task; walking starts from a walk-ready posture."""
        self.stop_walk()
        if self.posture not in STANDING:
            self.go_to_posture("StandInit", 1.0)
        self.task = task
        self.last_move_failed = False

    def stop_walk(self) -> None:
        """End the walk task at once; velocity becomes zero."""
        self.task = None
        self.velocity = (0.0, 0.0, 0.0)

    def _step_walk(self) -> None:
        task = self.task
        if task is None:
            self.velocity = (0.0, 0.0, 0.0)
            return
        if not self.awake:
            self.last_move_failed = True
            self.stop_walk()
            return
        if isinstance(task, VelocityWalk):
            inc = task.step(self.dt)
        else:
            inc = task.step(self.command, self.dt)
        # The odometry counts the step even when a wall stops the body (the feet slip).
        new_true = self.true_pose * self.odometry.walk(inc)
        if not self.is_free(new_true.x, new_true.y):
            self.last_move_failed = True
            self.stop_walk()
            return
        self.true_pose = Pose2D(new_true.x, new_true.y, modulo2PI(new_true.theta))
        if isinstance(task, VelocityWalk):
            self.velocity = (task.vx, task.vy, task.wz)
        else:
            self.velocity = (inc.x / self.dt, inc.y / self.dt, inc.theta / self.dt)
        if isinstance(task, PathWalk):
            task.advance()
            if task.done:
                self.task = None

    # -- joints --------------------------------------------------------------------------

    def set_joint_targets(self, targets: dict[str, float], fraction: float) -> None:
        """Start interpolating joints toward targets (rad, clamped to limits).

        Args:
            targets: Joint name -> angle in radians.
            fraction: Fraction of each joint's maximum speed, in (0, 1].
        """
        for name, angle in targets.items():
            lo, hi, vmax = joint_limits(name)
            self.joint_target[name] = min(max(float(angle), lo), hi)
            self.joint_speed[name] = fraction * vmax

    def joints_settled(self, names: list[str]) -> bool:
        """True when the named joints' commands reached their targets."""
        return all(self.joint_cmd[n] == self.joint_target[n] for n in names)

    def _step_joints(self) -> None:
        for name, target in self.joint_target.items():
            cmd = self.joint_cmd[name]
            if cmd != target:
                step = self.joint_speed[name] * self.dt
                if abs(target - cmd) <= step:
                    cmd = target
                else:
                    cmd += math.copysign(step, target - cmd)
                self.joint_cmd[name] = cmd
            if self.stiffness[name] > 0.0:
                self.joint_actual[name] = self.joint_cmd[name]

    def go_to_posture(self, name: str, fraction: float) -> None:
        """Move every joint to a predefined posture (blocking), stiffening the body.

        Args:
            name: A posture name from :func:`naoloc.backends.fake.joints.posture_names`.
            fraction: Fraction of the maximum posture speed, in (0, 1].
        """
        for joint in JOINT_NAMES:
            self.stiffness[joint] = 1.0
        target = posture_angles(name)
        change = max(abs(target[j] - self.joint_actual[j]) for j in JOINT_NAMES)
        duration = max(0.2, change / (1.5 * fraction))
        cycles = math.ceil(duration / self.dt)
        start = dict(self.joint_actual)
        for k in range(1, cycles + 1):
            a = k / cycles
            for j in JOINT_NAMES:
                self.joint_cmd[j] = start[j] + a * (target[j] - start[j])
            self.joint_target.update(self.joint_cmd)
            self.tick(1)
        self.joint_cmd.update(target)
        self.joint_target.update(target)
        self.joint_actual.update(target)
        self.posture = name

    def fk_transform(self, name: str, frame: int, use_sensors: bool) -> np.ndarray:
        """4x4 pose of an effector in a NAOqi frame from the joints (see naoloc.robot.kinematics).

        Sensors: measured joints, the sway and the sensor odometry; else the commands.
        """
        angles = self.joint_actual if use_sensors else self.joint_cmd
        odometry = self.sensor if use_sensors else self.command
        offset = self.sway.torso_offset() if use_sensors else None
        return kinematics.transform(name, frame, angles, odometry.to_list(), offset)

    def camera_in_room(self, index: int) -> np.ndarray:
        """True 4x4 pose of a camera (NAOqi camera frame) in the room frame."""
        name = "CameraTop" if index == 0 else "CameraBottom"
        local = kinematics.transform(
            name, FRAME_ROBOT, self.joint_actual, torso_offset=self.sway.torso_offset()
        )
        return kinematics.world_to_robot(self.true_pose.to_list()) @ local

    def head_angles(self) -> tuple[float, float]:
        """Measured ``(HeadYaw, HeadPitch)`` in radians."""
        return self.joint_actual["HeadYaw"], self.joint_actual["HeadPitch"]
