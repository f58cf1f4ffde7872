"""Write docs/cli.md: every verb and flag (from the argparse parser), every config key (from
the pydantic models) and every JSON field of each verb's last stdout line.

    python tools/gen_cli_doc.py           # rewrite docs/cli.md
    python tools/gen_cli_doc.py --check   # exit 1 when docs/cli.md is not up to date

tests/integration/test_cli_doc.py runs the check, so the page never drifts from the code. The
JSON fields are described in JSON_FIELDS below; the same test runs the verbs and fails on a
field that is printed but not described here.
"""

from __future__ import annotations

import argparse
import sys
import types
import typing
from pathlib import Path
from typing import Any

from pydantic import BaseModel
from pydantic_core import PydanticUndefined

REPO = Path(__file__).resolve().parent.parent
DOC = REPO / "docs" / "cli.md"

# verb -> field -> description. Units: m, rad, deg, s, ms; frames as named.
JSON_FIELDS: dict[str, dict[str, str]] = {
    "survey": {
        "frames": "wall pictures written to the dataset (the paper's survey images)",
        "far_frames": "far pictures written beside them (`survey.far_yaws_rad`; 0 = none)",
        "laps": "closed laps walked",
        "path_m": "distance walked by odometry (m)",
        "wall_s": "wall-clock time of the survey (s)",
        "dataset": "the MCAP dataset written",
        "direction": "`ccw` or `cw`: the circuit's direction",
        "head_yaw": "HeadYaw held during the laps (rad): toward the nearer side wall",
        "head_yaw_source": "what chose the wall side: `floorline` (the floor-wall lines left "
        "and right), `parallax`, `config` (`survey.head_yaw_rad`) or `caller` (Python only)",
        "metric_scale": "metres per odometry metre measured from the floor-wall line (null: none)",
        "wall_follow": "how the floor-wall line steered the survey (corrections, lines seen)",
        "ros2": "with --format ros2: the ROS 2 MCAP written beside (NAME.ros2.mcap)",
    },
    "build-map": {
        "images": "keyframes the map was built from (wall and far pictures)",
        "far_images": "of those, far pictures (the verified localizer's; the GCS learns the rest)",
        "neurons": "GCS neurons",
        "distinct_poses": "distinct neuron poses (1 mm apart or more)",
        "features_s": "feature extraction time (s)",
        "vocabulary_s": "vocabulary and histogram time (s)",
        "gcs_s": "GCS training time (s)",
        "total_s": "whole build time (s)",
        "map": "the map file written (.npz)",
        "png": "the picture of the map written beside it",
        "dataset_complete": "false when the dataset's writer died (frames up to there used)",
        "metric_scale": "the survey's metric scale applied to the keyframe poses (null: none)",
        "wall_poses": "keyframe poses from the survey's walls (`map.wall_poses`): sides, "
        "sides_with_corner, median_scale, lines_used, frames (null: odometry poses kept)",
        "checked": "true when the map passed every check; false: kept with --keep-unchecked",
        "checks": "the map frame's checks: each {name, figure, limit, unit, verdict "
        "(pass | fail | skip), detail} (`map.tuning.checks` holds the limits)",
    },
    "localize": {
        "x": "the belief's pose, map frame (m); null without one",
        "y": "the belief's pose, map frame (m); null without one",
        "theta": "the belief's heading, map frame (rad); null without one",
        "confidence": "probability of the best place given the observations, 0..1; 0 without "
        "a pose (exit code 3)",
        "method": "`filter` (the localization filter), `gcs` (the paper's Algorithm 5, "
        "localize.mode paper), `none` without a pose",
        "status": "`tracking` (a pose), `lost` (not concentrated yet, or a room it recognised "
        "whose place it lost) or `not the mapped room` (the observations fit no place of the "
        "map; exit code 3)",
        "reason": "why there is no pose (absent with one)",
        "strategy": "`scan` (a short look: head sweep, turns while lost) or `paper`",
        "images": "top-camera pictures taken",
        "line_scans": "bottom-camera floor pictures taken (floor-wall lines)",
        "extra_turns": "quarter turns in place made while the belief was not concentrated",
        "robot_s": "the robot's time spent (simulated time on a simulator) (s)",
        "error_m": "distance to the truth (m); simulator only",
        "heading_error_deg": "heading error (deg); simulator only",
        "truth": "true pose [x, y, theta], map frame; simulator only",
        "localize_s": "wall-clock time (s)",
        "compute_s": "CPU time of the estimation alone (s): features, matching, the filter, "
        "floor lines; not the pictures or the motion",
        "covariance": "3 x 3 covariance of x, y, theta (m^2, rad^2): the belief's spread; "
        "absent without a pose",
        "png": "the picture written with --png",
        "map_checked": "false for a map kept with --keep-unchecked after failing a check",
        "record": "with --record: the recording written (`naoloc replay` re-runs it)",
        "ros2": "with --format ros2: the ROS 2 MCAP written beside (NAME.ros2.mcap)",
        "at": "with --at: the start asked for, {room: [x, y, theta] as given (room frame), "
        "map: the same in the map frame (null when the map lacks origin_room_pose)}",
    },
    "go-home": {
        "x": "the belief's final pose, map frame (m); null without one",
        "y": "the belief's final pose, map frame (m); null without one",
        "theta": "the belief's final heading, map frame (rad); null without one",
        "confidence": "probability of the final pose, 0..1",
        "method": "`filter`, or `none` without a pose",
        "status": "the final belief's status (`tracking`, `lost`, `not the mapped room`)",
        "covariance": "3 x 3 covariance of the final pose (m^2, rad^2)",
        "tries": "looks from standstill (the first one included): it stops to look only "
        "when the belief is lost",
        "reached": "true when the belief put the robot within go_home.tolerance_m of home",
        "path_m": "length of the first planned path home (m)",
        "walked_m": "distance walked by odometry (m)",
        "robot_s": "the robot's time spent (s)",
        "walk_s": "time to walk the planned path at a NAO's 0.1 m/s (s)",
        "start": "where the first look put the robot [x, y, theta], map frame",
        "reason": "why it stopped without reaching home (`blocked: ...` when the body "
        "touched a wall or furniture)",
        "error_m": "true distance from the map origin at the end (m); simulator only",
        "truth": "true final pose [x, y, theta], map frame; simulator only",
        "png": "the picture written with --png",
        "record": "with --record: the recording written (`naoloc replay` re-runs it)",
        "ros2": "with --format ros2: the ROS 2 MCAP written beside (NAME.ros2.mcap)",
        "at": "with --at: the start asked for, {room: [x, y, theta] as given (room frame), "
        "map: the same in the map frame (null when the map lacks origin_room_pose)}",
    },
    "track": {
        "poses": "poses streamed (one JSON line each before this one)",
        "tracking": "of those, with a pose",
        "rate_hz": "poses per second of robot time",
        "cpu_ms_median": "median CPU time per camera frame (ms)",
        "walked_m": "distance walked by odometry (m)",
        "median_error_m": "median error of the poses (m); simulator only",
        "reason": "why it stopped early (`blocked` when the body touched a wall or furniture)",
        "record": "with --record: the recording written (`naoloc replay` re-runs it)",
        "ros2": "with --format ros2: the ROS 2 MCAP written beside (NAME.ros2.mcap)",
        "at": "with --at: the start asked for, {room: [x, y, theta] as given (room frame), "
        "map: the same in the map frame (null when the map lacks origin_room_pose)}",
    },
    "evaluate": {
        "protocol": "`paper`, `random`, `anywhere` or `changed`",
        "n": "estimates of the main variant",
        "median_error_m": "median position error (m)",
        "p90_error_m": "90th percentile position error (m)",
        "max_error_m": "largest position error (m)",
        "median_heading_error_deg": "median heading error (deg)",
        "map_build_s": "build time of the main map (s)",
        "localize_ms_median": "median localization time (ms)",
        "no_estimate": "test poses where nothing was recognised (counted as misses)",
        "seed": "seed of the test poses",
        "survey_frames": "images of the base survey",
        "wall_s": "wall-clock time of the whole evaluation (s)",
        "report": "report.md written in OUTDIR",
        "summary": "summary.json written in OUTDIR (these fields, `positions` and more)",
        "executor": "`local` or `ray`",
    },
    "serve": {
        "endpoint": "the URL served",
        "transport": "`libqi`, `qimessaging` or `zmq`",
        "backend": "the simulated robot's backend",
        "calls": "service calls answered",
        "deadman_stops": "times a silent client got the robot stopped",
        "speed": "simulated seconds per wall second (`--speed`)",
        "errors": "calls answered with an error",
    },
    "demo": {
        "backend": "the robot's backend",
        "frames": "survey wall pictures",
        "survey_stopped": "why the survey stopped early (null: it completed; the demo goes on "
        "with the frames taken)",
        "images": "map keyframes (wall and far pictures)",
        "neurons": "GCS neurons",
        "distinct_poses": "distinct neuron poses",
        "map_build_s": "map build time (s)",
        "n": "poses localized",
        "no_estimate": "of those, poses where nothing was recognised",
        "median_error_m": "median position error (m)",
        "max_error_m": "largest position error (m)",
        "median_heading_error_deg": "median heading error (deg)",
        "localize_s_median": "median localization time (s)",
        "wall_s": "wall-clock time of the demo (s)",
        "dataset": "the dataset written",
        "map": "the map written",
        "png": "the picture of the estimates",
        "positions": "per pose: truth, estimate [x, y, theta] (map frame), error_m, "
        "heading_error_deg, confidence, localize_s",
    },
    "replay": {
        "recording": "the recording replayed",
        "verb": "what was recorded: `localize`, `track` or `go-home`",
        "complete": "false for a partial recording (the run was interrupted)",
        "observations": "observations given to the filter, in the recorded order",
        "pictures": "of those, pictures (the others: floor-line scans and odometry)",
        "x": "the replay's pose, map frame (m); null without one",
        "y": "the replay's pose, map frame (m); null without one",
        "theta": "the replay's heading, map frame (rad); null without one",
        "confidence": "as localize's, 0..1",
        "status": "`tracking`, `lost` or `not the mapped room` (exit 3 without a pose)",
        "covariance": "3 x 3 covariance of x, y, theta (m^2, rad^2); null without a pose",
        "recorded": "the estimate the run itself ended with (status, confidence, x, y, theta, "
        "covariance)",
        "same": "true when the replay's estimate equals the recorded one (1e-9)",
        "compute_s": "CPU time of the replay's filter (s)",
    },
    "check": {
        "ok": "true when nothing is missing (exit 0; otherwise exit 4)",
        "missing": "one line per problem found: what and how to fix it",
        "survey": "what a survey with this config walks: side_m, wall_offset_m, laps, path_m, "
        "stops, minutes (at a NAO's 0.1 m/s and 2 s per picture)",
        "link": "backend and what it reports (url, transport; model and room on simulators)",
        "camera": "one image: width, height, colorspace, index, mean_grey (0-255), lens (fx, "
        "fy, cx, cy px at this size, k1); null when it failed",
        "odometry": "getRobotPosition: sensors and commands [x, y, theta], odom frame",
        "joints": "head_yaw, head_pitch (rad) and camera_z_m (the camera's height from the "
        "robot's kinematics)",
        "posture": "posture name and awake (robotIsWakeUp)",
        "battery": "charge_percent (ALBattery; null on a simulator)",
        "nod": "with --nod: moved_rad, how far HeadPitch moved",
    },
}

# ``naoloc track`` prints one JSON line per camera frame before its summary line.
TRACK_LINE: dict[str, str] = {
    "t": "robot time of the frame (s; simulated time on a simulator)",
    "status": "`tracking`, `lost` or `not the mapped room`",
    "x": "pose, map frame (m); null without one",
    "y": "pose, map frame (m); null without one",
    "theta": "heading, map frame (rad); null without one",
    "confidence": "0..1; 0 without a pose",
    "covariance": "3 x 3 covariance of x, y, theta (m^2, rad^2); with a pose",
    "reason": "why there is no pose; without one",
    "truth": "true pose [x, y, theta], map frame; simulator only",
    "error_m": "distance to the truth (m); simulator only",
}

# Exit codes of every verb (naoloc/app/cli.py).
EXIT_CODES: dict[int, str] = {
    0: "success",
    1: "a naoloc error (bad config, file, robot or network): one line on stderr",
    2: "a usage error (unknown verb or flag, bad value): argparse's message",
    3: "`localize`, `track` or `replay` has no pose: the JSON line is still printed",
    4: "`check` found something missing: the JSON line is still printed, `missing` says what",
    70: "an unexpected exception, a bug: one line naming it (`NAOLOC_DEBUG=1` for the traceback)",
    130: "interrupted by SIGINT (Ctrl-C); the robot is stopped",
    143: "stopped by SIGTERM; the robot is stopped",
}


def _type_name(annotation: Any) -> str:
    """A short readable name of a field's type."""
    origin = typing.get_origin(annotation)
    args = typing.get_args(annotation)
    if origin is typing.Literal:
        return " \\| ".join(f"`{a}`" for a in args)
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type_name(a) for a in args)
    if origin is tuple and len(args) == 2 and args[1] is Ellipsis:
        return f"list of {_type_name(args[0])}"
    if origin is tuple:
        return f"[{', '.join(_type_name(a) for a in args)}]"
    if origin is list:
        return f"list of {_type_name(args[0])}" if args else "list"
    if annotation is type(None):
        return "null"
    return getattr(annotation, "__name__", str(annotation))


def _default(field: Any) -> str:
    value = field.default
    if value is PydanticUndefined:
        value = field.default_factory() if field.default_factory is not None else None
    if isinstance(value, BaseModel):
        return ""
    if isinstance(value, tuple):
        value = list(value)
    return "`null`" if value is None else f"`{value}`".replace("|", "\\|")


def config_rows(model: type[BaseModel], prefix: str = "") -> list[tuple[str, str, str, str]]:
    """(key path, type, default, description) of every leaf key of ``model``, in order."""
    rows = []
    for name, field in model.model_fields.items():
        path = f"{prefix}{name}"
        annotation = field.annotation
        sub = annotation if isinstance(annotation, type) else None
        if sub is not None and issubclass(sub, BaseModel):
            rows += config_rows(sub, path + ".")
            continue
        desc = (field.description or "").replace("|", "\\|")
        rows.append((path, _type_name(annotation), _default(field), desc))
    return rows


def _flag_rows(parser: argparse.ArgumentParser) -> list[tuple[str, str, str]]:
    rows = []
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        names = ", ".join(action.option_strings) or (action.metavar or action.dest)
        metavar = action.metavar
        if isinstance(metavar, tuple):
            metavar = " ".join(metavar)
        if action.choices:
            metavar = "|".join(str(c) for c in action.choices)
        if action.nargs == "?" and metavar:
            metavar = f"[{metavar}]"
        elif metavar is None and action.nargs != 0:
            metavar = action.dest.upper()
        usage = f"`{names} {metavar}`" if metavar and action.nargs != 0 else f"`{names}`"
        default = action.default
        if action.required:
            default_text = "required"
        elif default is None or default is False or (isinstance(default, str) and not default):
            default_text = ""
        else:
            default_text = f"`{default}`"
        if action.nargs == "?" and action.const is not None:
            default_text = f"off; `{action.const}` when given alone"
        rows.append(
            (usage.replace("|", "\\|"), default_text, (action.help or "").replace("|", "\\|"))
        )
    return rows


def render() -> str:
    """The whole page."""
    from naoloc.app.cli import VERBS, build_parser
    from naoloc.config import Config, shipped_configs

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    out = [
        "# naoloc command line reference",
        "",
        "Generated by `tools/gen_cli_doc.py` from the parser and the config models; do not edit",
        "by hand (`python tools/gen_cli_doc.py` rewrites it, `tests/integration/test_cli_doc.py`",
        "checks it).",
        "",
        "Every verb that computes a result ends stdout with ONE line of JSON (the fields below),",
        "after any human-readable text. Errors are one line on stderr and a non-zero exit code.",
        "Progress bars go to stderr, only on a terminal.",
        "",
        "| exit code | meaning |",
        "| --- | --- |",
        *[f"| {code} | {meaning} |" for code, meaning in EXIT_CODES.items()],
        "",
        "`-c CFG` takes a YAML file or the name of a config shipped in the package: "
        + ", ".join(f"`{n}`" for n in shipped_configs())
        + " (the files of `configs/`, without `sim_`). It works from any folder.",
        "",
        "## Verbs",
        "",
    ]
    for verb, verb_parser in sub.choices.items():
        out += [f"### `naoloc {verb}`", "", VERBS[verb], "", "| flag | default | meaning |"]
        out += ["| --- | --- | --- |"]
        out += [f"| {u} | {d} | {h} |" for u, d, h in _flag_rows(verb_parser)]
        fields = JSON_FIELDS.get(verb, {})
        if fields:
            out += ["", "JSON line:", "", "| field | meaning |", "| --- | --- |"]
            out += [f"| `{k}` | {v} |" for k, v in fields.items()]
        if verb == "track":
            out += ["", "Before it, one JSON line per camera frame:", "", "| field | meaning |"]
            out += ["| --- | --- |", *[f"| `{k}` | {v} |" for k, v in TRACK_LINE.items()]]
        out.append("")
    out += [
        "## Live view (`--live [PORT]`)",
        "",
        "`survey`, `localize`, `go-home` and `serve` take `--live [PORT]`: a Foxglove WebSocket",
        "server on 127.0.0.1:PORT (default 8765; 0 picks a free port, printed on stderr). Open",
        "it in Foxglove with *Open connection -> Foxglove WebSocket*, `ws://127.0.0.1:PORT`.",
        "The map topics are latched (sent again every second) for a viewer that joins late;",
        "`/tf` carries REP-105's `map -> odom -> base_link`. `--record FILE.mcap` (`localize`,",
        "`track`, `go-home`) writes the same topics to a file, with every observation the",
        "filter took (`naoloc/data/recording.py`); `naoloc replay FILE.mcap -m MAP.npz` re-runs",
        "the localization from it without a robot.",
        "Topics (see `naoloc/viz/live.py`):",
        "",
    ]
    from naoloc.viz import live

    doc = live.__doc__ or ""
    topics = [line for line in doc.splitlines() if line.startswith(("- ``/", "  "))][:20]
    out += [line.replace("``", "`") for line in topics]
    out += [
        "",
        "## Config keys",
        "",
        "YAML, validated: an unknown or wrong key is an error naming its path. Every key has a",
        "default. Types, defaults and meanings come from `naoloc/config.py`.",
        "",
        "| key | type | default | meaning |",
        "| --- | --- | --- | --- |",
    ]
    out += [f"| `{k}` | {t} | {d} | {m} |" for k, t, d, m in config_rows(Config)]
    out.append("")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    """Write docs/cli.md, or with --check say whether it is up to date."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 when out of date")
    args = parser.parse_args(argv)
    text = render()
    if args.check:
        current = DOC.read_text(encoding="utf-8") if DOC.is_file() else ""
        if current != text:
            print(f"{DOC.relative_to(REPO)} is out of date: run python tools/gen_cli_doc.py")
            return 1
        return 0
    DOC.write_text(text, encoding="utf-8")
    print(f"wrote {DOC.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(REPO))
    sys.exit(main())
