"""``check_robot(robot)``: the NAOqi conformance suite, shipped like Gymnasium's ``check_env``.

Every backend (fake, MuJoCo, a virtual NAOqi over zmq or libqi, a real NAO) must pass
it: the services satisfy the Protocols of :mod:`naoloc.robot`, walks reach their
targets by odometry (and by ground truth on simulators), ``stopMove`` stops, head
joints clamp at NAO's limits and move no faster than their maximum speed, chains
expand, postures are reached, and the image array has NAOqi's layout for every format.

The checks work under both time models: simulated time advancing inside calls
(in-process backends) and a server clock running at K x real time (``naoloc serve``);
polling loops wait for a number of calls *and* a wall-clock budget.

Usage::

    import naoloc
    from naoloc.robot.conformance import check_robot

    with naoloc.connect("configs/sim_paper_room.yaml") as robot:
        check_robot(robot)          # raises ConformanceError naming the failed check

The robot walks about 1.5 m and turns; give it room (the default start pose does).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from typing import Final

import numpy as np

from naoloc.constants import (
    COLORSPACE_LAYERS,
    COLORSPACE_NAMES,
    JOINT_LIMITS,
    JOINT_NAMES,
    POSTURES,
    RESOLUTION_NAMES,
    RESOLUTIONS,
    kQQVGA,
    kQVGA,
    kRGBColorSpace,
    kTopCamera,
    kVGA,
)
from naoloc.errors import HandleError, NaolocError, RobotError
from naoloc.geometry import Pose2D, relative_pose
from naoloc.robot import Motion, Posture, Robot, SimControl, VideoDevice, pose_of
from naoloc.robot.image import frame_from_naoqi

POS_TOL_M: Final = 0.05
ANGLE_TOL_RAD: Final = math.radians(5.0)
DEFAULT_RESOLUTIONS: Final = (kQQVGA, kQVGA, kVGA)
DEFAULT_COLORSPACES: Final = tuple(sorted(COLORSPACE_LAYERS))
POLL_WALL_S: Final = 3.0  # wall-clock budget of a polling loop on real-time backends


class ConformanceError(AssertionError):
    """A backend broke a NAOqi rule; the message names the check and what was seen."""


def _require(condition: bool, message: str) -> None:
    if not condition:
        raise ConformanceError(message)


def _poll(predicate: Callable[[], bool], polls: int = 25, wall_s: float = POLL_WALL_S) -> bool:
    """True once ``predicate()`` holds; gives up after ``polls`` calls and ``wall_s`` seconds."""
    start = time.monotonic()
    count = 0
    while True:
        if predicate():
            return True
        count += 1
        if count >= polls and time.monotonic() - start >= wall_s:
            return False
        if count >= polls:
            time.sleep(0.02)


def _ready(robot: Robot) -> None:
    robot.motion.wakeUp()
    _require(robot.posture.goToPosture("StandInit", 0.8) is True, "goToPosture(StandInit) failed")


def _true(robot: Robot) -> Pose2D | None:
    return Pose2D(*robot.sim.true_pose()) if robot.sim is not None else None


def _clock(robot: Robot) -> float:
    return robot.sim.sim_time() if robot.sim is not None else time.monotonic()


def _check_move(robot: Robot, target: tuple[float, float, float]) -> None:
    start = pose_of(robot.motion, use_sensors=False)
    true_start = _true(robot)
    _require(robot.motion.moveTo(*target) is True, f"moveTo{target} returned not True")
    true_end = _true(robot)
    checks = [("getRobotPosition(False)", relative_pose(start, pose_of(robot.motion, False)))]
    if true_start is not None and true_end is not None:
        checks.append(("ground truth", relative_pose(true_start, true_end)))
    for name, moved in checks:
        err = math.hypot(moved.x - target[0], moved.y - target[1])
        _require(err < POS_TOL_M, f"moveTo{target}: {name} moved {moved} ({err:.3f} m off)")
        _require(
            abs(moved.theta - target[2]) < ANGLE_TOL_RAD, f"moveTo{target}: {name} turned {moved}"
        )


def check_services(robot: Robot) -> None:
    """The services satisfy naoloc's Protocols; ``info`` is a dict."""
    _require(isinstance(robot.motion, Motion), "robot.motion is not a Motion")
    _require(isinstance(robot.video, VideoDevice), "robot.video is not a VideoDevice")
    _require(isinstance(robot.posture, Posture), "robot.posture is not a Posture")
    _require(robot.sim is None or isinstance(robot.sim, SimControl), "robot.sim is no SimControl")
    _require(isinstance(robot.info, dict), "robot.info is not a dict")


def check_walk_forward(robot: Robot) -> None:
    """moveTo(0.5, 0, 0) reaches its target by commanded odometry and ground truth."""
    _ready(robot)
    _check_move(robot, (0.5, 0.0, 0.0))


def check_turn(robot: Robot) -> None:
    """moveTo(0, 0, pi/2) turns in place."""
    _ready(robot)
    _check_move(robot, (0.0, 0.0, math.pi / 2))


def check_odometry(robot: Robot) -> None:
    """Sensor and command odometry agree on a short walk, and are finite."""
    _ready(robot)
    start_cmd = pose_of(robot.motion, use_sensors=False)
    start_sensor = pose_of(robot.motion, use_sensors=True)
    _require(robot.motion.moveTo(0.3, 0.0, 0.0) is True, "moveTo(0.3, 0, 0) failed")
    by_cmd = robot.motion.getRobotPosition(False)
    by_sensor = robot.motion.getRobotPosition(True)
    for value in (by_cmd, by_sensor):
        _require(len(value) == 3 and all(math.isfinite(float(v)) for v in value), f"{value}")
    moved_cmd = relative_pose(start_cmd, Pose2D.from_list(by_cmd))
    moved_sensor = relative_pose(start_sensor, Pose2D.from_list(by_sensor))
    _require(moved_cmd.x > 0.2 and moved_sensor.x > 0.2, f"{moved_cmd} / {moved_sensor}")
    gap = math.hypot(moved_cmd.x - moved_sensor.x, moved_cmd.y - moved_sensor.y)
    _require(gap < POS_TOL_M, f"sensor and command odometry differ by {gap:.3f} m")
    _require(abs(moved_cmd.theta - moved_sensor.theta) < ANGLE_TOL_RAD, "headings differ")


def check_stop_move(robot: Robot) -> None:
    """move() walks, moveIsActive() is True, stopMove() stops it and the robot stays put."""
    _ready(robot)
    motion = robot.motion
    start = pose_of(motion, use_sensors=False)
    motion.move(0.08, 0.0, 0.0)
    try:
        moving = _poll(lambda: pose_of(motion, use_sensors=False).distance(start) > 0.005)
        _require(moving, "move() did not move the robot")
        _require(motion.moveIsActive() is True, "moveIsActive() is False during a move()")
    finally:
        motion.stopMove()
    _require(_poll(lambda: not motion.moveIsActive()), "moveIsActive() stays True after stopMove")
    _require(
        _poll(lambda: all(abs(v) < 1e-3 for v in motion.getRobotVelocity())),
        "the robot still has a velocity after stopMove",
    )
    a = pose_of(motion, use_sensors=False)
    for _ in range(5):
        motion.getRobotVelocity()
    time.sleep(0.05)
    b = pose_of(motion, use_sensors=False)
    _require(a.distance(b) < 1e-3 and abs(a.theta - b.theta) < 1e-3, "drifts after stopMove")


def check_head_limits(robot: Robot) -> None:
    """HeadYaw and HeadPitch clamp at NAO's limits (measured and commanded)."""
    _ready(robot)
    for joint in ("HeadYaw", "HeadPitch"):
        robot.motion.angleInterpolationWithSpeed("Head", [0.0, 0.0], 1.0)  # the shell limits
        lo, hi, _ = JOINT_LIMITS[joint]
        for asked, limit in ((hi + 1.0, hi), (lo - 1.0, lo)):
            robot.motion.angleInterpolationWithSpeed(joint, asked, 1.0)
            (measured,) = robot.motion.getAngles(joint, True)
            (commanded,) = robot.motion.getAngles(joint, False)
            _require(abs(measured - limit) < 0.03, f"{joint} asked {asked:.2f}: at {measured:.3f}")
            _require(lo - 1e-6 <= commanded <= hi + 1e-6, f"{joint} commanded {commanded}")


def check_set_angles(robot: Robot) -> None:
    """setAngles does not block and moves a joint no faster than its maximum speed."""
    _ready(robot)
    motion = robot.motion
    motion.angleInterpolationWithSpeed("HeadYaw", -1.0, 1.0)
    fraction = 0.1
    max_speed = JOINT_LIMITS["HeadYaw"][2] * fraction
    t0 = _clock(robot)
    motion.setAngles("HeadYaw", 1.0, fraction)
    (first,) = motion.getAngles("HeadYaw", True)
    _require(first < 0.5, "setAngles blocked until a far target was reached")
    previous, t_prev = -1.0, t0
    for _ in range(10):
        (angle,) = motion.getAngles("HeadYaw", True)
        now = _clock(robot)
        _require(
            angle - previous <= max_speed * (now - t_prev) + 0.05,
            f"HeadYaw moved {angle - previous:.3f} rad in {now - t_prev:.3f} s",
        )
        previous, t_prev = angle, now
    motion.angleInterpolationWithSpeed("HeadYaw", 1.0, 1.0)
    (end,) = motion.getAngles("HeadYaw", True)
    _require(abs(end - 1.0) < 0.03, f"angleInterpolationWithSpeed ended at {end:.3f}")
    motion.angleInterpolationWithSpeed("Head", [0.0, 0.0], 1.0)


def check_chains(robot: Robot) -> None:
    """getAngles expands "Head" and "Body"."""
    _require(len(robot.motion.getAngles("Head", False)) == 2, "Head is not 2 joints")
    body = robot.motion.getAngles("Body", True)
    _require(len(body) == len(JOINT_NAMES), f"Body has {len(body)} joints")
    _require(all(math.isfinite(v) for v in body), "non-finite joint angles")


def check_postures(robot: Robot) -> None:
    """Every predefined posture is listed; wakeUp wakes; StandInit is reached and reported."""
    _require(set(POSTURES) <= set(robot.posture.getPostureList()), "postures missing")
    robot.motion.wakeUp()
    _require(robot.motion.robotIsWakeUp() is True, "robotIsWakeUp() False after wakeUp()")
    _require(robot.posture.goToPosture("StandInit", 0.8) is True, "goToPosture failed")
    _require(robot.posture.getPosture() == "StandInit", "getPosture() is not StandInit")


def check_image_formats(
    robot: Robot,
    resolutions: Sequence[int] = DEFAULT_RESOLUTIONS,
    colorspaces: Sequence[int] = DEFAULT_COLORSPACES,
) -> None:
    """getImageRemote has NAOqi's 12-slot layout for every claimed resolution and colorspace."""
    hfov = robot.video.getHorizontalFOV(kTopCamera)
    vfov = robot.video.getVerticalFOV(kTopCamera)
    _require(0.6 < hfov < 1.3 and 0.5 < vfov < hfov, f"field of view {hfov}, {vfov}")
    for resolution in resolutions:
        for colorspace in colorspaces:
            what = f"{RESOLUTION_NAMES[resolution]}/{COLORSPACE_NAMES[colorspace]}"
            handle = robot.video.subscribeCamera("conf", kTopCamera, resolution, colorspace, 30)
            try:
                value = robot.video.getImageRemote(handle)
            finally:
                _require(robot.video.unsubscribe(handle) is True, f"{what}: unsubscribe")
            width, height = RESOLUTIONS[resolution]
            layers = COLORSPACE_LAYERS[colorspace]
            _require(len(value) == 12, f"{what}: {len(value)} slots")
            head = [int(v) for v in value[:4]]
            _require(head == [width, height, layers, colorspace], f"{what}: header {head}")
            _require(int(value[4]) >= 0 and 0 <= int(value[5]) < 1_000_000, f"{what}: stamp")
            _require(isinstance(value[6], bytes | bytearray | str), f"{what}: pixel type")
            _require(len(value[6]) == width * height * layers, f"{what}: {len(value[6])} bytes")
            _require(int(value[7]) == kTopCamera, f"{what}: camera {value[7]}")
            left, top, right, bottom = (float(v) for v in value[8:12])
            _require(abs(left - hfov / 2) < 0.02 and abs(right + left) < 1e-6, f"{what}: l/r")
            _require(abs(top - vfov / 2) < 0.02 and abs(bottom + top) < 1e-6, f"{what}: t/b")
            frame = frame_from_naoqi(value)
            _require(frame.pixels.shape == (height, width, layers), f"{what}: shape")
            if width >= 160:
                _require(float(np.std(frame.gray())) > 5.0, f"{what}: a blank image")


def check_subscriptions(robot: Robot) -> None:
    """Handles are unique; resolution, colorspace and timestamps read back."""
    video = robot.video
    first = video.subscribeCamera("conf", kTopCamera, kQVGA, kRGBColorSpace, 15)
    second = video.subscribeCamera("conf", kTopCamera, kQQVGA, kRGBColorSpace, 15)
    try:
        _require(isinstance(first, str) and isinstance(second, str), "handles are not str")
        _require(first != second, "two subscribers got the same handle")
        _require(video.getResolution(first) == kQVGA, "getResolution of the first")
        _require(video.getResolution(second) == kQQVGA, "getResolution of the second")
        _require(video.getColorSpace(first) == kRGBColorSpace, "getColorSpace")
        early = frame_from_naoqi(video.getImageRemote(first))
        late = frame_from_naoqi(video.getImageRemote(first))
        _require(late.stamp >= early.stamp, "image timestamps go back")
    finally:
        video.unsubscribe(first)
        video.unsubscribe(second)


def check_bad_handles(robot: Robot) -> None:
    """Unknown and unsubscribed handles raise an error naming the handle."""
    video = robot.video
    for handle_text in ("no-such-handle",):
        try:
            video.getImageRemote(handle_text)
        except RobotError as err:
            _require(handle_text in str(err), f"the error does not name the handle: {err}")
        else:
            raise ConformanceError("getImageRemote of an unknown handle did not raise")
    handle = video.subscribeCamera("conf_gone", kTopCamera, kQQVGA, kRGBColorSpace, 30)
    _require(video.unsubscribe(handle) is True, "unsubscribe of a live handle")
    try:
        video.getImageRemote(handle)
    except (HandleError, RobotError) as err:
        _require(handle in str(err), f"the error does not name the handle: {err}")
    else:
        raise ConformanceError("getImageRemote of an unsubscribed handle did not raise")
    _require(video.unsubscribe(handle) is False, "a second unsubscribe returned True")


def check_teleport(robot: Robot) -> None:
    """On simulators: teleport moves the truth, not odometry; is_free sees walls."""
    if robot.sim is None:
        return
    sim = robot.sim
    sx, sy = sim.room_size()
    _require(sim.is_free(sx / 2, sy / 2, 0.3), "the room's centre is not free")
    _require(not sim.is_free(0.05, sy / 2, 0.3), "a wall is free")
    before = pose_of(robot.motion, use_sensors=False)
    t0 = sim.sim_time()
    sim.teleport(sx / 2, sy / 2, 1.0)
    x, y, theta = sim.true_pose()
    _require(math.hypot(x - sx / 2, y - sy / 2) < 0.02 and abs(theta - 1.0) < 0.02, "teleport")
    after = pose_of(robot.motion, use_sensors=False)
    _require(after.distance(before) < 0.02, "teleport moved the odometry")
    _require(sim.sim_time() >= t0, "simulated time went back")


CHECKS: Final[dict[str, Callable[[Robot], None]]] = {
    "services": check_services,
    "walk_forward": check_walk_forward,
    "turn": check_turn,
    "odometry": check_odometry,
    "stop_move": check_stop_move,
    "head_limits": check_head_limits,
    "set_angles": check_set_angles,
    "chains": check_chains,
    "postures": check_postures,
    "subscriptions": check_subscriptions,
    "bad_handles": check_bad_handles,
    "teleport": check_teleport,
}


def check_robot(
    robot: Robot,
    *,
    resolutions: Sequence[int] = DEFAULT_RESOLUTIONS,
    colorspaces: Sequence[int] = DEFAULT_COLORSPACES,
    skip: Sequence[str] = (),
) -> None:
    """Run every conformance check on ``robot``; raise at the first that fails.

    Args:
        robot: A connected robot with room to walk 1.5 m.
        resolutions: NAOqi resolution ids the backend claims to render.
        colorspaces: NAOqi colorspace ids it claims.
        skip: Names of checks (keys of :data:`CHECKS`) not to run.

    Raises:
        ConformanceError: The first broken rule, prefixed with the check's name.
    """
    for name, check in CHECKS.items():
        if name in skip:
            continue
        try:
            check(robot)
        except ConformanceError as err:
            raise ConformanceError(f"{name}: {err}") from None
        except NaolocError as err:
            raise ConformanceError(f"{name}: {type(err).__name__}: {err}") from None
    if "image_formats" not in skip:
        try:
            check_image_formats(robot, resolutions, colorspaces)
        except ConformanceError as err:
            raise ConformanceError(f"image_formats: {err}") from None
