"""The floor-wall line detector on synthetic images and on rendered MuJoCo rooms."""

from __future__ import annotations

import math

import numpy as np
import pytest

import naoloc
from naoloc.behaviours.wall_follow import (
    MAX_LATERAL_M,
    MAX_TURN_RAD,
    FloorEye,
    FrontSample,
    corrected_step,
    metric_scale,
)
from naoloc.config import FloorLineTuning, load_config
from naoloc.errors import FeatureError
from naoloc.geometry import Pose2D
from naoloc.perception.floorline import WallLine, detect_wall_line, detect_wall_lines, pixel_rays
from naoloc.robot.kinematics import rot_y, rot_z

HFOV, VFOV = 1.0629, 0.8308


def camera_pose(yaw: float, down: float, height: float = 0.46) -> np.ndarray:
    """A camera at ``height`` m looking ``down`` rad below the horizon toward ``yaw``."""
    t = np.eye(4)
    t[:3, :3] = rot_z(yaw) @ rot_y(down)
    t[:3, 3] = (0.03, 0.0, height)
    return t


def trace(
    pose: np.ndarray, wall_normal: float, wall_distance: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each pixel's ray of a 320x240 view through a floor and a wall standing on the line
    ``wall_distance`` m along ``wall_normal`` (FRAME_ROBOT): whether it meets the floor
    first, where on the floor (x, y, m; the camera's foot where it does not) and at what
    height it meets the wall (m; the camera's height where it meets the floor)."""
    origin, rays = pixel_rays(320, 240, HFOV, VFOV, pose)
    n = np.array([math.cos(wall_normal), math.sin(wall_normal)])
    with np.errstate(divide="ignore", invalid="ignore"):
        s_floor = np.where(rays[..., 2] < 0, -origin[2] / rays[..., 2], np.inf)
        toward = rays[..., :2] @ n
        s_wall = np.where(toward > 0, (wall_distance - origin[:2] @ n) / toward, np.inf)
    floor = s_floor < s_wall
    hit = origin[None, None, :2] + np.where(floor, s_floor, 0)[..., None] * rays[..., :2]
    z_wall = origin[2] + np.where(floor, 0.0, s_wall) * rays[..., 2]
    return floor, hit, z_wall


def render(
    pose: np.ndarray, wall_normal: float, wall_distance: float, *, seed: int = 0
) -> np.ndarray:
    """A 320x240 view of a floor with seams and a blank wall standing on the given line."""
    rng = np.random.default_rng(seed)
    floor, hit, _z = trace(pose, wall_normal, wall_distance)
    img = np.empty((240, 320, 3), np.uint8)
    wood = np.array([40, 90, 150], float)  # BGR brown
    tone = 1.0 + 0.12 * np.sin(hit[..., 1] * 40.0)  # planks of varying tone
    seam = (np.abs(((hit[..., 1] * 6.0) % 1.0) - 0.5) < 0.03)[..., None]
    floor_bgr = np.clip(wood * tone[..., None] * np.where(seam, 0.7, 1.0), 0, 255)
    wall_bgr = np.array([215, 220, 225], float)  # a blank off-white wall
    img[:] = np.where(floor[..., None], floor_bgr, wall_bgr).astype(np.uint8)
    noise = rng.normal(0, 3, img.shape)
    return np.clip(img + noise, 0, 255).astype(np.uint8)


@pytest.mark.parametrize(
    ("normal", "distance"), [(-math.pi / 2, 1.0), (-math.pi / 2 - 0.15, 0.8), (-1.3, 1.4)]
)
def test_synthetic_blank_wall_on_the_right(normal: float, distance: float) -> None:
    pose = camera_pose(-math.pi / 2, 0.5)
    line = detect_wall_line(render(pose, normal, distance), HFOV, VFOV, pose,
                            expect_normal=-math.pi / 2)  # fmt: skip
    assert line is not None
    assert abs(line.distance - distance) < 0.02
    assert abs(line.normal - normal) < 0.02
    assert line.rms_m < 0.01 and line.inliers > 100


def test_synthetic_front_wall() -> None:
    pose = camera_pose(0.0, 0.35)
    line = detect_wall_line(render(pose, 0.05, 1.6), HFOV, VFOV, pose, expect_normal=0.0)
    assert line is not None
    assert abs(line.distance - 1.6) < 0.03 and abs(line.normal - 0.05) < 0.02


def test_no_wall_in_view_gives_none() -> None:
    pose = camera_pose(-math.pi / 2, 0.7)  # looks at the floor only: the wall is 3.5 m away
    assert detect_wall_lines(render(pose, -math.pi / 2, 3.5), HFOV, VFOV, pose) == []
    same = np.full((240, 320, 3), 128, np.uint8)  # a floor and wall of one colour
    assert detect_wall_line(same, HFOV, VFOV, camera_pose(-math.pi / 2, 0.5)) is None


def test_wrong_direction_is_rejected() -> None:
    pose = camera_pose(-math.pi / 2, 0.5)
    img = render(pose, -math.pi / 2, 1.0)
    assert detect_wall_line(img, HFOV, VFOV, pose, expect_normal=0.0, tolerance=0.4) is None


def test_bad_input_names_the_problem() -> None:
    with pytest.raises(FeatureError, match="uint8"):
        detect_wall_line(np.zeros((10, 10, 4)), HFOV, VFOV, np.eye(4))
    with pytest.raises(FeatureError, match="16 finite"):
        detect_wall_line(np.zeros((10, 10, 3), np.uint8), HFOV, VFOV, np.eye(3))


def test_the_config_tunes_the_detector() -> None:
    """``camera.floor_lines`` reaches the detector: a line shorter than its least span, or
    with fewer inliers than its least count, is no line."""
    pose = camera_pose(0.0, 0.35)
    img = render(pose, 0.05, 1.6)
    line = detect_wall_line(img, HFOV, VFOV, pose, tun=load_config(None).camera.floor_lines)
    assert line is not None and line.span_m < 2.5
    assert line == detect_wall_line(img, HFOV, VFOV, pose)  # None: the defaults
    long = load_config({"camera": {"floor_lines": {"min_span_m": 2.5}}}).camera.floor_lines
    assert detect_wall_line(img, HFOV, VFOV, pose, tun=long) is None
    many = FloorLineTuning(min_inliers=line.inliers + 1)
    assert detect_wall_lines(img, HFOV, VFOV, pose, tun=many) == []


def test_the_survey_eye_uses_the_camera_config_floor_lines() -> None:
    pose = camera_pose(0.0, 0.35)
    view = (render(pose, 0.05, 1.6), HFOV, VFOV, pose)
    cfg = load_config({"robot": {"backend": "fake"}})
    tuned = cfg.with_overrides({"camera": {"floor_lines": {"min_span_m": 2.5}}})
    with naoloc.connect(cfg) as robot:
        for camera, found in [(cfg.camera, 1), (tuned.camera, 0)]:
            eye = FloorEye(robot, camera)
            try:
                assert len(eye.detect(view)) == found
            finally:
                eye.close()


def _line(distance: float, normal: float) -> WallLine:
    return WallLine(distance, normal, 100, 1.0, 0.003, 1.0)


def test_corrected_step_returns_to_the_offset_and_is_bounded() -> None:
    move, used = corrected_step(_line(1.05, -math.pi / 2), -math.pi / 2, 1.0, 0.2)
    assert used and move.x == pytest.approx(0.2) and move.y == pytest.approx(-0.05)
    assert move.theta == pytest.approx(0.0)
    # far off and turned: bounded sideways and in heading, never toward the wall beyond it
    move, used = corrected_step(_line(0.6, -math.pi / 2 + 0.3), -math.pi / 2, 1.0, 0.2)
    assert used and abs(move.theta) <= MAX_TURN_RAD + 1e-9
    assert math.hypot(move.x - 0.2 * math.cos(move.theta), move.y - 0.2 * math.sin(move.theta)) <= (
        MAX_LATERAL_M + 1e-9
    )
    assert move.y > 0  # away from a wall on the right that is too near
    # implausible line (furniture, a far wall, another wall's corner): straight ahead
    move, used = corrected_step(_line(2.0, -math.pi / 2), -math.pi / 2, 1.0, 0.2)
    assert not used and move == Pose2D(0.2, 0.0, 0.0)
    move, used = corrected_step(_line(0.9, -math.pi / 2 + 0.5), -math.pi / 2, 1.0, 0.2)
    assert not used and move == Pose2D(0.2, 0.0, 0.0)
    assert corrected_step(None, math.pi / 2, 1.0, 0.2) == (Pose2D(0.2, 0.0, 0.0), False)


def test_metric_scale_from_front_distances() -> None:
    # odometry reads 3 % long: 0.8 m walked toward the wall shows as 0.824 m
    samples = [
        FrontSample(k, Pose2D(3.0 + 1.03 * i * 0.2, k, 0.0), _line(2.0 - i * 0.2, 0.0))
        for k in range(3)
        for i in range(5)
    ]
    scale, ratios = metric_scale(samples)
    assert scale == pytest.approx(1 / 1.03) and len(ratios) == 3
    assert metric_scale(samples[:5])[0] is None  # one side only
    assert metric_scale(samples[:1]) == (None, [])  # no baseline
    # sides that disagree (a wrong line): no scale rather than a wrong one
    bad = [
        FrontSample(9, Pose2D(0, 0, 0), _line(2.0, 0)),
        FrontSample(9, Pose2D(0.5, 0, 0), _line(1.2, 0)),
    ]
    assert metric_scale(samples[:5] + bad)[0] is None


def test_front_wall_must_agree_with_the_odometry() -> None:
    from naoloc.behaviours.survey import trusted_front

    wall = _line(1.6, 0.0)
    assert trusted_front(wall, 1.0, 0.7, 4.0) is wall  # the corner 0.6 m ahead, odometry 0.7
    assert trusted_front(_line(0.61, 0.0), 1.0, 1.3, 4.0) is None  # a rug's edge, not a wall
    assert trusted_front(_line(3.5, 0.0), 1.0, 2.5, 4.0) is None  # beyond the camera's range
    assert trusted_front(None, 1.0, 0.7, 4.0) is None


def render_boards(
    pose: np.ndarray, wall_distance: float, *, band: float, skirting: float | None, seed: int = 0
) -> np.ndarray:
    """A wall straight ahead of ``pose``'s yaw on a wooden floor whose last 0.3 m before
    the wall is a board ``band`` times as light, with an 8 cm skirting of the floor's
    wood ``skirting`` times as light (band 1.0: no board; skirting None: no skirting)."""
    rng = np.random.default_rng(seed)
    yaw = math.atan2(pose[1, 0], pose[0, 0])
    floor, hit, z_wall = trace(pose, yaw, wall_distance)
    depth = hit @ np.array([math.cos(yaw), math.sin(yaw)])
    wood = np.array([70, 110, 150], float)  # BGR light oak
    tone = np.where(depth > wall_distance - 0.3, band, 1.0)
    floor_bgr = wood * tone[..., None]
    skirt = (z_wall < 0.08) if skirting is not None else np.zeros_like(floor)
    wall_bgr = np.where(skirt[..., None], wood * (skirting or 1.0), [200, 215, 230])
    img = np.where(floor[..., None], floor_bgr, wall_bgr)
    return np.clip(img + rng.normal(0, 3, img.shape), 0, 255).astype(np.uint8)


@pytest.mark.parametrize(("band", "skirting"), [(1.3, None), (1.0, 0.55), (1.25, 0.55)])
@pytest.mark.parametrize(("yaw", "down", "distance"), [(-math.pi / 2, 0.5, 1.0), (0.0, 0.35, 1.8)])
def test_a_lighter_board_and_a_wooden_skirting_are_not_the_wall(
    band: float, skirting: float | None, yaw: float, down: float, distance: float
) -> None:
    # The room-913 failures: a lighter board 0.3 m before the wall read as the wall (0.3 m
    # short), and a skirting of the floor's wood read as floor (its top, 20 % long).
    pose = camera_pose(yaw, down)
    image = render_boards(pose, distance, band=band, skirting=skirting)
    line = detect_wall_line(image, HFOV, VFOV, pose, expect_normal=yaw)
    assert line is not None
    assert abs(line.distance - distance) < 0.03 * distance


def test_boundary_pixels_takes_the_top_of_the_lowest_floor_run() -> None:
    """Per column, from the bottom: the robot's body is skipped, a run shorter than min_run
    or floor up to the image's top gives nothing."""
    from naoloc.perception.floorline import boundary_pixels

    h = 20
    mask = np.zeros((h, 5), bool)
    mask[12:, 0] = True  # floor from row 12 down: boundary 12
    mask[8:17, 1] = True  # body in the bottom 3 rows, floor above: boundary 8
    mask[18:, 2] = True  # a 2-row run: too short
    mask[:, 3] = True  # floor to the top: no wall
    mask[2:6, 4] = mask[10:, 4] = True  # the lowest run counts, not the one above it
    rows, cols = boundary_pixels(mask, min_run=4)
    assert cols.tolist() == [0, 1, 4] and rows.tolist() == [12, 8, 10]


@pytest.mark.parametrize("channels", [2, 3])
def test_the_colour_distance_is_numpys_norm_to_the_bit(channels: int) -> None:
    """floor_mask's norm over colour channels gives np.linalg.norm's float32 bits (the same
    masks, so the same lines and surveys)."""
    from naoloc.perception.floorline import _norm_last

    rng = np.random.default_rng(5)
    v = (rng.normal(0.0, 40.0, (240, 320, channels))).astype(np.float32)
    got = _norm_last(v)
    assert got.dtype == np.float32
    assert np.array_equal(got, np.linalg.norm(v, axis=-1))


def render_skirting(
    pose: np.ndarray, wall_distance: float, *, shade: float, front: float | None = None
) -> np.ndarray:
    """A wall straight ahead on a blue-grey carpet, an 8 cm light-grey skirting board along
    its foot; left of column 110 the light is ``shade`` times as strong on the board (in
    shade a grey board passes for the carpet's colour). ``front``: a bench's front that
    far ahead in columns 110-210 (floor before the wall on either side of it)."""
    rng = np.random.default_rng(0)
    yaw = math.atan2(pose[1, 0], pose[0, 0])
    floor, _hit, z = trace(pose, yaw, wall_distance)
    cols = np.arange(320)[None, :]
    carpet = (
        np.array([125, 112, 100], float) * (1 + 0.08 * rng.standard_normal(floor.shape))[..., None]
    )
    board = np.where((cols < 110)[..., None], shade, 1.0) * np.array([185, 185, 182], float)
    wall = np.array([150, 160, 172], float)
    img = np.where(floor[..., None], carpet, np.where((z < 0.08)[..., None], board, wall))
    if front is not None:
        before, _hit, _z = trace(pose, yaw, front)
        bench = ((cols >= 110) & (cols < 210)) & ~before
        img = np.where(bench[..., None], np.array([40, 70, 110], float), img)
    return np.clip(img + rng.normal(0, 2, img.shape), 0, 255).astype(np.uint8)


@pytest.mark.parametrize("shade", [0.6, 0.7])
def test_a_skirting_board_in_shade_is_no_second_wall(shade: float) -> None:
    # Offices (stop 51): where the light makes a grey board pass for a grey carpet, the
    # board's top edge, 8 cm up, read as a second wall line 1.2 times as far.
    pose = camera_pose(0.0, 0.35)
    lines = detect_wall_lines(render_skirting(pose, 1.8, shade=shade), HFOV, VFOV, pose)
    assert [round(ln.distance, 1) for ln in lines] == [1.8]


def test_the_skirting_ghost_is_only_dropped_within_the_tuned_ratio() -> None:
    # The ghost stands 1.19 times as far as the foot: outside [1.3, 1.4] it is kept.
    pose = camera_pose(0.0, 0.35)
    image = render_skirting(pose, 1.8, shade=0.6)
    narrow = FloorLineTuning(ghost_ratio=(1.3, 1.4))
    lines = detect_wall_lines(image, HFOV, VFOV, pose, tun=narrow)
    assert [round(ln.distance, 1) for ln in lines] == [1.8, 2.2]


def test_a_wall_beyond_a_bench_stays_a_second_line() -> None:
    # The same ratio (1.25) with floor between: a wall seen on either side of a bench.
    pose = camera_pose(0.0, 0.35)
    lines = detect_wall_lines(render_skirting(pose, 1.5, shade=1.0, front=1.2), HFOV, VFOV, pose)
    assert sorted(round(ln.distance, 1) for ln in lines) == [1.2, 1.5]


@pytest.mark.parametrize(
    ("band", "ghost"),
    [
        ((40.0, 127.0, 128.0), True),  # the board in shade: its hue, not its lightness
        ((52.0, 127.0, 121.0), True),  # the board lit: its lightness
        ((36.0, 127.0, 120.5), False),  # floor (a wall beyond a bench)
        ((30.0, 127.0, 119.0), False),  # a darker plank of the floor, no nearer the board
    ],
)
def test_skirting_ghost_asks_whether_the_band_moved_toward_the_board(
    band: tuple[float, float, float], ghost: bool
) -> None:
    from naoloc.perception.floorline import skirting_ghost

    near = np.array([[57.0, 127.0, 128.0], [35.4, 127.0, 119.0]])  # board, floor
    below = np.array([35.4, 126.0, 120.0])
    assert skirting_ghost(near, np.array([band, below])) is ghost
