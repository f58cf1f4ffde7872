"""ALNavigation of a served NAOqi: navigateTo and moveAlong on naoloc's own planner.

``navigateTo(x, y[, theta])`` (FRAME_ROBOT, m and rad) plans around walls and furniture
with :class:`naoloc.navigation.grid.FloorGrid` (A* with the robot's clearance) over
the room's free floor as the simulator knows it (``SimControl.is_free``, sampled once
per room at :data:`CELL_M`), then walks the waypoints with ALMotion.moveTo, one leg at
a time from the robot's true pose (a NAO re-plans from its odometry and sonars), and
takes up to :data:`CORRECTIONS` short legs more when the walk strayed. It returns True
within :data:`REACHED_M` of the goal, False when no path exists (it then goes as near
as it can), a walk failed or the navigation was stopped (``stopNavigateTo``,
``ALMotion.stopMove``).

``moveAlong(trajectory)`` follows NAOqi's trajectory description:
``["Holonomic", ["Line", [x, y]], finalTheta, revolutions]``,
``["Holonomic", ["Circle", [cx, cy], spanAngle], finalTheta, revolutions]`` and
``["Composed", trajectory, ...]``, each part starting where the previous one ended,
in the frame of the robot there. A circle is walked as chords of at most
:data:`ARC_STEP_RAD`. It stops (False) before a part whose end is not free floor.
"""

from __future__ import annotations

import math
import threading
from typing import Any, Final

from naoloc.backends.naoqi.emulation.context import FrontContext
from naoloc.errors import RobotError
from naoloc.geometry import Pose2D, modulo2PI, pose2DInverse
from naoloc.navigation.grid import FREE, FloorGrid, NoPath

CELL_M: Final = 0.1  # the planner's grid cell
CLEARANCE_M: Final = 0.2  # kept from walls and furniture
REACHED_M: Final = 0.15
CORRECTIONS: Final = 2  # short extra legs when the walk ended farther than REACHED_M
ARC_STEP_RAD: Final = 0.4


def _number(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise RobotError(f"{what} must be a finite number, got {value!r}")
    return float(value)


class NavigationFront:
    """ALNavigation over the served robot's motion front and simulator.

    Args:
        ctx: The host's context.
        sim: SimControl (true pose, room size, is_free).
        motion: The served ALMotion front (moveTo, stopMove).
    """

    def __init__(self, ctx: FrontContext, sim: Any, motion: Any) -> None:
        self._ctx, self._sim, self._motion = ctx, sim, motion
        self._grid: FloorGrid | None = None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._security_m = 0.4

    # ------------------------------------------------------------------ the map
    def _floor(self) -> FloorGrid:
        with self._lock:
            if self._grid is None:
                self._grid = self._ctx.run(self._build_grid)
            return self._grid

    def _build_grid(self) -> FloorGrid:
        width, depth = (float(v) for v in self._sim.room_size())
        grid = FloorGrid.empty((0.0, 0.0, width, depth), CELL_M, CLEARANCE_M)
        ny, nx = grid.cells.shape
        for r in range(ny):
            for c in range(nx):
                x, y = grid.centre(r, c)
                if self._sim.is_free(x, y, 0.0):
                    grid.cells[r, c] = FREE
                else:
                    grid.cells[r, c] = 2  # BLOCKED
        return grid

    def _pose(self) -> Pose2D:
        x, y, theta = (float(v) for v in self._ctx.run(self._sim.true_pose))
        return Pose2D(x, y, theta)

    # ------------------------------------------------------------------ walking
    def _walk_to(self, goal: Pose2D) -> bool:
        """One straight leg to ``goal`` (room frame) with ALMotion.moveTo."""
        if self._stop.is_set():
            return False
        rel = pose2DInverse(self._pose()) * goal
        return bool(self._motion.moveTo(rel.x, rel.y, modulo2PI(rel.theta)))

    def navigateTo(self, x: Any, y: Any, *theta: Any) -> bool:
        """Walk to ``(x, y[, theta])`` in FRAME_ROBOT around obstacles; True when there."""
        gx, gy = _number(x, "x"), _number(y, "y")
        gtheta = _number(theta[0], "theta") if theta else None
        self._stop.clear()
        start = self._pose()
        goal = start * Pose2D(gx, gy, gtheta or 0.0)
        try:
            waypoints = self._floor().plan(start, goal)
        except NoPath as err:
            self._ctx.log(f"naoloc serve: ALNavigation.navigateTo: {err}")
            return False
        here = start
        for i, point in enumerate(waypoints):
            last = i == len(waypoints) - 1
            heading = math.atan2(point.y - here.y, point.x - here.x)
            if last and gtheta is not None:
                heading = goal.theta
            elif math.hypot(point.x - here.x, point.y - here.y) < 1e-3:
                heading = here.theta
            target = Pose2D(point.x, point.y, heading)
            if not self._walk_to(target):
                self._ctx.log("naoloc serve: ALNavigation.navigateTo: a walk stopped short")
                return False
            here = target
        end = self._pose()
        missed = math.hypot(end.x - goal.x, end.y - goal.y)
        for _ in range(CORRECTIONS):  # the walk strays from odometry: step to the goal again
            if (
                missed <= REACHED_M
                or missed > 1.0
                or not self._walk_to(
                    Pose2D(goal.x, goal.y, goal.theta if gtheta is not None else end.theta)
                )
            ):
                break
            end = self._pose()
            missed = math.hypot(end.x - goal.x, end.y - goal.y)
        if missed > REACHED_M:
            self._ctx.log(f"naoloc serve: ALNavigation.navigateTo: ended {missed:.2f} m away")
        return missed <= REACHED_M

    def moveAlong(self, trajectory: Any) -> bool:
        """Follow a NAOqi trajectory (Holonomic Line/Circle, Composed); True when done."""
        legs = _legs(trajectory)
        self._stop.clear()
        for leg in legs:
            start = self._pose()
            end = start * leg
            if not self._ctx.run(self._sim.is_free, end.x, end.y, CLEARANCE_M):
                self._ctx.log("naoloc serve: ALNavigation.moveAlong: an obstacle on the way")
                return False
            if not self._walk_to(end):
                return False
        return True

    def stopNavigateTo(self) -> None:
        """Stop navigateTo / moveAlong (the current walk ends now)."""
        self._stop.set()
        self._motion.stopMove()

    def setSecurityDistance(self, arg1: Any) -> None:
        """Distance (m) kept from obstacles in front (stored; the planner keeps 0.2 m)."""
        value = _number(arg1, "security distance")
        if value < 0:
            raise RobotError(f"security distance must be >= 0, got {value}")
        self._security_m = value

    def getSecurityDistance(self) -> float:
        """The stored security distance, m."""
        return self._security_m


def _legs(trajectory: Any) -> list[Pose2D]:
    """Relative moves (each in the frame where the previous ended) of a trajectory.

    Raises:
        RobotError: Not one of NAOqi's trajectory shapes.
    """
    if not isinstance(trajectory, list | tuple) or not trajectory:
        raise RobotError(f"a trajectory is a list, got {trajectory!r}")
    kind = trajectory[0]
    if kind == "Composed":
        return [leg for part in trajectory[1:] for leg in _legs(part)]
    if kind != "Holonomic" or len(trajectory) < 3:
        raise RobotError(
            "a trajectory is ['Holonomic', path, finalTheta, revolutions] or ['Composed', ...]"
        )
    path, final_theta = trajectory[1], _number(trajectory[2], "finalTheta")
    if not isinstance(path, list | tuple) or not path:
        raise RobotError(f"a path is ['Line', [x, y]] or ['Circle', [cx, cy], span], got {path!r}")
    if path[0] == "Line" and len(path) == 2:
        x, y = (_number(v, "Line end") for v in path[1])
        return [Pose2D(x, y, final_theta)]
    if path[0] == "Circle" and len(path) == 3:
        cx, cy = (_number(v, "Circle centre") for v in path[1])
        span = _number(path[2], "Circle span")
        steps = max(1, math.ceil(abs(span) / ARC_STEP_RAD))
        radius, a0 = math.hypot(cx, cy), math.atan2(-cy, -cx)
        angles = [a0 + span * k / steps for k in range(steps + 1)]
        points = [(cx + radius * math.cos(a), cy + radius * math.sin(a)) for a in angles]
        legs, here = [], Pose2D(0.0, 0.0, 0.0)
        for k in range(1, steps + 1):
            goal = Pose2D(points[k][0], points[k][1], final_theta * k / steps)
            legs.append(pose2DInverse(here) * goal)
            here = goal
        return legs
    raise RobotError(f"unknown path {path[0]!r}; NAOqi's are Line and Circle")
