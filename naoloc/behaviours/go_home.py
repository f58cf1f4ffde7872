"""Walk back to the map origin (where the survey started) using the map.

Each round localizes (:func:`naoloc.behaviours.localize.localize`), then walks with
``moveTo`` to the origin as seen from the estimate (the map origin in FRAME_ROBOT is the
inverse of the estimated pose), and localizes again, until the estimate is within
``go_home.tolerance_m`` of the origin or ``go_home.max_tries`` walks were made.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from naoloc.behaviours.camera import Camera
from naoloc.behaviours.localize import Localization, localize, truth_in_map
from naoloc.config import Config
from naoloc.errors import MotionError
from naoloc.geometry import Pose2D, relative_pose
from naoloc.robot import Robot

if TYPE_CHECKING:
    from naoloc.mapping import VisualMap


@dataclass
class GoHomeResult:
    """How going home went.

    Attributes:
        final: The last localization (estimate in the map frame).
        tries: Walks made toward the origin.
        reached: True when the last estimate was within the tolerance.
        rounds: Every localization, in order.
        truth: The true final pose in the map frame (simulator), else None.
        error_m: True distance from the map origin at the end, m (simulator), else None.
    """

    final: Localization
    tries: int
    reached: bool
    rounds: list[Localization] = field(default_factory=list)
    truth: Pose2D | None = None
    error_m: float | None = None

    def summary(self) -> dict[str, Any]:
        """JSON-able fields of CONTRACT.md's ``go-home`` line."""
        est = self.final.estimate
        out: dict[str, Any] = {
            "x": round(est.x, 4),
            "y": round(est.y, 4),
            "theta": round(est.theta, 4),
            "confidence": round(float(est.confidence), 4),
            "tries": self.tries,
            "reached": self.reached,
            "estimates": [[round(r.estimate.x, 3), round(r.estimate.y, 3)] for r in self.rounds],
        }
        if self.truth is not None and self.error_m is not None:
            out["error_m"] = round(self.error_m, 4)
            out["truth"] = [round(v, 4) for v in self.truth]
        return out


def go_home(
    robot: Robot,
    vmap: VisualMap,
    cfg: Config,
    *,
    on_round: Callable[[int, Localization], None] | None = None,
    turns: int = 1,
) -> GoHomeResult:
    """Localize, walk to the map origin, and repeat until close enough or out of tries.

    Args:
        robot: The robot, anywhere in the mapped room.
        vmap: The map.
        cfg: Config; uses ``go_home.tolerance_m``, ``go_home.max_tries``, ``localize`` and
            ``camera``.
        on_round: Called after each localization with the walk count so far and its result.
        turns: Body headings of each localization scan (1 = no turning in place).

    Returns:
        The final estimate, walks made, and the true error on a simulator.

    Raises:
        MotionError: A walk failed (the robot is stopped).
    """
    tolerance = cfg.go_home.tolerance_m
    rounds: list[Localization] = []
    tries = 0
    reached = False
    with Camera(robot, cfg.camera, "naoloc_go_home") as camera:
        try:
            while True:
                loc = localize(robot, vmap, cfg, camera=camera, turns=turns)
                rounds.append(loc)
                if on_round is not None:
                    on_round(tries, loc)
                est = loc.estimate
                if math.hypot(est.x, est.y) <= tolerance:
                    reached = True
                    break
                if tries >= cfg.go_home.max_tries:
                    break
                home = relative_pose(Pose2D(est.x, est.y, est.theta), Pose2D())
                tries += 1
                if not robot.motion.moveTo(home.x, home.y, home.theta):
                    raise MotionError(
                        f"moveTo({home.x:.2f}, {home.y:.2f}, {home.theta:.2f}) toward the "
                        "map origin failed"
                    )
        finally:
            robot.motion.stopMove()
    truth = truth_in_map(robot, vmap.meta)
    error = None if truth is None else math.hypot(truth.x, truth.y)
    return GoHomeResult(rounds[-1], tries, reached, rounds, truth, error)
