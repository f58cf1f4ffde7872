"""Test poses of the evaluation protocols, and the seed paper's own figures.

Two protocols (docs/cli.md, `evaluate`):

- ``paper``: the Table 3 positions of Trujillo-Romero (2024) in the map frame, five
  evaluations each. The paper gives positions only; the heading at each position is ours
  (:data:`PAPER_POSITIONS`): the direction the survey walked along the nearest side of the
  circuit, so the nearest wall is on the robot's right as during the survey. The five
  evaluations differ by a seeded heading perturbation, uniform in +-``PAPER_HEADING_JITTER_RAD``,
  and by the seed handed to the localizer.
- ``random``: N poses drawn with a seed, uniform over the free floor (no furniture within
  the robot's clearance) whose distance to the nearest wall is 0.6 to 1.4 m, each with a
  uniform random heading.

Frames: the map frame is the odometry frame at the start of the survey; the room frame has
its origin at a room corner with x and y along the walls. ``origin_room_pose`` (the true pose
when the survey started) links them: ``room = origin * map`` and
``map = relative_pose(origin, room)``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from naoloc.errors import ConfigError
from naoloc.geometry import Pose2D, modulo2PI, relative_pose

# Table 1: lap, images, images per wall 1..4 (walls numbered counter-clockwise).
PAPER_TABLE1: tuple[tuple[int, int, tuple[int, int, int, int]], ...] = (
    (1, 89, (20, 21, 31, 17)),
    (2, 75, (18, 20, 24, 13)),
)

# Table 2: experiment, training images, neurons, epochs, training time (s), distinct poses.
PAPER_TABLE2: tuple[tuple[int, int, int, int, float, int], ...] = (
    (1, 164, 100, 100, 4.063, 72),
    (2, 164, 200, 200, 14.287, 111),
    (3, 164, 300, 300, 33.347, 132),
)

#: Half-width of the seeded heading perturbation between the five paper evaluations (rad).
PAPER_HEADING_JITTER_RAD = math.radians(10.0)

#: Evaluations per position in the paper protocol (Table 3 columns 1..5).
PAPER_EVALUATIONS = 5

#: Survey square of the paper protocol, metres along x and y.
PAPER_SQUARE_M = (4.0, 4.0)


@dataclass(frozen=True, slots=True)
class PaperPosition:
    """One row of the paper's Table 3.

    Attributes:
        number: Experiment number (1-4).
        paper_map: The map the paper used (1: 100 neurons, 2: 200, 3: 300).
        x: Truth x in the map frame (m).
        y: Truth y in the map frame (m).
        heading: Our base heading at the position, map frame (rad); the paper gives none.
        paper_estimates: The paper's five estimates (x, y) in the map frame (m).
    """

    number: int
    paper_map: int
    x: float
    y: float
    heading: float
    paper_estimates: tuple[tuple[float, float], ...]

    def paper_mean_error_m(self) -> float:
        """Mean Euclidean error of the paper's five estimates (m)."""
        return float(
            np.mean([math.hypot(ex - self.x, ey - self.y) for ex, ey in self.paper_estimates])
        )


PAPER_POSITIONS: tuple[PaperPosition, ...] = (
    PaperPosition(
        1, 1, 3.5, 0.5, 0.0, ((3.7, 1.7), (3.6, 1.6), (3.7, 1.7), (3.8, 1.8), (3.3, 1.7))
    ),
    PaperPosition(
        2, 1, 0.0, 0.0, 0.0, ((0.1, 0.2), (0.2, 0.2), (0.3, 0.1), (0.3, 0.0), (0.3, 0.2))
    ),
    PaperPosition(
        3, 2, 0.5, 3.5, -math.pi / 2, ((0.0, 2.0), (0.0, 2.0), (0.2, 2.2), (0.0, 2.0), (0.2, 2.2))
    ),
    PaperPosition(
        4, 3, 4.0, 4.0, math.pi, ((4.0, 3.8), (3.9, 3.9), (4.0, 4.0), (3.9, 3.9), (3.9, 3.9))
    ),
)


@dataclass(frozen=True, slots=True)
class EvalPose:
    """One place the robot is put to localize itself.

    Attributes:
        index: Position in the protocol's list of poses.
        group: Rows of the summary group poses: the Table 3 experiment number (paper) or
            ``index`` (random; one estimate per pose).
        room_pose: Where the robot is teleported, room frame (m, rad).
        seed: Seed of everything random in this localization.
    """

    index: int
    group: int
    room_pose: tuple[float, float, float]
    seed: int


def distance_to_walls(x: float, y: float, room_size: tuple[float, float]) -> float:
    """Distance from ``(x, y)`` (room frame, m) to the nearest wall of the room (m)."""
    sx, sy = room_size
    return min(x, sx - x, y, sy - y)


# Where each drawn protocol puts the robot: (min, max) distance to the nearest wall (m) and
# the free radius around it (m) that no furniture may enter. ``random`` keeps near the survey
# circuit; ``anywhere`` takes the whole free floor, the room's interior included.
PROTOCOL_BANDS: dict[str, tuple[tuple[float, float], float]] = {
    "random": ((0.6, 1.4), 0.25),
    "anywhere": ((0.3, math.inf), 0.3),
    "changed": ((0.3, math.inf), 0.3),  # anywhere, in the room as it changed
}


def sample_protocol_poses(
    protocol: str,
    n: int,
    seed: int,
    room_size: tuple[float, float],
    is_free: Callable[[float, float, float], bool],
) -> list[EvalPose]:
    """Draw the poses of a drawn protocol (``random`` or ``anywhere``; see PROTOCOL_BANDS).

    Raises:
        ConfigError: Unknown protocol, ``n`` < 1, or too little free floor.
    """
    if protocol not in PROTOCOL_BANDS:
        valid = ", ".join(["paper", *PROTOCOL_BANDS])
        raise ConfigError(f"unknown protocol {protocol!r}; valid: {valid}")
    band, clearance = PROTOCOL_BANDS[protocol]
    return sample_random_poses(n, seed, room_size, is_free, band_m=band, clearance_m=clearance)


def sample_random_poses(
    n: int,
    seed: int,
    room_size: tuple[float, float],
    is_free: Callable[[float, float, float], bool],
    *,
    band_m: tuple[float, float] = (0.6, 1.4),
    clearance_m: float = 0.25,
    max_draws: int = 200_000,
) -> list[EvalPose]:
    """Draw the ``random`` protocol's poses by rejection sampling.

    Positions are uniform over the part of the floor whose distance to the nearest wall is
    within ``band_m`` and where a disc of ``clearance_m`` touches no furniture; headings are
    uniform in (-pi, pi].

    Args:
        n: Number of poses (>= 1).
        seed: Seed of the draw; the same seed gives the same poses.
        room_size: Inner room size (x, y) in metres.
        is_free: ``robot.sim.is_free(x, y, clearance)`` (room frame).
        band_m: Allowed distance to the nearest wall (m), inclusive.
        clearance_m: Free radius around the robot (m).
        max_draws: Give up after this many candidate positions.

    Returns:
        ``n`` test poses in the room frame, each with its own seed.

    Raises:
        ConfigError: ``n`` < 1, or the room has too little free floor in the band.
    """
    if n < 1:
        raise ConfigError(f"-n must be at least 1, got {n}")
    lo, hi = band_m
    sx, sy = room_size
    if min(sx, sy) < 2 * lo:
        raise ConfigError(f"room {sx} x {sy} m has no floor {lo} m from every wall")
    band = f"{lo}-{hi}" if math.isfinite(hi) else f"at least {lo}"
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x7E57]))
    child_seeds = rng.integers(0, 2**31 - 1, size=n)
    poses: list[EvalPose] = []
    draws = 0
    while len(poses) < n:
        if draws >= max_draws:
            raise ConfigError(
                f"found only {len(poses)} of {n} free poses {band} m from the walls "
                f"after {max_draws} draws"
            )
        draws += 1
        x = float(rng.uniform(0.0, sx))
        y = float(rng.uniform(0.0, sy))
        theta = modulo2PI(float(rng.uniform(-math.pi, math.pi)))
        d = distance_to_walls(x, y, room_size)
        if not (lo <= d <= hi) or not is_free(x, y, clearance_m):
            continue
        i = len(poses)
        poses.append(EvalPose(i, i, (x, y, theta), int(child_seeds[i])))
    return poses


def paper_poses(
    origin_room_pose: tuple[float, float, float],
    seed: int,
    *,
    evaluations: int = PAPER_EVALUATIONS,
    jitter_rad: float = PAPER_HEADING_JITTER_RAD,
) -> list[EvalPose]:
    """The ``paper`` protocol's poses: each Table 3 position ``evaluations`` times.

    Args:
        origin_room_pose: True pose when the survey started (room frame); the map frame's origin.
        seed: Seed of the heading perturbations and of the localizer.
        evaluations: Evaluations per position (the paper: 5).
        jitter_rad: Half-width of the uniform heading perturbation (rad).

    Returns:
        ``4 * evaluations`` test poses in the room frame, grouped by experiment number.
    """
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x7AB3]))
    origin = Pose2D(*origin_room_pose)
    poses: list[EvalPose] = []
    for pos in PAPER_POSITIONS:
        for _ in range(evaluations):
            heading = pos.heading + float(rng.uniform(-jitter_rad, jitter_rad))
            room = (origin * Pose2D(pos.x, pos.y, heading)).normalized()
            seed_i = int(rng.integers(0, 2**31 - 1))
            poses.append(EvalPose(len(poses), pos.number, (room.x, room.y, room.theta), seed_i))
    return poses


def room_to_map(
    origin_room_pose: tuple[float, float, float], room_pose: tuple[float, float, float]
) -> Pose2D:
    """Express a room-frame pose in the map frame (``relative_pose(origin, room_pose)``)."""
    return relative_pose(Pose2D(*origin_room_pose), Pose2D(*room_pose))


def map_to_room(origin_room_pose: tuple[float, float, float], map_pose: Pose2D) -> Pose2D:
    """Express a map-frame pose in the room frame (``origin * map_pose``)."""
    return (Pose2D(*origin_room_pose) * map_pose).normalized()


def wall_seen(
    room_pose: tuple[float, float, float], view_heading: float, room_size: tuple[float, float]
) -> int:
    """Which wall a camera looks at: 1 (y = 0), 2 (x = sx), 3 (y = sy), 4 (x = 0).

    Walls are numbered counter-clockwise from the one on the right of a robot that starts at
    the room-frame origin corner facing +x, as in the paper's Table 1.

    Args:
        room_pose: Robot position (room frame, m); its theta is ignored.
        view_heading: Direction of the camera's optical axis in the room frame (rad).
        room_size: Inner room size (x, y) in metres.

    Returns:
        The wall number the view ray hits first.
    """
    x, y = room_pose[0], room_pose[1]
    sx, sy = room_size
    dx, dy = math.cos(view_heading), math.sin(view_heading)
    hits: list[tuple[float, int]] = []
    if dy < -1e-12:
        hits.append((-y / dy, 1))
    if dx > 1e-12:
        hits.append(((sx - x) / dx, 2))
    if dy > 1e-12:
        hits.append(((sy - y) / dy, 3))
    if dx < -1e-12:
        hits.append((-x / dx, 4))
    return min(hits)[1]


def lap_of(poses: np.ndarray, perimeter_m: float, laps: int) -> np.ndarray:
    """Lap number (1-based) of each survey pose, from the path length walked so far.

    The survey starts at the map origin and takes a picture after each step, so the path
    to a pose is its distance from the origin for the first one, plus the steps since.

    Args:
        poses: ``(N, 3)`` survey poses in walking order, map frame (m).
        perimeter_m: Length of one lap of the circuit (m).
        laps: Laps walked.

    Returns:
        ``(N,)`` int lap numbers in 1..laps; the picture at a lap's closing corner is in it.
    """
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    if len(p) == 0:
        return np.zeros(0, dtype=int)
    steps = np.hypot(np.diff(p[:, 0]), np.diff(p[:, 1]))
    walked = np.concatenate([[0.0], np.cumsum(steps)]) + math.hypot(p[0, 0], p[0, 1])
    lap = np.ceil(walked / perimeter_m - 1e-6).astype(int)
    return np.clip(lap, 1, max(1, laps))
