"""The localization filter's parts on synthetic observations: sensor models, the motion
model, one hypothesis' updates, the status decision (a table), proposals from lines."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from naoloc.config import FilterTuning
from naoloc.geometry import Pose2D
from naoloc.localization.filter import Belief, MultiHypothesisFilter, WalkingLines
from naoloc.localization.hypothesis import Hypothesis, motion_step
from naoloc.localization.line_poses import line_poses
from naoloc.localization.localizer import (
    PoseEstimate,
    Status,
    decide,
    frame_covariance,
    heading_std_of,
)
from naoloc.localization.pictures import (
    PictureMatches,
    RoomObjects,
    identity_evidence,
    landmarks_in_view,
    mixture,
    picture_log_ratio,
    reprojection,
)
from naoloc.localization.walls import WallMap, fit_line, wall_map
from naoloc.perception.floorline import WallLine

TUN = FilterTuning()
# A 6 x 4 m room whose wall frame is the map frame turned 0.3 rad and moved (1, -0.5).
WALLS = WallMap.of(Pose2D(1.0, -0.5, 0.3), (-1.0, 5.0, -1.0, 3.0))


def _line(walls: WallMap, pose: np.ndarray, k: int, span: float = 1.0) -> WallLine:
    """The floor line of wall ``k`` seen exactly from ``pose``."""
    dist, direction = walls.expected(pose)
    return WallLine(float(dist[k]), float(direction[k]), 200, 0.9, 0.01, span)


def test_walls_from_the_meta_and_what_a_pose_sees() -> None:
    meta = {"wall_poses": {"wall_frame": [1.0, -0.5, 0.3], "walls_m": [-1.0, 5.0, -1.0, 3.0]}}
    walls = wall_map(meta)
    assert walls is not None and np.allclose(walls.coords, WALLS.coords)
    assert wall_map({}) is None
    assert wall_map({"wall_poses": {"wall_frame": [0, 0, 0], "walls_m": [1, 0, 0, 1]}}) is None
    # At the wall frame's origin facing along its x: the +x wall 5 m ahead, +y 3 m left.
    dist, direction = WALLS.expected(np.array([1.0, -0.5, 0.3]))
    assert dist == pytest.approx([5.0, 3.0, 1.0, 1.0])
    assert direction == pytest.approx([0.0, math.pi / 2, math.pi, -math.pi / 2])
    assert WALLS.inside(1.0, -0.5, 0.5) and not WALLS.inside(-5.0, 0.0)


def test_a_seen_wall_explains_its_line_and_clutter_explains_a_stray_one() -> None:
    pose = np.array([2.0, 0.5, 0.7])
    fit = fit_line(WALLS, _line(WALLS, pose, 1), pose, TUN, None)
    assert fit.wall == 1 and np.allclose(fit.residual, 0.0) and fit.log_ratio > 3.0
    # Numerical Jacobian of the residual matches.
    eps = 1e-6
    for i in range(3):
        d = np.zeros(3)
        d[i] = eps
        moved = fit_line(WALLS, _line(WALLS, pose, 1), pose + d, TUN, None)
        num = (moved.residual - fit.residual) / eps
        assert num == pytest.approx(fit.jacobian[:, i], abs=1e-5)
    stray = WallLine(0.8, 0.45, 100, 0.5, 0.02, 0.6)  # a direction no wall has
    assert fit_line(WALLS, stray, pose, TUN, None).wall == -1


@pytest.mark.parametrize(
    ("beyond_m", "ends", "against"),
    [
        (0.0, None, "none"),  # the wall's own foot
        (-0.6, None, "none"),  # a front 0.6 m before the wall: clutter inside the room
        (0.6, None, "full"),  # 0.6 m beyond the wall: no wall nor furniture makes it
        (0.6, (-0.3, 0.3), "full"),  # the same, its inliers about the foot
        (0.03, None, "none"),  # 3 cm beyond, at 1.5 m: the wall's foot, its noise
        (0.15, None, "none"),  # 0.15 m beyond at 1.65 m: a skirting board's top edge
        (0.4, None, "full"),  # 0.4 m beyond: past the skirting's band and the noise
        (-0.6, (5.0, 6.0), "full"),  # before the wall ahead, its inliers 2 m beyond the side wall
        (-0.6, (-0.5, 6.0), "none"),  # ... its inliers from inside the room: a vertical edge
    ],
)
def test_a_line_beyond_the_walls_speaks_against_the_mapped_room(
    beyond_m: float, ends: tuple[float, float] | None, against: str
) -> None:
    """The beam model's part of the line likelihood (nav2 AMCL): clutter stands inside the
    walls, so a line beyond them (and beyond a skirting board's band, ``line_ghost_share``
    of its range) is only a detector's error (``line_beyond_share``); a wall's foot or a
    line inside the room says nothing against the room, nor does a line whose stretch
    begins inside it."""
    frame = Pose2D(1.0, -0.5, 0.3)
    here = frame * Pose2D(2.0, 1.5, math.pi / 2)  # in W: 1.5 m from the +y wall, facing it
    pose = np.array([here.x, here.y, here.theta])
    line = WallLine(1.5 + beyond_m, 0.0, 200, 0.9, 0.01, 1.0, ends)
    fit = fit_line(WALLS, line, pose, TUN, None)
    full = math.log(TUN.line_beyond_share)
    if against == "none":
        assert fit.log_beyond == pytest.approx(0.0, abs=0.01)
    else:
        assert fit.log_beyond == pytest.approx(full, abs=0.01) and fit.wall == -1
        assert fit.log_ratio == pytest.approx(0.0, abs=0.01)  # among the places: clutter
    # The pose's own uncertainty makes a line beyond the walls less telling.
    if against != "none":
        vague = fit_line(WALLS, line, pose, TUN, np.diag([0.3**2, 0.3**2, 0.1**2]))
        assert vague.log_beyond > fit.log_beyond


def test_a_scan_says_at_most_identity_floor_nats_against_the_room() -> None:
    """However many lines a scan shows beyond the walls, it says at most
    ``identity_floor_nats`` against the room (its lines share one view), and nothing among
    the places (a place that lost nats to one scan would hand the lead to another)."""
    frame = Pose2D(1.0, -0.5, 0.3)
    here = frame * Pose2D(2.0, 1.5, math.pi / 2)
    pose = np.array([here.x, here.y, here.theta])
    far = tuple(WallLine(2.5 + 0.1 * k, 0.0, 200, 0.9, 0.01, 1.0) for k in range(4))
    h = Hypothesis(pose, np.diag([0.01**2, 0.01**2, 0.005**2]), TUN)
    ev, against = h.update_lines(WALLS, far, TUN)
    assert against == pytest.approx(-TUN.identity_floor_nats)
    assert ev == pytest.approx(0.0, abs=1e-6)
    assert h.line_support == 0 and np.allclose(h.pose, pose)


def test_a_furniture_front_the_survey_saw_explains_its_line_where_it_stands() -> None:
    """A front 0.35 m before the +y wall, seen over x 1-3 m of W: a line on it, from a pose
    that sees it, is the front's (no residual), not the wall's seen from a pose 0.35 m off;
    beyond the stretch seen the same line is not the front's; the meta's malformed fronts
    are dropped."""
    faces = [[1, 0.35, 1.0, 3.0, 3.0, 3.0]]
    meta = {"wall_poses": {"wall_frame": [1.0, -0.5, 0.3], "walls_m": [-1.0, 5.0, -1.0, 3.0],
                           "faces": [*faces, [1, 0.35, 1.0], [7, 0.3, 0, 0, 1, 0],
                                     [1, -0.2, 0, 0, 1, 0], [1, True, 0, 0, 1, 0]]}}  # fmt: skip
    walls = wall_map(meta)
    assert walls is not None and walls.faces.shape == (1, 4)
    assert walls.faces[0, 1] == pytest.approx(WALLS.coords[1] - 0.35)
    frame = Pose2D(1.0, -0.5, 0.3)
    here = frame * Pose2D(2.0, 1.5, math.pi / 2)  # in W: 1.5 m from the +y wall, facing it
    pose = np.array([here.x, here.y, here.theta])
    line = WallLine(1.5 - 0.35, 0.0, 200, 0.9, 0.01, 1.0)  # the front, straight ahead
    fit = fit_line(walls, line, pose, TUN, None)
    assert fit.wall >= 4 and np.allclose(fit.residual, 0.0, atol=1e-9)
    assert fit_line(WALLS, line, pose, TUN, None).wall in (-1, 1)  # no front: the wall, 0.35 off
    beyond = frame * Pose2D(4.6, 1.5, math.pi / 2)  # the same line where no front was seen
    far = fit_line(walls, line, np.array([beyond.x, beyond.y, beyond.theta]), TUN, None)
    assert far.wall < 4


def test_the_motion_model_moves_and_grows_uncertainty_with_the_walk() -> None:
    pose, cov = np.array([1.0, 2.0, math.pi / 2]), np.zeros((3, 3))
    new, grown = motion_step(pose, cov, np.array([1.0, 0.0, 0.0]), TUN)
    assert new == pytest.approx([1.0, 3.0, math.pi / 2])
    assert math.sqrt(grown[1, 1]) == pytest.approx(TUN.trans_per_m + TUN.floor_m)
    same, still = motion_step(pose, cov, np.zeros(3), TUN)
    assert np.array_equal(same, pose) and not still.any()  # standing adds no noise
    # A quarter turn in place: the feet slip, so the position is less sure too.
    turned, slipped = motion_step(pose, cov, np.array([0.0, 0.0, math.pi / 2]), TUN)
    assert turned[:2] == pytest.approx(pose[:2])
    sigma = math.hypot(TUN.floor_m, TUN.slip_per_sqrt_rad * math.sqrt(math.pi / 2))
    assert math.sqrt(slipped[0, 0]) == pytest.approx(sigma)
    assert math.sqrt(slipped[1, 1]) == pytest.approx(sigma)


def _picture(pose: np.ndarray, n: int = 60, seed: int = 0, wrong: float = 0.0) -> PictureMatches:
    """Landmarks 1-3 m in front of a camera at ``pose`` and their exact pixels."""
    rng = np.random.default_rng(seed)
    k = np.array([[278.0, 0, 160], [0, 278.0, 120], [0, 0, 1]])
    cam = np.array([[0, 0, 1, 0.05], [-1, 0, 0, 0], [0, -1, 0, 0.45], [0, 0, 0, 1.0]])
    projection = k @ np.linalg.inv(cam)[:3, :]
    c, s = math.cos(pose[2]), math.sin(pose[2])
    local = np.column_stack(
        [rng.uniform(1, 3, n), rng.uniform(-0.8, 0.8, n), rng.uniform(0.3, 1.5, n)]
    )
    points = np.column_stack(
        [pose[0] + c * local[:, 0] - s * local[:, 1], pose[1] + s * local[:, 0] + c * local[:, 1],
         local[:, 2]]
    )  # fmt: skip
    m0 = PictureMatches(points, np.zeros((n, 2)), np.arange(n), 1, points, np.zeros((n, 2)),
                        projection, 320 * 240.0, n, (), None, 0)  # fmt: skip
    res, _front, _ = reprojection(m0, pose)
    pixels = res.copy()
    bad = rng.random(n) < wrong
    pixels[bad] = rng.uniform([0, 0], [320, 240], (int(bad.sum()), 2))
    return PictureMatches(points, pixels, np.arange(n), 1, points, pixels, projection,
                          320 * 240.0, n, (), None, 0, points, pixels)  # fmt: skip


def _object_picture(pose: np.ndarray, centre: tuple[float, float], seed: int) -> PictureMatches:
    """A picture from ``pose`` whose 40 distinctive matches all lie on one print 0.4 m wide
    centred at ``centre`` (x, y in the map frame, 0.6-1.0 m up), exact pixels."""
    rng = np.random.default_rng(seed)
    m = _picture(pose, n=40, seed=seed)
    points = np.column_stack(
        [centre[0] + rng.uniform(-0.02, 0.02, 40), centre[1] + rng.uniform(-0.2, 0.2, 40),
         rng.uniform(0.6, 1.0, 40)]
    )  # fmt: skip
    zero = np.zeros((40, 2))
    probe = dataclasses.replace(m, points=points, pixels=zero, matched=points, distinct=points)
    pixels, _front, _ = reprojection(probe, pose)  # the residual from no pixel: the pixel
    return dataclasses.replace(
        probe, pixels=pixels, matched_pixels=pixels, distinct_pixels=pixels.copy()
    )


def test_one_object_seen_again_speaks_for_the_room_once() -> None:
    """A print seen in five pictures gives a place at most ``identity_cap_nats`` that this
    is the mapped room (its twin may hang in another room); a second print 2 m away gives
    as much again; an object's credit forgets with the room evidence, and tops up."""
    pose = np.array([1.0, 1.0, 0.0])
    objects = RoomObjects()
    first = identity_evidence(_object_picture(pose, (3.0, 1.0), 0), pose, TUN, objects)
    assert first == pytest.approx(TUN.identity_cap_nats)
    again = [identity_evidence(_object_picture(pose, (3.0, 1.0), k), pose, TUN, objects)
             for k in range(1, 5)]  # fmt: skip
    assert sum(again) == pytest.approx(0.0, abs=1e-9) and len(objects.credit) == 1
    other = identity_evidence(_object_picture(pose, (3.0, 3.0), 9), pose, TUN, objects)
    assert other == pytest.approx(TUN.identity_cap_nats) and len(objects.credit) == 2
    objects.forget(0.5)
    topped = identity_evidence(_object_picture(pose, (3.0, 1.0), 11), pose, TUN, objects)
    assert topped == pytest.approx(TUN.identity_cap_nats / 2)
    # Matches that do not fit the pose speak for no object.
    elsewhere = np.array([1.0, 1.5, 0.3])
    assert identity_evidence(_object_picture(pose, (3.0, 5.0), 12), elsewhere, TUN, objects) < 0.5


def test_reprojection_jacobian_is_the_numerical_one() -> None:
    pose = np.array([0.5, -0.2, 0.4])
    m = _picture(pose)
    res, front, jac = reprojection(m, pose + np.array([0.02, -0.01, 0.01]), jacobian=True)
    assert front.all() and jac is not None
    eps = 1e-7
    for i in range(3):
        d = np.zeros(3)
        d[i] = eps
        moved, _, _ = reprojection(m, pose + np.array([0.02, -0.01, 0.01]) + d)
        assert (moved - res) / eps == pytest.approx(jac[:, :, i], abs=1e-3)


def test_the_picture_model_prefers_the_true_pose_and_shrugs_off_wrong_matches() -> None:
    pose = np.array([0.5, -0.2, 0.4])
    m = _picture(pose, wrong=0.4)
    at_truth = picture_log_ratio(m, pose, TUN)
    assert at_truth > picture_log_ratio(m, pose + np.array([0.2, 0.0, 0.0]), TUN) + 5
    assert picture_log_ratio(m, pose + np.array([0.0, 0.0, 0.5]), TUN) < 1.0
    res, front, _ = reprojection(m, pose)
    resp, _ = mixture(m, res, front, np.eye(2) * 4.0, TUN)
    exact = np.hypot(res[:, 0], res[:, 1]) < 1e-6
    assert (resp[exact] > 0.9).all() and (resp[~exact] < 0.1).mean() > 0.9


def test_a_hypothesis_walks_to_the_pose_a_picture_and_lines_show() -> None:
    truth = np.array([2.0, 0.5, 0.7])
    h = Hypothesis(truth + np.array([0.08, -0.06, 0.03]), np.diag([0.1**2, 0.1**2, 0.05**2]), TUN)
    fit = h.update_picture(_picture(truth, wrong=0.3), TUN)
    assert fit.updated and fit.inliers > 30
    assert math.hypot(*(h.pose[:2] - truth[:2])) < 0.03
    lines = (_line(WALLS, truth, 0), _line(WALLS, truth, 1))
    ev, against = h.update_lines(WALLS, lines, TUN)
    assert ev > 0 and h.line_support == 2 and against == pytest.approx(0.0, abs=0.01)
    assert math.hypot(*(h.pose[:2] - truth[:2])) < 0.03 and abs(h.pose[2] - truth[2]) < 0.01
    # The walls make it better than the landmarks' own error; the covariance says so.
    assert math.sqrt(h.cov[0, 0]) < TUN.landmark_sigma_m
    # A hypothesis elsewhere finds no support in the same picture.
    far = Hypothesis(truth + np.array([1.5, 0.0, 0.0]), np.diag([0.05**2, 0.05**2, 0.02**2]), TUN)
    assert not far.update_picture(_picture(truth), TUN).updated


def _belief(**kw: object) -> Belief:
    base: dict[str, object] = {
        "pose": np.zeros(3), "cov": np.diag([0.02**2, 0.02**2, 0.01**2]), "probability": 0.99,
        "other_room": 0.0, "hypotheses": 1, "support": 3, "score": 50.0, "seen_score": 40.0,
        "pictures": 6,
        "contradicted": False,
    }  # fmt: skip
    base.update(kw)
    return Belief(**base)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("changes", "status"),
    [
        ({}, Status.TRACKING),
        ({"probability": 0.6}, Status.LOST),  # two places share the belief
        ({"cov": np.diag([0.3**2, 0.02**2, 0.01**2])}, Status.LOST),  # too wide
        ({"contradicted": True}, Status.LOST),  # the latest picture says elsewhere
        ({"seen_score": 10.0}, Status.LOST),  # floor lines alone: any corner fits them
        ({"probability": 0.2, "other_room": 0.8}, Status.NOT_MAPPED),
        ({"probability": 0.2, "other_room": 0.8, "pictures": 2}, Status.LOST),  # too early
        ({"pose": None, "cov": None, "pictures": 9}, Status.NOT_MAPPED),
        ({"pose": None, "cov": None, "pictures": 1}, Status.LOST),
        # A robot that recognised the room before (it was carried, or lost its place):
        # no pose, but not "another room" either.
        ({"probability": 0.2, "other_room": 0.8, "room_seen": 25.0}, Status.LOST),
        ({"pose": None, "cov": None, "pictures": 9, "room_seen": 25.0}, Status.LOST),
        ({"probability": 0.2, "other_room": 0.8, "room_seen": 15.0}, Status.NOT_MAPPED),
    ],
)
def test_the_status_is_a_function_of_the_belief(changes: dict, status: Status) -> None:
    got, reason = decide(_belief(**changes), TUN)
    assert got is status and (reason == "") == (status is Status.TRACKING)


def test_the_lines_of_a_corner_propose_the_pose_modulo_the_rooms_symmetry() -> None:
    truth = np.array([2.0, 0.5, 0.7])
    lines = [_line(WALLS, truth, 0), _line(WALLS, truth, 1), _line(WALLS, truth, 2)]
    poses = line_poses(lines, WALLS, TUN)
    near = [p for p in poses if math.hypot(*(p[:2] - truth[:2])) < 1e-6]
    assert near and abs(math.remainder(near[0][2] - truth[2], 2 * math.pi)) < 1e-6
    # At the truth's quarter turn only, the truth is the one pose.
    only = line_poses(lines, WALLS, TUN, heading=truth[2] + 0.05)
    assert len(only) == 1 and np.allclose(only[0], truth, atol=1e-6)
    assert line_poses(lines[:1], WALLS, TUN) == []  # one line gives no pose


def test_the_filter_starts_from_the_lines_and_a_picture_decides() -> None:
    truth = np.array([2.0, 0.5, 0.7])
    f = MultiHypothesisFilter(WALLS, TUN)
    odo = Pose2D(10.0, -3.0, 1.0)  # the odometry frame is anywhere
    lines = tuple(_line(WALLS, truth, k) for k in (0, 1, 2))
    f.observe(lines, odo)
    assert len(f.hypotheses) >= 1  # the corner's poses (no picture to rank them yet)
    f.observe(_picture(truth, seed=1, wrong=0.3), odo)
    f.observe(lines, odo)
    f.observe(_picture(truth, seed=2, wrong=0.3), odo)
    f.observe(_picture(truth, seed=3, wrong=0.3), odo)  # no one picture proves the room
    b = f.belief()
    assert b.pose is not None and math.hypot(*(b.pose[:2] - truth[:2])) < 0.02
    assert decide(b, TUN)[0] is Status.TRACKING


@pytest.mark.parametrize(("grow_m", "status"), [(0.0, Status.TRACKING), (0.6, Status.LOST)])
def test_the_same_pictures_in_a_larger_room_do_not_make_a_place(
    grow_m: float, status: Status
) -> None:
    """Pictures that match the map (a room whose posters are the mapped room's) with floor
    lines 0.6 m beyond the map's walls (a larger room): each scan speaks against the room
    (``identity_floor_nats``), so two pictures that make a place in the mapped room leave
    the other-room alternative ahead there."""
    truth = np.array([2.0, 0.5, 0.7])
    f = MultiHypothesisFilter(WALLS, TUN)
    odo = Pose2D(10.0, -3.0, 1.0)
    seen = (_line(WALLS, truth, k) for k in (0, 1, 2))
    lines = tuple(dataclasses.replace(line, distance=line.distance + grow_m) for line in seen)
    f.observe(lines, odo)
    for seed in (1, 2):
        f.observe(_picture(truth, seed=seed, wrong=0.3), odo)
        f.observe(lines, odo)
    b = f.belief()
    assert decide(b, TUN)[0] is status
    assert (b.other_room > 0.9) is (grow_m > 0)


def test_a_merged_hypothesis_keeps_what_the_pictures_showed_of_the_room() -> None:
    f = MultiHypothesisFilter(WALLS, TUN)
    old = Hypothesis(np.array([2.0, 0.5, 0.7]), np.diag([0.02**2, 0.02**2, 0.01**2]), TUN, 50.0)
    new = Hypothesis(np.array([2.005, 0.5, 0.7]), np.diag([0.02**2, 0.02**2, 0.01**2]), TUN, 55.0)
    old.seen_score, new.seen_score = 40.0, 3.0  # the new one was spawned from the window
    f.hypotheses = [old, new]
    f._prune()
    assert len(f.hypotheses) == 1 and f.hypotheses[0] is new
    assert f.hypotheses[0].seen_score == 40.0


@pytest.mark.parametrize(
    ("second", "weight", "probability", "status"),
    [
        # Two sharp hypotheses 3 cm apart (2.5 sd each: not merged) are one place.
        ((2.03, 0.5, 0.7), 1.0, 1.0, Status.TRACKING),
        # 0.3 m apart and as likely: the belief's spread covers both, and is too wide.
        ((2.3, 0.5, 0.7), 1.0, 1.0, Status.LOST),
        # The same place turned 0.3 rad, as likely: too wide in heading.
        ((2.0, 0.5, 1.0), 1.0, 1.0, Status.LOST),
        # A place 2 m away with 1/20 of the best's weight stands outside the belief's 99 %
        # region (the spread it adds is 0.45 m): the best place holds 20/21 of the belief.
        ((4.0, 0.5, 0.7), 0.05, 1 / 1.05, Status.LOST),
        # ... with 1/1000 of the weight: the best place is sure.
        ((4.0, 0.5, 0.7), 0.001, 1 / 1.001, Status.TRACKING),
    ],
)
def test_a_belief_is_concentrated_by_the_places_inside_its_own_region(
    second: tuple[float, float, float], weight: float, probability: float, status: Status
) -> None:
    f = MultiHypothesisFilter(WALLS, TUN)
    cov = np.diag([0.012**2, 0.012**2, 0.005**2])
    a = Hypothesis(np.array([2.0, 0.5, 0.7]), cov, TUN, 50.0)
    b = Hypothesis(np.array(second), cov, TUN, 50.0 + math.log(weight))
    a.seen_score = b.seen_score = 40.0
    f.hypotheses = [a, b]
    belief = f.belief()
    assert belief.probability == pytest.approx(probability, abs=1e-3)
    assert decide(belief, TUN)[0] is status


def test_a_line_of_furniture_before_a_wall_is_not_the_wall() -> None:
    """Fronts 0.15 m before a wall 2.3 m away: clutter, not the wall (the lines' measured
    noise there is 0.02 m; with the noise once assumed, 0.07 m, they pulled the pose toward
    the wall); the wall's own line is explained."""
    pose = np.array([2.0, 0.5, 0.7])
    wall = _line(WALLS, pose, 1)
    assert 2.0 < wall.distance < 2.5
    cov = np.diag([0.02**2, 0.02**2, 0.01**2])
    assert fit_line(WALLS, wall, pose, TUN, cov).wall == 1
    front = dataclasses.replace(wall, distance=wall.distance - 0.15)
    assert fit_line(WALLS, front, pose, TUN, cov).wall == -1


@pytest.mark.parametrize(("walked_m", "explained"), [(0.0, False), (0.05, True)])
def test_lines_taken_walking_are_weighed_at_the_walking_noise(
    walked_m: float, explained: bool
) -> None:
    """The same line 0.15 m before a wall 2.3 m away: standing, clutter (the measured
    noise); after the odometry walked, the wall (the camera sways with the gait)."""
    pose = np.array([2.0, 0.5, 0.7])
    front = dataclasses.replace(
        _line(WALLS, pose, 1), distance=_line(WALLS, pose, 1).distance - 0.15
    )
    f = MultiHypothesisFilter(WALLS, TUN)
    h = Hypothesis(pose.copy(), np.diag([0.02**2, 0.02**2, 0.01**2]), TUN, 50.0)
    f.hypotheses = [h]
    f.observe(None, Pose2D(0.0, 0.0, 0.0))
    f.observe((front,), Pose2D(walked_m, 0.0, 0.0))
    walked = isinstance(f.window[-1][0], WalkingLines)
    assert walked == (walked_m > 0)
    assert (h.line_support > 0) == explained


def test_the_room_evidence_is_the_places_by_their_weight() -> None:
    """Two places equally likely, one of which the pictures showed to be the mapped room
    many times: the room is the mapped one, whichever place leads."""
    f = MultiHypothesisFilter(WALLS, TUN)
    a = Hypothesis(np.array([2.0, 0.5, 0.7]), np.eye(3) * 1e-4, TUN, 50.0)
    b = Hypothesis(np.array([1.0, 0.5, 0.7]), np.eye(3) * 1e-4, TUN, 50.0)
    a.seen_score, b.seen_score = 3.0, 60.0
    f.hypotheses = [a, b]
    assert f.belief().other_room < 1e-6
    a.seen_score = b.seen_score = 3.0
    assert f.belief().other_room > 0.99


@pytest.mark.parametrize(
    ("seen", "room_seen", "status"),
    [
        (21.0, 0.0, Status.LOST),  # only this place showed the room: "another room" weighs
        (21.0, 30.0, Status.TRACKING),  # the room was recognised before: the place suffices
        (5.0, 30.0, Status.LOST),  # the room is known, but no picture has shown this place
    ],
)
def test_a_recognised_room_speaks_for_a_new_place(
    seen: float, room_seen: float, status: Status
) -> None:
    """A place found again after the robot lost it (or was carried) needs its own pictures
    to show it (``null_nats``), not to prove the room once more."""
    f = MultiHypothesisFilter(WALLS, TUN)
    h = Hypothesis(np.array([2.0, 0.5, 0.7]), np.eye(3) * 1e-4, TUN, 50.0)
    h.seen_score = seen
    f.hypotheses = [h]
    f.room_seen = room_seen
    assert decide(f.belief(), TUN)[0] is status


def test_a_picture_no_place_explains_does_not_contradict_the_leader() -> None:
    """A blurred view (no distinctive match, no PnP pose) explains nothing of the leader,
    nor of anywhere else: it says nothing, and the leader keeps tracking."""
    truth = np.array([2.0, 0.5, 0.7])
    f = MultiHypothesisFilter(WALLS, TUN)
    odo = Pose2D(0.0, 0.0, 0.0)
    f.observe(None, odo)
    f.set_pose(truth, np.diag([0.01**2, 0.01**2, 0.005**2]), 40.0)
    f.hypotheses[0].usual = f.hypotheses[0].recent = 3 * TUN.contradiction_nats  # usually fit
    for seed in range(4):  # every match wrong and none distinctive: a blurred view
        blurred = dataclasses.replace(
            _picture(truth, seed=seed, wrong=1.0),
            distinct=np.zeros((0, 3)),
            distinct_pixels=np.zeros((0, 2)),
        )
        f.observe(blurred, odo)
        assert f.hypotheses[0].recent == 3 * TUN.contradiction_nats and not f.contradicted
    assert decide(f.belief(), TUN)[1] != "the latest picture puts the robot elsewhere"


def test_a_view_the_leader_no_longer_explains_contradicts_it() -> None:
    """Distinctive matches the leading place explains nothing of, where its pictures
    usually fit well (a carried robot): it gives no pose at once, and its past evidence
    no longer outweighs a new place."""
    truth = np.array([2.0, 0.5, 0.7])
    f = MultiHypothesisFilter(WALLS, TUN)
    odo = Pose2D(0.0, 0.0, 0.0)
    f.observe(None, odo)
    f.set_pose(truth, np.diag([0.01**2, 0.01**2, 0.005**2]), 40.0)
    f.hypotheses[0].usual = f.hypotheses[0].recent = 5 * TUN.contradiction_nats
    f.observe(_picture(truth + np.array([1.5, -0.5, 1.0]), seed=5), odo)  # somewhere else
    assert f.contradicted
    assert decide(f.belief(), TUN)[0] is not Status.TRACKING


def test_a_map_whose_laps_disagree_reports_its_own_error_in_the_covariance() -> None:
    """The map's keyframes' error (meta ``keyframe_sigma_m``, from how its survey's laps
    disagree) is a floor of the reported covariance when it exceeds the tuning's; a map
    without it, or with less, keeps ``map_floor_m``; a malformed value is no floor."""
    from naoloc.localization.localizer import keyframe_sigma_of

    tun = FilterTuning()
    pose = np.array([1.0, 2.0, 0.3])
    tight = np.diag([0.001**2, 0.001**2, 0.001**2])
    for floor, expected in ((None, tun.map_floor_m), (0.005, tun.map_floor_m), (0.05, 0.05)):
        f = MultiHypothesisFilter(None, tun, map_floor_m=floor)
        f.set_pose(pose, tight, 40.0)
        cov = f.belief().cov
        assert cov is not None
        assert cov[0, 0] == pytest.approx(expected**2 + 0.001**2)
        assert cov[1, 1] == pytest.approx(expected**2 + 0.001**2)
    assert keyframe_sigma_of({"keyframe_sigma_m": 0.04}) == 0.04
    for bad in ({}, {"keyframe_sigma_m": None}, {"keyframe_sigma_m": "0.04"},
                {"keyframe_sigma_m": -1.0}, {"keyframe_sigma_m": float("nan")},
                {"keyframe_sigma_m": True}):  # fmt: skip
        assert keyframe_sigma_of(bad) is None


def test_a_recognised_room_stays_recognised_when_the_place_is_lost() -> None:
    """The room's evidence a probable place gave outlives the place: pictures that fit no
    place (a carried robot's blank wall) make the belief lost, not "another room"."""
    truth = np.array([2.0, 0.5, 0.7])
    f = MultiHypothesisFilter(WALLS, TUN)
    odo = Pose2D(0.0, 0.0, 0.0)
    lines = tuple(_line(WALLS, truth, k) for k in (0, 1, 2))
    f.observe(lines, odo)
    for seed in range(1, 7):
        f.observe(_picture(truth, seed=seed, wrong=0.3), odo)
    assert decide(f.belief(), TUN)[0] is Status.TRACKING
    assert f.belief().room_seen >= TUN.null_nats
    # Carried: every picture's matches are now wrong for every place of the map.
    for seed in range(10, 30):
        f.observe(_picture(truth + np.array([1.3, 0.9, 2.0]), seed=seed, wrong=1.0), odo)
    status, _ = decide(f.belief(), TUN)
    assert status is Status.LOST
    # A fresh filter given the same wrong pictures says it is not the mapped room.
    g = MultiHypothesisFilter(WALLS, TUN)
    for seed in range(10, 30):
        g.observe(_picture(truth + np.array([1.3, 0.9, 2.0]), seed=seed, wrong=1.0), odo)
    assert decide(g.belief(), TUN)[0] is Status.NOT_MAPPED


def _empty(pose: np.ndarray) -> PictureMatches:
    """A picture from ``pose`` with no features at all (a blank view), 320 x 240 px."""
    m = _picture(pose, n=1)
    none3, none2 = np.zeros((0, 3)), np.zeros((0, 2))
    return PictureMatches(none3, none2, np.zeros(0, np.int64), 1, none3, none2, m.projection,
                          320 * 240.0, 0, (), None, 0, size_px=(320, 240))  # fmt: skip


@pytest.mark.parametrize(
    ("local", "counted"),
    [
        ((2.0, 0.0, 0.45), True),  # ahead, at the camera's height
        ((2.0, 0.3, 1.0), True),
        ((-2.0, 0.0, 0.45), False),  # behind
        ((2.0, 3.0, 0.45), False),  # beside: outside the image
        ((5.0, 0.0, 0.45), False),  # beyond the range
        ((2.0, 0.0, 6.0), False),  # above the image
    ],
)
def test_the_landmarks_a_picture_should_show_from_a_pose(local: tuple, counted: bool) -> None:
    pose = np.array([1.0, -0.5, 0.8])
    c, s = math.cos(pose[2]), math.sin(pose[2])
    point = np.array([[pose[0] + c * local[0] - s * local[1],
                       pose[1] + s * local[0] + c * local[1], local[2]]])  # fmt: skip
    m = _empty(pose)
    assert landmarks_in_view(point, m, pose, 4.0) == int(counted)
    assert landmarks_in_view(point, dataclasses.replace(m, size_px=(0, 0)), pose, 4.0) == 0


def test_a_blank_view_where_the_map_expects_landmarks_fades_the_place() -> None:
    """Negative information: a carried robot facing a blank wall, where the leading place's
    map shows many landmarks in view, explains none of them; within a few pictures the
    place gives no pose, and a place beside it that explains the view no better loses its
    past too. With no landmarks in view from the place, the same pictures say nothing."""
    truth = np.array([2.0, 0.5, 0.7])
    rng = np.random.default_rng(7)
    n = TUN.expected_landmarks + 20
    local = np.column_stack([rng.uniform(2, 3, n), rng.uniform(-0.5, 0.5, n),
                             rng.uniform(0.3, 0.6, n)])  # fmt: skip
    c, s = math.cos(truth[2]), math.sin(truth[2])
    expected = np.column_stack([truth[0] + c * local[:, 0] - s * local[:, 1],
                                truth[1] + s * local[:, 0] + c * local[:, 1],
                                local[:, 2]])  # fmt: skip
    assert landmarks_in_view(expected, _empty(truth), truth, TUN.expect_range_m) == n
    for landmarks, fades in ((expected, True), (None, False), (expected[:10], False)):
        f = MultiHypothesisFilter(WALLS, TUN, landmarks=landmarks)
        odo = Pose2D(0.0, 0.0, 0.0)
        f.observe(None, odo)
        f.set_pose(truth, np.diag([0.01**2, 0.01**2, 0.005**2]), 80.0)
        beside = Hypothesis(truth + np.array([0.3, 0.0, 0.0]), np.eye(3) * 1e-4, TUN, 70.0)
        f.hypotheses.append(beside)
        for h in f.hypotheses:
            h.usual = h.recent = 3 * TUN.contradiction_nats
            h.seen_score = 2 * TUN.null_nats  # its pictures showed the room
        for _ in range(5):
            f.observe(_empty(truth), odo)
        assert f.contradicted is fades
        assert (decide(f.belief(), TUN)[0] is Status.TRACKING) is not fades
        assert all(h.score <= 0.0 for h in f.hypotheses) is fades


@pytest.mark.parametrize(
    ("meta", "expected"),
    [
        ({"wall_poses": {"heading_std_rad": 0.012}}, 0.012),
        ({"wall_poses": {}}, 0.005),  # older maps: the tuning's
        ({}, 0.005),
        ({"wall_poses": {"heading_std_rad": "x"}}, 0.005),
        ({"wall_poses": {"heading_std_rad": -1.0}}, 0.005),
        ({"wall_poses": {"heading_std_rad": float("nan")}}, 0.005),
    ],
)
def test_the_map_frames_heading_error_comes_from_the_map(
    meta: dict[str, object], expected: float
) -> None:
    assert heading_std_of(meta, FilterTuning().map_frame_rad) == expected


def test_the_map_frames_heading_error_grows_across_with_the_distance_from_the_origin() -> None:
    """A map turned 1 deg about its origin puts a place 5 m along x 8.7 cm off along y: the
    covariance admits that across the ray from the origin, not along it."""
    sigma = math.radians(1.0)
    at_origin = frame_covariance(np.array([0.0, 0.0, 0.3]), sigma)
    assert at_origin[:2, :2] == pytest.approx(np.zeros((2, 2)))
    assert at_origin[2, 2] == pytest.approx(sigma**2)
    far = frame_covariance(np.array([5.0, 0.0, 0.3]), sigma)
    assert math.sqrt(far[1, 1]) == pytest.approx(5.0 * sigma)
    assert far[0, 0] == pytest.approx(0.0)
    assert far[1, 2] == pytest.approx(5.0 * sigma**2)  # position and heading turn together
    # the estimate's own spread leaves it out; the reported covariance keeps it
    base = np.diag([0.02**2, 0.02**2, 0.01**2])
    est = PoseEstimate(5.0, 0.0, 0.3, base + far, 1.0, Status.TRACKING, map_frame=far)
    assert est.sigmas()[0] == pytest.approx(math.hypot(0.02, 5.0 * sigma))
    assert est.sigmas(frame=False)[0] == pytest.approx(0.02)


@pytest.mark.parametrize(("walked_m", "found"), [(0.0, True), (0.002, False)])
def test_a_neighbour_the_pictures_favour_is_tried_though_the_leader_covers_it(
    walked_m: float, found: bool
) -> None:
    """A hypothesis 0.3 m off along the walls, within the proposal gate of the truth, where
    the pictures' matches pull it only part of the way (their residuals there are the
    robust model's outliers): at rest, exploring its neighbours along the walls' axes finds
    the place the pictures favour though the leader's gate covers it, and it takes the
    lead. Walking (the scan's odometry moved), the leader's gate still decides: the
    window's quick score carries the walk's odometry error."""
    truth = np.array([2.0, 0.5, 0.3])
    f = MultiHypothesisFilter(WALLS, TUN)
    odo = Pose2D(0.0, 0.0, 0.0)
    f.observe(None, odo)
    off = truth.copy()
    off[:2] += 0.3 * np.array([math.cos(0.3), math.sin(0.3)])  # along the wall frame's x
    f.set_pose(off, np.diag([0.02**2, 0.02**2, 0.01**2]), 0.0)
    for seed in (1, 2, 3):
        f.observe(_picture(truth, seed=seed), odo)
    # Lines of the walls across the offset's axis (the +-y walls): they place only y.
    lines = tuple(_line(WALLS, truth, k) for k in (1, 3))
    f.observe(lines, Pose2D(odo.x + walked_m, odo.y, odo.theta))
    b = f.belief()
    assert b.pose is not None
    assert (math.hypot(*(b.pose[:2] - truth[:2])) < 0.05) is found
