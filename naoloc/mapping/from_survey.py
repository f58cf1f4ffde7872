"""A map from a survey dataset: its keyframes posed from the walls, then Algorithm 4.

The one place that turns a read survey (:class:`naoloc.data.dataset.Dataset`) into a
:class:`naoloc.mapping.VisualMap`; ``naoloc build-map`` and the evaluation both call
:func:`build_from_survey`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from typing import Any

from naoloc.config import MapConfig, WallPoseTuning
from naoloc.errors import MapCheckFailed
from naoloc.geometry import Pose2D
from naoloc.mapping.builder import ProgressFn, carried, map_extractor, pinhole_features
from naoloc.mapping.checks import Check, check_survey, failed
from naoloc.mapping.landmarks import query_camera
from naoloc.mapping.laps import LapAgreement, lap_agreement
from naoloc.mapping.map import VisualMap, build_map
from naoloc.mapping.wall_poses import WallPoses, wall_poses
from naoloc.perception.features import Features
from naoloc.robot.keyframe import Keyframe
from naoloc.robot.lens import Lens

# Fewest frames a map is built from: one or two pictures give no place to tell apart.
MIN_MAP_FRAMES = 3


def apply_metric_scale(
    keyframes: list[Keyframe],
    meta: dict[str, Any],
    scale_range: tuple[float, float] | None = None,
) -> tuple[list[Keyframe], float | None]:
    """Scale the keyframes' odometry positions to metres, by the survey's ``metric_scale``.

    The survey measures it (metres per odometry metre) from the floor-wall line's
    distances, which the camera height from the kinematics makes metric
    (:func:`naoloc.behaviours.wall_follow.metric_scale`). Positions scale about the map
    origin (the survey start); headings are unchanged. A scale outside ``scale_range``
    (``map.tuning.wall_poses.scale_range``: the metres per odometry metre a NAO's odometry
    can err to) is a failed measurement and is not applied.

    Args:
        keyframes: Keyframes with odometry poses in the map frame.
        meta: The survey meta (``metric_scale`` may be missing or null).
        scale_range: The plausible scales, (low, high) (None: the default tuning's).

    Returns:
        The keyframes to build from and the scale applied (None: left as they were).
    """
    low, high = WallPoseTuning().scale_range if scale_range is None else scale_range
    scale = meta.get("metric_scale")
    if not isinstance(scale, (int, float)) or not low <= scale <= high:
        return keyframes, None
    k = float(scale)

    def scaled(p: Pose2D | None) -> Pose2D | None:
        return None if p is None else Pose2D(p.x * k, p.y * k, p.theta)

    out = [
        dataclasses.replace(kf, pose=Pose2D(kf.pose.x * k, kf.pose.y * k, kf.pose.theta),
                            command_pose=scaled(kf.command_pose))
        for kf in keyframes
    ]  # fmt: skip
    return out, k


def survey_keyframes(
    data: Any, cfg: MapConfig, offset: float | None = None
) -> tuple[list[Keyframe], dict[str, Any]]:
    """The keyframes a map is built from, with the poses ``cfg`` asks for.

    ``map.wall_poses`` (default): poses from the survey's walls
    (:func:`naoloc.mapping.wall_poses.wall_poses`), which also fixes the metric scale (the known
    circuit); a survey without floor-line records keeps its odometry. Otherwise, and
    ``map.apply_metric_scale``: odometry scaled by the survey's ``metric_scale``.

    Args:
        data: The :class:`naoloc.data.dataset.Dataset`.
        cfg: The map config.
        offset: ``survey.wall_offset_m`` when the dataset's own config lacks it.

    Returns:
        The keyframes and facts for the map's meta (``metric_scale``, ``wall_poses``).
    """
    keyframes, facts, _ = pose_survey(data, cfg, offset)
    return keyframes, facts


def pose_survey(
    data: Any, cfg: MapConfig, offset: float | None = None
) -> tuple[list[Keyframe], dict[str, Any], WallPoses | None]:
    """:func:`survey_keyframes`, with the :class:`WallPoses` behind them (None: the
    odometry's poses were kept)."""
    facts: dict[str, Any] = {"metric_scale": None, "wall_poses": None}
    if cfg.wall_poses:
        offset = survey_offset(data, offset)
        skirting = survey_skirting(data)
        walled = (
            None
            if offset is None
            else wall_poses(
                data.keyframes,
                data.meta,
                offset=offset,
                skirting=skirting,
                tuning=cfg.tuning.wall_poses,
            )
        )
        if walled is not None:
            facts["wall_poses"] = walled.summary()
            return walled.keyframes, facts, walled
    if cfg.apply_metric_scale:
        keyframes, facts["metric_scale"] = apply_metric_scale(
            data.keyframes, data.meta, cfg.tuning.wall_poses.scale_range
        )
        return keyframes, facts, None
    return list(data.keyframes), facts, None


def survey_offset(data: Any, offset: float | None = None) -> float | None:
    """The wall offset the survey walked at: its own config's, else ``offset``."""
    value = survey_value(data, "wall_offset_m", None)
    return value if value is not None and value > 0 else offset


DEFAULT_SKIRTING_M = 0.012  # a common skirting board's depth, m (MuJoCo's home and office)


def survey_skirting(data: Any) -> float:
    """How far the survey's skirting boards stood out of its walls, m: ``survey.skirting_m``,
    else 0.012, or 0 in a simulated room without boards (the fake robot's, a room of style
    ``posters`` on any backend, served ones included); datasets from before the key: 0 (their
    maps were built so)."""
    config = data.config if isinstance(data.config, dict) else {}
    survey = config.get("survey")
    if not isinstance(survey, dict) or "skirting_m" not in survey:
        return 0.0
    value = survey.get("skirting_m")
    if isinstance(value, (int, float)):
        return float(value)
    robot, world = config.get("robot") or {}, config.get("world") or {}
    style = (world.get("room") or {}).get("style") if isinstance(world, dict) else None
    backend = robot.get("backend") if isinstance(robot, dict) else None
    bare = backend == "fake" or style == "posters"
    return 0.0 if bare else DEFAULT_SKIRTING_M


def survey_value(data: Any, key: str, default: Any) -> Any:
    """A number of the survey's own config section (``survey.KEY``), else ``default``
    (datasets from before the key existed)."""
    survey = data.config.get("survey") if isinstance(data.config, dict) else None
    value = survey.get(key) if isinstance(survey, dict) else None
    return float(value) if isinstance(value, (int, float)) else default


def wall_features(data: Any, keyframes: Sequence[Keyframe], cfg: MapConfig) -> list[Features]:
    """The features of the survey's wall pictures, as the map is built from them (the map's
    extractor, the survey camera's lens undone)."""
    extractor = map_extractor(cfg)
    lens = Lens.from_dict(data.meta.get("lens") if isinstance(data.meta, dict) else None)
    return [pinhole_features(extractor, kf, query_camera(kf), lens) for kf in keyframes]


def survey_laps(
    data: Any,
    cfg: MapConfig,
    walled: WallPoses | None,
    features: Sequence[Features] | None = None,
) -> LapAgreement | None:
    """How the survey's laps agree picture by picture (:mod:`naoloc.mapping.laps`); None for
    a survey of one lap or without wall poses.

    Args:
        data: The dataset.
        cfg: The map config.
        walled: The wall poses.
        features: The wall pictures' features (:func:`wall_features`); extracted when None.
    """
    if walled is None or len(set(s // 4 for s in walled.sides_of)) < 2:
        return None
    feats = wall_features(data, walled.keyframes, cfg) if features is None else features
    return lap_agreement(
        walled.keyframes, feats, walled.sides_of, map_extractor(cfg).binary,
        cfg.tuning.checks, cfg.tuning.landmarks,
    )  # fmt: skip


def run_checks(
    data: Any,
    cfg: MapConfig,
    walled: WallPoses | None,
    features: Sequence[Features] | None = None,
    laps: LapAgreement | None = None,
) -> list[Check]:
    """build-map's checks of the survey's map frame (:mod:`naoloc.mapping.checks`).

    Args:
        data: The dataset.
        cfg: The map config.
        walled: The wall poses (None: the floor lines placed none).
        features: The wall pictures' features (:func:`wall_features`); extracted here when
            None and the survey walked more than one lap.
        laps: :func:`survey_laps`, when already measured.
    """
    survey = data.config.get("survey") if isinstance(data.config, dict) else None
    if laps is None:
        laps = survey_laps(data, cfg, walled, features)
    return check_survey(data, walled, survey if isinstance(survey, dict) else {},
                        cfg.tuning.checks, laps)  # fmt: skip


def far_keyframes(data: Any, keyframes: Sequence[Keyframe]) -> list[tuple[int, Keyframe]]:
    """The dataset's far pictures with their stops, posed as the map's keyframes are.

    A far picture is taken where its stop's wall picture was, the head turned: it takes
    that keyframe's pose (from the walls or the scaled odometry, :func:`survey_keyframes`)
    composed with the raw odometry from the wall picture to it.

    Args:
        data: The :class:`naoloc.data.dataset.Dataset`.
        keyframes: Its wall pictures as :func:`survey_keyframes` posed them.
    """
    out = []
    for stop, kf in data.far:
        pose = carried(keyframes[stop].pose, data.keyframes[stop].pose, kf.pose)
        out.append((stop, dataclasses.replace(kf, pose=pose)))
    return out


def build_from_survey(
    data: Any,
    cfg: MapConfig,
    *,
    offset: float | None = None,
    meta: dict[str, Any] | None = None,
    progress: ProgressFn | None = None,
    keep_unchecked: bool = True,
    on_checks: Callable[[list[Check]], None] | None = None,
) -> tuple[VisualMap, dict[str, Any]]:
    """Build the map of a survey dataset with ``cfg`` (not saved), after checking it.

    The checks (:mod:`naoloc.mapping.checks`) run on the posed keyframes before the map is
    trained; their figures and verdicts go into the map's meta (``checks``) with
    ``checked``: True when all passed.

    Args:
        data: The :class:`naoloc.data.dataset.Dataset`.
        cfg: The map config.
        offset: ``survey.wall_offset_m`` when the dataset's own config lacks it.
        meta: Extra entries for the map's meta (e.g. the dataset's path).
        progress: Called as ``progress(stage, done, total)`` while building.
        keep_unchecked: Build a map that failed a check anyway, marked ``checked: False``
            (the default: the evaluation and the demo keep their maps and say so);
            False refuses it, as ``naoloc build-map`` does without ``--keep-unchecked``.
        on_checks: Called with the checks once they ran (before any refusal).

    Returns:
        The map and the facts :func:`survey_keyframes` found (``metric_scale``,
        ``wall_poses``) with ``checks`` (a list of dicts) and ``checked``, which are also in
        the map's meta.

    Raises:
        MapCheckFailed: A check failed and ``keep_unchecked`` is False; the message names
            the first failing check and its figure.
    """
    keyframes, facts, walled = pose_survey(data, cfg, offset)
    feats = wall_features(data, keyframes, cfg)
    laps = survey_laps(data, cfg, walled, feats)
    checks = run_checks(data, cfg, walled, feats, laps)
    if on_checks is not None:
        on_checks(checks)
    bad = failed(checks)
    if bad and not keep_unchecked:
        first = bad[0]
        more = f" (and {', '.join(c.name for c in bad[1:])})" if len(bad) > 1 else ""
        raise MapCheckFailed(
            f"the map failed its {first.name} check{more}: {first.line()}; "
            "--keep-unchecked keeps it, marked unchecked"
        )
    facts["checks"] = [c.to_dict() for c in checks]
    facts["checked"] = not bad
    # The keyframes' own error, as the laps' disagreement shows it: the localizer's floor.
    sigma = None if laps is None else laps.keyframe_sigma_m
    facts["keyframe_sigma_m"] = None if sigma is None else round(sigma, 4)
    map_meta = dict(data.meta)
    map_meta.pop("vision", None)  # per-frame survey measurements stay in the dataset
    map_meta.update({**(meta or {}), **facts})
    far = far_keyframes(data, keyframes) if cfg.far_pictures else []
    vmap = build_map(keyframes, cfg, meta=map_meta, progress=progress, far=far, wall_features=feats)
    return vmap, facts
