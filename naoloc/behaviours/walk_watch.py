"""Whether the survey's steps happened: the robot's own evidence against its odometry.

NAO's ``moveTo`` returns True once its walk engine has played the footsteps it planned,
whether or not the body went anywhere: pressed against a wall the robot slides or marks
time while its odometry walks on (issue 31: a whole lap against a wall, ``moveTo`` True
every time, the dataset written as complete). After each step the survey hands
:class:`WalkWatch` what it measured, and the watch raises :class:`SurveyBlocked` with one
line naming the evidence, e.g. ``blocked on side 2 of lap 1 after 1.2 m: the wall ahead
is 0.15 m away``. The evidence:

- the wall pictures: two in a row on one side must not stay put when the odometry
  stepped (A-KAZE matches: most of them still is a robot that did not move);
- the front wall's line: it must get nearer as the odometry walks toward it;
- the side wall's line: it must follow the odometry's steps toward or away from the wall
  (the survey's corrections); a robot sliding along something does not;
- the simulator's contacts (``robot.sim``; simulator only, None on a real NAO): the body's
  disc touching a wall or furniture.

On a NAO the foot bumpers and the FSRs are ALMemory keys, which the robot interface (ALMotion,
ALVideoDevice, ALRobotPosture) does not reach; ALMotion's failed move is ``moveTo``'s
False, which the survey turns into the same error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from naoloc.behaviours.wall_follow import carry
from naoloc.errors import SurveyBlocked
from naoloc.geometry import Pose2D, modulo2PI
from naoloc.perception.floorline import WallLine
from naoloc.perception.wall_gate import crosses_path
from naoloc.robot import Robot

FRONT_CHECK_M = 1.6  # front lines farther than this err too much to say a step did not close
MAX_SIDE_DEVIATION_M = 0.25  # side lines farther than this from the offset are not judged
MIN_SIDE_STEP_M = 0.1  # odometry steps toward or away from the wall smaller are not judged
CONTACT_CLEARANCE_M = 0.155  # simulator only: the body's disc (MuJoCo's 0.15 m capsule) touches
TOUCHING = "the simulator reports the body touching a wall or furniture"
MIN_STEP_M = 0.08  # odometry steps shorter than this are not judged by the pictures
STILL_PX = 2.0  # a matched feature that moved less than this (px) stayed put
MIN_STILL_SHARE = 0.7  # pictures with this share of their features still: the robot did not move
MIN_MATCHES = 12  # matched features a picture comparison needs
MIN_FRONT_ADVANCE_M = 0.15  # odometry advance toward the front wall a comparison needs
MAX_FRONT_ADVANCE_M = 0.6  # and the most: lines measured farther apart are not compared
MIN_FRONT_SHARE = 0.3  # the front line must close at least this share of that advance
SAME_LINE_RAD = 0.15  # two lines ahead whose directions (map frame) differ more are not one
STRIKES = 2  # evidence on this many steps in a row stops the survey
MIN_AHEAD_M = 0.35  # lines nearer than this ahead are the feet or a seam at them, m
MIN_AHEAD_SPAN_M = 0.5  # a wall across the path fills the view; a door frame's edge does not
FRONT_WATCH_M = 1.2  # a line ahead this near, sooner than expected, is looked at every stop
MAX_AHEAD_DISAGREEMENT_M = 0.3  # and a quarter of the side: how much sooner the wall ahead
#                                 may end a side than the odometry says


def image_shift(
    before: tuple[Any, Any] | None, after: tuple[Any, Any] | None
) -> tuple[float, float, int]:
    """How two pictures' matched features moved.

    Args:
        before: ``(keypoints, descriptors)`` of the earlier picture (A-KAZE).
        after: The same of the later one.

    Returns:
        ``(median |dx| px, share of matches that stayed within STILL_PX, matches)``; the
        first two are NaN with fewer than :data:`MIN_MATCHES` matches.
    """
    import cv2

    nan = float("nan")
    if before is None or after is None:
        return nan, nan, 0
    (kp1, d1), (kp2, d2) = before, after
    if d1 is None or d2 is None or len(kp1) < 2 or len(kp2) < 2:
        return nan, nan, 0
    pairs = cv2.BFMatcher(cv2.NORM_HAMMING).knnMatch(d1, d2, k=2)
    good = [p[0] for p in pairs if len(p) == 2 and p[0].distance < 0.75 * p[1].distance]
    if len(good) < MIN_MATCHES:
        return nan, nan, len(good)
    moved = np.array(
        [math.dist(kp2[m.trainIdx].pt, kp1[m.queryIdx].pt) for m in good], dtype=np.float64
    )
    dx = [abs(kp2[m.trainIdx].pt[0] - kp1[m.queryIdx].pt[0]) for m in good]
    return float(np.median(dx)), float(np.mean(moved < STILL_PX)), len(good)


def features(gray: np.ndarray) -> tuple[Any, Any]:
    """A-KAZE keypoints and descriptors of a grey picture."""
    import cv2

    return cv2.AKAZE_create().detectAndCompute(gray, None)  # type: ignore[attr-defined]


def expected_shift_px(step_m: float, offset: float, look_ahead: float, f_px: float) -> float:
    """About how far (px) a step along the wall moves the wall picture's centre.

    The picture looks ``look_ahead`` rad from the wall toward the walking direction; the
    wall ``offset`` m away is ``offset / cos(look_ahead)`` along its axis, and a step
    ``step_m`` along the wall turns that point's bearing by ``step * cos(look_ahead) /
    range`` rad.
    """
    reach = offset / max(0.2, math.cos(look_ahead))
    return f_px * abs(step_m) * math.cos(look_ahead) / reach


def touching(robot: Robot) -> bool:
    """Whether the body touches a wall or furniture: the simulator's contacts (the body's
    disc, :data:`CONTACT_CLEARANCE_M`), as a NAO's bumpers would tell. Always False on a
    real NAO: the robot interface (ALMotion, ALVideoDevice, ALRobotPosture) does not reach
    the bumpers' ALMemory keys."""
    sim = robot.sim
    if sim is None:
        return False
    x, y, _ = sim.true_pose()
    return not sim.is_free(x, y, CONTACT_CLEARANCE_M)


@dataclass
class WalkWatch:
    """The evidence of one survey's steps (see the module's docstring).

    Args:
        robot: The robot (``robot.sim`` for the simulator's contacts only).
        offset: The survey's wall offset, m.
        wall: "left" or "right": the side wall's side (for the messages).
        look_ahead: The wall pictures' turn from the wall, rad.
        f_px: The wall pictures' focal length, px.
    """

    robot: Robot
    offset: float
    wall: str
    look_ahead: float
    f_px: float
    side: int = 0
    lap: int = 0
    walked: float = 0.0
    _picture: tuple[Any, Any] | None = None
    _front: tuple[float, float, bool, Pose2D] | None = None
    _seen_ahead: tuple[WallLine, Pose2D] | None = None
    ahead_m: float = math.inf  # the last line ahead judged (measured or carried), m
    _near: bool = False
    _side: tuple[float, float, Pose2D] | None = None
    _strikes: dict[str, int] = field(default_factory=dict)

    def new_side(self, lap: int, side: int) -> None:
        """A new side begins (after a corner): the pictures and front line start over."""
        self.lap, self.side, self.walked = lap, side, 0.0
        self._picture, self._front, self._near, self._side = None, None, False, None
        self._seen_ahead = None
        self._strikes.clear()

    def clear(self, name: str) -> None:
        """Forget evidence ``name``'s strike (a second look showed it was not what it
        seemed)."""
        self._strikes[name] = 0
        if name == "ahead":
            self._near, self._seen_ahead = False, None

    def pending(self, name: str) -> bool:
        """Whether evidence ``name`` (``ahead``, ``front``, ``side``, ``picture``) has one
        strike and waits for its second."""
        return self._strikes.get(name, 0) > 0

    @property
    def wants_front(self) -> bool:
        """Whether the front wall should be looked at after the next step: a line ahead
        was seen nearer than :data:`FRONT_WATCH_M` where the odometry expects none, or a
        piece of evidence ahead waits for its second strike."""
        return self._near or any(self._strikes.get(name, 0) > 0 for name in ("ahead", "front"))

    def blocked(self, why: str) -> SurveyBlocked:
        """The one-line error for this side, e.g. ``blocked on side 2 of lap 1 after 1.2 m:
        the wall ahead is 0.15 m away``."""
        return SurveyBlocked(
            f"blocked on side {self.side + 1} of lap {self.lap + 1} after {self.walked:.1f} m: "
            f"{why}"
        )

    def _strike(self, name: str, hit: bool, why: str) -> None:
        self._strikes[name] = self._strikes.get(name, 0) + 1 if hit else 0
        if self._strikes[name] >= STRIKES:
            raise self.blocked(why)

    def stepped(self, step_m: float) -> None:
        """The odometry says the robot walked ``step_m`` m; the simulator's contacts first.

        Raises:
            SurveyBlocked: The simulator reports the body touching a wall or furniture.
        """
        self.walked += step_m
        if touching(self.robot):
            raise self.blocked(TOUCHING)

    def picture(self, gray: np.ndarray, step_m: float) -> dict[str, Any]:
        """A new wall picture after an odometry step of ``step_m`` m (along the side).

        A robot that walked sees its wall picture slide by about :func:`expected_shift_px`;
        one that did not sees the same picture: most of its matched features stay put
        (a wallpaper's repeats or the matcher's mistakes can make a few moving pictures'
        median shift small, never most of their features still).

        Returns:
            ``{"shift_px", "still", "expected_px", "matches"}`` (None when not compared).

        Raises:
            SurveyBlocked: Two pictures in a row had at least :data:`MIN_STILL_SHARE` of
                their matches still after steps of :data:`MIN_STEP_M` or more.
        """
        now = features(gray)
        shift, still, matches = image_shift(self._picture, now)
        self._picture = now
        expected = expected_shift_px(step_m, self.offset, self.look_ahead, self.f_px)
        judged = math.isfinite(still) and step_m >= MIN_STEP_M and expected >= 3 * STILL_PX
        self._strike(
            "picture",
            judged and still >= MIN_STILL_SHARE,
            f"the pictures did not move ({100 * still:.0f} % of their features stayed put) "
            f"where a {step_m:.2f} m step moves them about {expected:.0f} px",
        )
        return {
            "shift_px": round(shift, 1) if math.isfinite(shift) else None,
            "still": round(still, 3) if math.isfinite(still) else None,
            "expected_px": round(expected, 1),
            "matches": matches,
        }

    def side_line(self, line: WallLine | None, here: Pose2D, level: float = 0.0) -> None:
        """The side wall's line after a step (only lines of the wall itself, ``level`` 0,
        near the offset: the views see nothing nearer than about 0.45 m, and what they
        show there is the robot's own arm; a furniture face's line is noisier).

        Raises:
            SurveyBlocked: Twice in a row the odometry stepped at least
                :data:`MIN_SIDE_STEP_M` toward or away from the wall and the line closed
                less than :data:`MIN_FRONT_SHARE` of it: the robot slides along something.
        """
        if line is None or abs(line.distance - self.offset) > MAX_SIDE_DEVIATION_M or level:
            self._side = None  # furniture before the wall, or no line: nothing to judge by
            self._strikes["side"] = 0
            return
        before, self._side = self._side, (line.distance, line.normal, here)
        if before is None:
            return
        distance, normal, there = before
        heading = there.theta + normal  # toward the wall, map frame
        toward = (here.x - there.x) * math.cos(heading) + (here.y - there.y) * math.sin(heading)
        if abs(toward) < MIN_SIDE_STEP_M:
            self._strike("side", False, "")
            return
        closed = (distance - line.distance) * math.copysign(1.0, toward)
        self._strike(
            "side",
            closed < MIN_FRONT_SHARE * abs(toward),
            f"sliding along the wall on the {self.wall}: it stayed {line.distance:.2f} m away "
            f"while the odometry stepped {abs(toward):.2f} m "
            f"{'toward' if toward > 0 else 'away from'} it",
        )

    def front_line(
        self, line: WallLine | None, here: Pose2D, remaining: float, length: float
    ) -> None:
        """A front wall's line measured at odometry pose ``here`` (map frame).

        Args:
            line: The line ahead (None: unseen, no evidence).
            here: Where the odometry says the robot is (map frame).
            remaining: What the odometry says is left of the side, m.
            length: The side's length, m.

        Raises:
            SurveyBlocked: Twice in a row: the wall ahead was nearer than the offset plus
                :data:`MIN_STEP_M` while the odometry had more than a quarter of the side
                plus :data:`MAX_AHEAD_DISAGREEMENT_M` to go (a robot walking into a wall; a
                NAO's odometry errs 10 %), or the line closed less than
                :data:`MIN_FRONT_SHARE` of the odometry's advance toward it (both lines
                across the way, and one line: directions within :data:`SAME_LINE_RAD`).
                Lines nearer than :data:`MIN_AHEAD_M` are no evidence (the feet, a seam
                at them).
        """
        if line is None and self._seen_ahead is not None:
            # Unseen is not gone: the last wall seen ahead, carried by the odometry (a wall
            # at the bottom camera's near edge can vanish from both pitches).
            seen, there = self._seen_ahead
            motion = there.inverse() * here
            if math.hypot(motion.x, motion.y) <= MAX_FRONT_ADVANCE_M:
                self._ahead(carry(seen, motion), remaining, length)
            return
        if line is None or line.distance < MIN_AHEAD_M:
            return  # no view sees a wall that near: the robot's own feet, a seam at them
        across = crosses_path(line)
        if across:
            self._seen_ahead = (line, here)
        self._ahead(line, remaining, length)
        before, self._front = self._front, (line.distance, here.theta + line.normal, across, here)
        if before is None or line.distance > FRONT_CHECK_M:
            return
        distance, heading, was_across, there = before
        if not (across and was_across):
            return  # a face beside the way: another thing at each look, perhaps
        if abs(modulo2PI(here.theta + line.normal - heading)) > SAME_LINE_RAD:
            return  # another line than the last one: its distance says nothing of the walk
        advance = (here.x - there.x) * math.cos(heading) + (here.y - there.y) * math.sin(heading)
        if not MIN_FRONT_ADVANCE_M <= advance <= MAX_FRONT_ADVANCE_M:
            return  # too short to judge, or so long since that it may be another thing
        closed = distance - line.distance
        self._strike(
            "front",
            closed < MIN_FRONT_SHARE * advance,
            f"the wall ahead is {line.distance:.2f} m away and came {max(0.0, closed):.2f} m "
            f"nearer while the odometry walked {advance:.2f} m toward it",
        )

    def _ahead(self, line: WallLine, remaining: float, length: float) -> None:
        """The 'ahead' evidence of one line (measured or carried) and the near flag."""
        self.ahead_m = line.distance
        early = remaining - (line.distance - self.offset)
        self._strike(
            "ahead",
            line.distance < self.offset + MIN_STEP_M
            and line.span_m >= MIN_AHEAD_SPAN_M
            and crosses_path(line)
            and early > 0.25 * length + MAX_AHEAD_DISAGREEMENT_M,
            f"the wall ahead is {line.distance:.2f} m away with {remaining:.1f} m of the "
            "side still to walk by the odometry",
        )
        self._near = line.distance < FRONT_WATCH_M and early > MAX_AHEAD_DISAGREEMENT_M
