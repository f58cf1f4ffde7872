"""build-map's checks of a survey's map frame, before the map is written (issue 31, item 4).

A survey that walked into a wall, or beside the wrong wall, used to give a map of the
right size, mirrored or shifted, with no doubt raised. Each check here measures one thing
the survey's own records can contradict, and gives a figure, its limit and a verdict
(``pass``, ``fail``, or ``skip`` when the survey holds nothing to measure it by):

- ``survey_complete``: the survey walked every lap (a blocked or interrupted one did not);
- ``wall_poses``: the floor lines placed the keyframes (figure: the share of the circuit's
  corners they placed); without them the map would be the drifting odometry's;
- ``origin``: the map origin's heading to its wall, from the start's own lines, against
  what side 0's first steps' lines say (less the odometry's turn since the start);
- ``coverage``: each wall's share of the survey's stops whose side line was usable (near
  the offset, at the expected angle); a survey beside the wrong wall, or pressed against
  one, sees its walls nowhere near where the circuit puts them;
- ``wall_fit``: the residuals of the wall fit: how much the side lines' change between
  consecutive stops differs from the odometry's walk away from the wall (RMS, m); a
  robot pressed into a wall marches on while its lines stand still;
- ``loop_closure``: lap-to-lap agreement: the same side's metres per odometry metre in
  each lap (the largest relative difference);
- ``odometry``: the odometry against the wall poses: each side's metres per odometry metre
  and the corners' turn per odometry turn, against what a NAO's odometry errs;
- ``room_size``: the circuit's sides against the room the config gives: the metres per
  odometry metre the sides imply (configured length over the odometry's walk) along x
  against those along y;
- ``laps_agree``: the laps' pictures against each other: where the first lap's landmarks
  put each later lap's pictures (PnP) against where the map has them, the largest
  precision-weighted mean offset over a side (m, :mod:`naoloc.mapping.laps`); a lap that
  turned early at furniture and was drawn where the rectangle says stands apart from the
  first lap's view of it.

The limits are the config's ``map.checks`` tuning record. :func:`check_survey` runs them,
:func:`failed` names the failing ones, and :func:`map_checked` tells whether a map (its
meta) passed them all (``meta["checked"]``).
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from naoloc.config import MapCheckTuning
from naoloc.mapping.laps import LapAgreement

Verdict = Literal["pass", "fail", "skip"]


@dataclass(frozen=True, slots=True)
class Check:
    """One check of a survey's map frame.

    Attributes:
        name: Short name (``coverage``, ``wall_fit``, ...).
        figure: What was measured (None when nothing could be).
        limit: The bound the figure is held to (None with no figure).
        unit: The figure's unit ("m", "%", "share", ...).
        verdict: "pass", "fail" or "skip".
        detail: One phrase: what the figure is, or why the check failed.
    """

    name: str
    figure: float | None
    limit: float | None
    unit: str
    verdict: Verdict
    detail: str

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (figures rounded)."""
        return {
            "name": self.name,
            "figure": None if self.figure is None else round(self.figure, 4),
            "limit": self.limit,
            "unit": self.unit,
            "verdict": self.verdict,
            "detail": self.detail,
        }

    def line(self) -> str:
        """A human-readable line, e.g. ``coverage 0.92 share (>= 0.5): pass``."""
        figure = "-" if self.figure is None else f"{self.figure:.4g}"
        limit = "" if self.limit is None else f" (limit {self.limit:g})"
        return f"{self.name} {figure} {self.unit}{limit}: {self.verdict}, {self.detail}"


def _check(
    name: str, figure: float | None, limit: float, unit: str, ok: bool | None, detail: str
) -> Check:
    verdict: Verdict = "skip" if ok is None else "pass" if ok else "fail"
    return Check(name, figure, limit, unit, verdict, detail)


def check_survey(
    data: Any,
    walled: Any,
    survey: dict[str, Any],
    tuning: MapCheckTuning,
    laps: LapAgreement | None = None,
) -> list[Check]:
    """Every check of a survey's map frame (see the module's docstring).

    Args:
        data: The :class:`naoloc.data.dataset.Dataset` (its meta: ``vision``,
            ``metric_scale``, ``laps``; its completeness).
        walled: The :class:`naoloc.mapping.wall_poses.WallPoses` of its keyframes, or None
            when the floor lines could not place them.
        survey: The survey's config section (``laps``, ``wall_offset_m``), as a dict.
        tuning: The limits.
        laps: The laps' agreement (:func:`naoloc.mapping.laps.lap_agreement`); None skips
            ``laps_agree``.

    Returns:
        The checks, in the order of the module's docstring.
    """
    meta = data.meta if isinstance(data.meta, dict) else {}
    checks = [_complete(data, meta)]
    if walled is None:
        checks.append(
            Check(
                "wall_poses",
                0.0,
                tuning.min_corner_share,
                "share",
                "fail",
                "the floor lines placed fewer than half of the circuit's corners: the map "
                "would be the drifting odometry's",
            )
        )
        return checks
    known = [s for s in walled.side_scales if s is not None]
    share = len(known) / max(1, len(walled.side_scales))
    checks.append(
        _check(
            "wall_poses",
            share,
            tuning.min_corner_share,
            "share",
            share >= tuning.min_corner_share,
            "of the circuit's corners placed by a wall",
        )
    )
    checks.append(_origin(walled, tuning))
    checks.append(_coverage(walled, tuning))
    checks.append(_wall_fit(walled, tuning))
    checks.append(_loop_closure(walled, tuning))
    checks.append(_odometry(walled, tuning))
    checks.append(_room_size(walled, meta, tuning))
    checks.append(_laps_agree(laps, tuning))
    return checks


def _complete(data: Any, meta: dict[str, Any]) -> Check:
    if data.complete:
        return Check("survey_complete", 1.0, 1.0, "", "pass", "every lap walked")
    reason = meta.get("reason") or "incomplete"
    return Check("survey_complete", 0.0, 1.0, "", "fail", f"the survey stopped: {reason}")


def _origin(walled: Any, tuning: MapCheckTuning) -> Check:
    """The map origin's heading to its wall: the start's own lines against side 0's first
    frames' (each less the odometry's turn since the start)."""
    own, frames = walled.start_own, walled.start_frames
    if own is None or frames is None:
        return _check(
            "origin",
            None,
            tuning.max_origin_heading_deg,
            "deg",
            None,
            "the start or side 0's first frames saw no wall line",
        )
    diff = abs(math.degrees(math.remainder(own - frames, 2 * math.pi)))
    return _check(
        "origin",
        diff,
        tuning.max_origin_heading_deg,
        "deg",
        diff <= tuning.max_origin_heading_deg,
        "the start's heading to its wall: its own lines against its first steps'",
    )


def _coverage(walled: Any, tuning: MapCheckTuning) -> Check:
    """The least share of a wall's stops with a usable side line (the four walls, all laps)."""
    seen: dict[int, list[bool]] = {}
    for side, usable in zip(walled.sides_of, walled.lines_seen, strict=True):
        seen.setdefault(side % 4, []).append(usable)
    shares = {wall: sum(v) / len(v) for wall, v in seen.items() if v}
    if not shares:
        return _check("coverage", None, tuning.min_coverage, "share", None, "no stops")
    wall, worst = min(shares.items(), key=lambda kv: kv[1])
    walls_missing = 4 - len(shares)
    ok = worst >= tuning.min_coverage and walls_missing == 0
    detail = (
        f"least share of a wall's stops with its floor line: wall {wall + 1}"
        if walls_missing == 0
        else f"{walls_missing} wall(s) without a stop"
    )
    return _check(
        "coverage", worst if walls_missing == 0 else 0.0, tuning.min_coverage, "share", ok, detail
    )


def _wall_fit(walled: Any, tuning: MapCheckTuning) -> Check:
    res = np.asarray(walled.residuals, dtype=np.float64)
    if res.size < 3:
        return _check(
            "wall_fit",
            None,
            tuning.max_wall_fit_m,
            "m",
            None,
            "fewer than 3 pairs of stops saw their wall",
        )
    rms = float(np.sqrt(np.mean(res**2)))
    return _check(
        "wall_fit",
        rms,
        tuning.max_wall_fit_m,
        "m",
        rms <= tuning.max_wall_fit_m,
        "RMS of the side lines' change between stops against the odometry's",
    )


def _loop_closure(walled: Any, tuning: MapCheckTuning) -> Check:
    scales = walled.side_scales
    diffs = [
        abs(scales[k] / scales[k - 4] - 1.0) * 100
        for k in range(4, len(scales))
        if scales[k] is not None and scales[k - 4] is not None
    ]
    if not diffs:
        return _check(
            "loop_closure",
            None,
            tuning.max_lap_difference_pct,
            "%",
            None,
            "one lap, or no side measured in two laps",
        )
    worst = max(diffs)
    return _check(
        "loop_closure",
        worst,
        tuning.max_lap_difference_pct,
        "%",
        worst <= tuning.max_lap_difference_pct,
        "largest lap-to-lap difference of a side's metres per odometry metre",
    )


def _odometry(walled: Any, tuning: MapCheckTuning) -> Check:
    known = [s for s in walled.side_scales if s is not None]
    low, high = tuning.odometry_scale_range
    worst = max(known, key=lambda s: abs(math.log(s)))
    turn = walled.turn_scale
    ok = low <= worst <= high
    detail = "the side whose metres per odometry metre are farthest from 1"
    if turn is None:
        detail += "; the corners' turns read implausibly or were not seen"
    return _check("odometry", worst, high, "m/m", ok, detail)


def _room_size(walled: Any, meta: dict[str, Any], tuning: MapCheckTuning) -> Check:
    """The configured sides along x against those along y: the metres per odometry metre
    each implies (configured length over the odometry's walk) should agree, a NAO's
    odometry erring alike in every direction; a side configured wrong stands out. (The
    survey's own floor-line metric scale is no judge: front lines that see furniture, or
    a simulated floor's, scatter it 0.6-1.5.)"""
    scales = walled.side_scales
    by_axis = [
        [s for k, s in enumerate(scales) if s is not None and k % 2 == axis] for axis in (0, 1)
    ]
    if not by_axis[0] or not by_axis[1]:
        return _check(
            "room_size", None, tuning.max_size_error_pct, "%", None,
            "the sides along x or along y have no measured corner",
        )  # fmt: skip
    sx, sy = (statistics.median(v) for v in by_axis)
    worst = abs(sx / sy - 1.0) * 100
    return _check(
        "room_size", worst, tuning.max_size_error_pct, "%", worst <= tuning.max_size_error_pct,
        "the configured sides along x against those along y, by the walk",
    )  # fmt: skip


def _laps_agree(laps: LapAgreement | None, tuning: MapCheckTuning) -> Check:
    """How far, at most over a later lap's side, the first lap's landmarks put its pictures
    from their map poses (the precision-weighted mean offset)."""
    limit = tuning.max_lap_disagreement_m
    worst = None if laps is None else laps.worst
    if laps is None or worst is None:
        why = (
            "one lap, or no later side with enough pictures placed on the first lap's landmarks"
            if laps is not None
            else "not measured"
        )
        return _check("laps_agree", None, limit, "m", None, why)
    return _check(
        "laps_agree", worst.offset_m, limit, "m", worst.offset_m <= limit,
        f"the first lap's landmarks against the map, worst on side {worst.side + 1} "
        f"(+-{worst.sigma_m:.3f} m, {worst.pictures} pictures; {len(laps.frames)} of "
        f"{laps.tried} later pictures placed)",
    )  # fmt: skip


def failed(checks: list[Check]) -> list[Check]:
    """The checks that failed."""
    return [c for c in checks if c.verdict == "fail"]


def map_checked(meta_or_map: Any) -> bool:
    """Whether a map passed build-map's checks (``meta["checked"]``).

    Args:
        meta_or_map: A :class:`naoloc.mapping.VisualMap` or its meta dict.

    Returns:
        True only for a map whose checks all passed; False for one kept with
        ``--keep-unchecked`` and for maps built before the checks existed.
    """
    meta = getattr(meta_or_map, "meta", meta_or_map)
    return isinstance(meta, dict) and meta.get("checked") is True
