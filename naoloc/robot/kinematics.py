"""Forward kinematics of the NAO H25: where the torso, head and cameras are for joint angles.

Pure numpy. Frames follow NAOqi (x forward, y left, z up; metres and radians):

- FRAME_TORSO (0): the torso frame.
- FRAME_ROBOT (2): the mean of the two feet's soles, projected on the ground, rotation about
  z only (the feet are taken to be flat on the floor, as when standing or walking).
- FRAME_WORLD (1): the odometry frame; ``FRAME_ROBOT`` sits at the odometry pose
  ``(x, y, theta)`` in it.

A camera's frame is NAOqi's: x along the optical axis, y left, z up (image up).
:func:`optical_from_camera` gives OpenCV's optical frame (z forward, x right, y down).

Link lengths (mm): NeckOffsetZ 126.5, HipOffsetY 50, HipOffsetZ 85, ThighLength 100,
TibiaLength 102.9, FootHeight 45.19; cameras in the head (HeadPitch) frame, V4/V5 head:
top (58.71, 0, 63.64) pitched down 1.2 deg, bottom (50.71, 0, 17.74) pitched down 39.7 deg
(Aldebaran's NAO H25 "Links" and "Video camera" documentation pages). In StandInit (hip
-0.45, knee 0.70, ankle -0.35 rad) the torso leans 0.1 rad forward and the top camera sits at
about (87, 0, 504) mm in FRAME_ROBOT, looking 6.9 deg down with the head at zero.

Poses as 6 floats ``[x, y, z, wx, wy, wz]`` use NAOqi's convention: the rotation is
``Rz(wz) @ Ry(wy) @ Rx(wx)`` (roll, pitch, yaw), so ``wy > 0`` looks down.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from naoloc.constants import (
    BOTTOM_CAMERA_IN_HEAD,
    FRAME_ROBOT,
    FRAME_TORSO,
    FRAME_WORLD,
    JOINT_LIMITS,
    NECK_OFFSET_Z,
    TOP_CAMERA_IN_HEAD,
)
from naoloc.errors import RobotError

HIP_OFFSET_Y = 0.050
HIP_OFFSET_Z = 0.085
THIGH_LENGTH = 0.100
TIBIA_LENGTH = 0.1029
FOOT_HEIGHT = 0.04519

#: Names :func:`transform` knows: the chains' end effectors NAOqi's getPosition takes.
EFFECTORS = ("CameraTop", "CameraBottom", "Head", "Torso", "LLeg", "RLeg")
FRAMES = (FRAME_TORSO, FRAME_WORLD, FRAME_ROBOT)

# NAOqi's head anti-collision limits (the head's shell meets the shoulders): HeadPitch range
# (deg) at HeadYaw (deg), linearly interpolated, from the NAO "Joints" documentation page
# (head section); at yaw 0 the range is the joint's own (-38.5..29.5 deg).
_SHELL_YAW_DEG = (-119.52, -87.49, -62.45, -51.74, -43.32, -27.85, 0.0,
                  27.85, 43.32, 51.74, 62.45, 87.49, 119.52)  # fmt: skip
_SHELL_PITCH_MIN_DEG = (-25.73, -18.91, -24.64, -27.50, -31.40, -38.50, -38.50,
                        -38.50, -31.40, -27.50, -24.64, -18.91, -25.73)  # fmt: skip
_SHELL_PITCH_MAX_DEG = (18.91, 11.46, 17.19, 18.91, 21.20, 24.18, 29.51,
                        24.18, 21.20, 18.91, 17.19, 11.46, 18.91)  # fmt: skip

_SQRT_HALF = math.sqrt(0.5)
_HIP_YAW_PITCH_AXIS = {"L": (0.0, _SQRT_HALF, -_SQRT_HALF), "R": (0.0, _SQRT_HALF, _SQRT_HALF)}


def _interp(x: float, xs: tuple[float, ...], ys: tuple[float, ...]) -> float:
    """Piecewise-linear interpolation of ``ys`` over increasing ``xs``, clamped at the ends."""
    if x <= xs[0]:
        return ys[0]
    for x0, x1, y0, y1 in zip(xs, xs[1:], ys, ys[1:], strict=False):
        if x <= x1:
            return y0 + (y1 - y0) * (x - x0) / (x1 - x0)
    return ys[-1]


def head_pitch_limits(head_yaw: float) -> tuple[float, float]:
    """HeadPitch range NAOqi lets the head reach at a HeadYaw: the joint's own range,
    narrowed at large yaw where the head's shell meets the shoulders.

    At yaw 0 it is the joint's range (-0.672..+0.515 rad); at +-1.53 rad (87.5 deg) it is
    about -0.33..+0.20 rad. The client clamps its head commands to it
    (:func:`naoloc.robot.camera.clamp_head`) and the MuJoCo backend its joints.

    Args:
        head_yaw: HeadYaw in radians.

    Returns:
        ``(min, max)`` HeadPitch in radians.
    """
    deg = math.degrees(head_yaw)
    lo = math.radians(_interp(deg, _SHELL_YAW_DEG, _SHELL_PITCH_MIN_DEG))
    hi = math.radians(_interp(deg, _SHELL_YAW_DEG, _SHELL_PITCH_MAX_DEG))
    pitch_min, pitch_max, _ = JOINT_LIMITS["HeadPitch"]
    return max(lo, pitch_min), min(hi, pitch_max)


def rot_x(a: float) -> np.ndarray:
    """3x3 rotation about x by ``a`` radians."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> np.ndarray:
    """3x3 rotation about y by ``a`` radians (positive tips x down)."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> np.ndarray:
    """3x3 rotation about z by ``a`` radians."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rot_axis(axis: Sequence[float], a: float) -> np.ndarray:
    k = np.asarray(axis, dtype=np.float64)
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(a) * kx + (1.0 - math.cos(a)) * kx @ kx


def homogeneous(
    rotation: np.ndarray | None = None, translation: Sequence[float] = (0, 0, 0)
) -> np.ndarray:
    """A 4x4 transform from a 3x3 rotation (identity if None) and a translation (m)."""
    t = np.eye(4)
    if rotation is not None:
        t[:3, :3] = rotation
    t[:3, 3] = translation
    return t


def _trans(x: float, y: float, z: float) -> np.ndarray:
    return homogeneous(None, (x, y, z))


def _rot(r: np.ndarray) -> np.ndarray:
    return homogeneous(r)


def position6d(t: np.ndarray) -> list[float]:
    """``[x, y, z, wx, wy, wz]`` of a 4x4 transform (NAOqi's roll-pitch-yaw)."""
    r = t[:3, :3]
    wy = math.atan2(-r[2, 0], math.hypot(r[0, 0], r[1, 0]))
    wx = math.atan2(r[2, 1], r[2, 2])
    wz = math.atan2(r[1, 0], r[0, 0])
    return [float(t[0, 3]), float(t[1, 3]), float(t[2, 3]), wx, wy, wz]


def transform_from_6d(p: Sequence[float]) -> np.ndarray:
    """The 4x4 transform of ``[x, y, z, wx, wy, wz]`` (inverse of :func:`position6d`)."""
    x, y, z, wx, wy, wz = (float(v) for v in p)
    return homogeneous(rot_z(wz) @ rot_y(wy) @ rot_x(wx), (x, y, z))


def _angle(angles: Mapping[str, float], name: str) -> float:
    return float(angles.get(name, 0.0))


def torso_to_head(angles: Mapping[str, float]) -> np.ndarray:
    """FRAME_TORSO -> head (HeadPitch joint frame), from HeadYaw and HeadPitch."""
    return (
        _trans(0.0, 0.0, NECK_OFFSET_Z)
        @ _rot(rot_z(_angle(angles, "HeadYaw")))
        @ _rot(rot_y(_angle(angles, "HeadPitch")))
    )


def head_to_camera(index: int) -> np.ndarray:
    """Head frame -> camera frame (NAOqi's: x along the view) of camera 0 (top) or 1 (bottom)."""
    (x, y, z), pitch = TOP_CAMERA_IN_HEAD if index == 0 else BOTTOM_CAMERA_IN_HEAD
    return homogeneous(rot_y(pitch), (x, y, z))


def torso_to_sole(angles: Mapping[str, float], side: str) -> np.ndarray:
    """FRAME_TORSO -> the sole of the ``side`` ("L" or "R") foot (the LLeg/RLeg effector)."""
    sign = 1.0 if side == "L" else -1.0
    hyp = _angle(angles, f"{side}HipYawPitch")
    if side == "R" and "RHipYawPitch" not in angles:
        hyp = _angle(angles, "LHipYawPitch")  # one motor for both
    return (
        _trans(0.0, sign * HIP_OFFSET_Y, -HIP_OFFSET_Z)
        @ _rot(_rot_axis(_HIP_YAW_PITCH_AXIS[side], hyp))
        @ _rot(rot_x(_angle(angles, f"{side}HipRoll")))
        @ _rot(rot_y(_angle(angles, f"{side}HipPitch")))
        @ _trans(0.0, 0.0, -THIGH_LENGTH)
        @ _rot(rot_y(_angle(angles, f"{side}KneePitch")))
        @ _trans(0.0, 0.0, -TIBIA_LENGTH)
        @ _rot(rot_y(_angle(angles, f"{side}AnklePitch")))
        @ _rot(rot_x(_angle(angles, f"{side}AnkleRoll")))
        @ _trans(0.0, 0.0, -FOOT_HEIGHT)
    )


def torso_to_robot(angles: Mapping[str, float]) -> np.ndarray:
    """FRAME_TORSO -> FRAME_ROBOT: the feet's mean sole, flat on the floor, yaw only."""
    left, right = torso_to_sole(angles, "L"), torso_to_sole(angles, "R")
    u, _, vt = np.linalg.svd(left[:3, :3] + right[:3, :3])  # mean rotation of the two feet
    rot = u @ vt
    return homogeneous(rot, (left[:3, 3] + right[:3, 3]) / 2.0)


def robot_to_torso(angles: Mapping[str, float]) -> np.ndarray:
    """FRAME_ROBOT -> FRAME_TORSO (the torso's pose in FRAME_ROBOT, StandInit's lean included)."""
    return np.linalg.inv(torso_to_robot(angles))


def world_to_robot(pose: Sequence[float]) -> np.ndarray:
    """FRAME_WORLD -> FRAME_ROBOT for an odometry pose ``(x, y, theta)`` (m, rad)."""
    x, y, theta = (float(v) for v in pose)
    return homogeneous(rot_z(theta), (x, y, 0.0))


def in_torso(name: str, angles: Mapping[str, float]) -> np.ndarray:
    """Pose of an effector in FRAME_TORSO as a 4x4 transform.

    Raises:
        RobotError: An unknown effector name.
    """
    if name == "Torso":
        return np.eye(4)
    if name == "Head":
        return torso_to_head(angles)
    if name in ("CameraTop", "CameraBottom"):
        return torso_to_head(angles) @ head_to_camera(0 if name == "CameraTop" else 1)
    if name in ("LLeg", "RLeg"):
        return torso_to_sole(angles, name[0])
    raise RobotError(f"unknown effector {name!r}; known: {', '.join(EFFECTORS)}")


def transform(
    name: str,
    frame: int,
    angles: Mapping[str, float],
    odometry: Sequence[float] = (0.0, 0.0, 0.0),
    torso_offset: np.ndarray | None = None,
) -> np.ndarray:
    """Pose of an effector in a NAOqi frame as a 4x4 transform (metres).

    Args:
        name: One of :data:`EFFECTORS`.
        frame: FRAME_TORSO (0), FRAME_WORLD (1) or FRAME_ROBOT (2).
        angles: Joint name -> angle (rad); missing joints count as 0.
        odometry: The robot's odometry pose ``(x, y, theta)`` in FRAME_WORLD.
        torso_offset: Extra 4x4 motion of the torso in FRAME_ROBOT (walk sway), applied
            after the legs' kinematics; None for none.

    Returns:
        ``T`` with ``p_frame = T @ [p_effector, 1]``.

    Raises:
        RobotError: An unknown effector name or frame.
    """
    if frame not in FRAMES:
        raise RobotError(
            f"unknown frame {frame!r}; use FRAME_TORSO 0, FRAME_WORLD 1, FRAME_ROBOT 2"
        )
    local = in_torso(name, angles)
    if frame == FRAME_TORSO:
        return local
    torso = robot_to_torso(angles)
    if torso_offset is not None:
        torso = torso_offset @ torso
    in_robot = torso @ local
    if frame == FRAME_ROBOT:
        return in_robot
    return world_to_robot(odometry) @ in_robot


# Optical frame (OpenCV: z along the view, x right, y down) in NAOqi's camera frame.
_OPTICAL = homogeneous(np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]))


def optical_from_camera(t_camera: np.ndarray) -> np.ndarray:
    """The optical frame (z forward, x right, y down) of a camera pose in NAOqi's frame."""
    return np.asarray(t_camera, dtype=np.float64) @ _OPTICAL


def camera_from_optical(t_optical: np.ndarray) -> np.ndarray:
    """NAOqi's camera frame (x forward, y left, z up) of an optical-frame pose."""
    return np.asarray(t_optical, dtype=np.float64) @ _OPTICAL.T
