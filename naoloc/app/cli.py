"""The ``naoloc`` command line: survey, build-map, localize, track, go-home, evaluate, serve,
demo, check.

Each verb lives in ``naoloc.app.commands.<verb>`` and returns a JSON-able dict that is
printed as the single last line of stdout. Errors are one line on stderr and a
non-zero exit: 1 for a naoloc error, 2 for bad usage, 3 when ``localize`` recognised
nothing (its JSON line is still printed, with null pose fields), 4 when ``check`` found
something missing (its JSON line is still printed, ``missing`` says what), 70 for a bug (an
unexpected exception: one line naming it; set ``NAOLOC_DEBUG=1`` for the traceback), 130
for SIGINT (Ctrl-C) and 143 for SIGTERM. Both signals are honoured also where the shell
ignores SIGINT (background jobs): :func:`naoloc.app.interrupt.interruptible` installs the
handlers for the whole run. Notes attached to the error (e.g. where a partial dataset was
kept) join its line.
"""

from __future__ import annotations

import argparse
import difflib
import importlib
import json
import math
import os
import sys
import traceback
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from naoloc import __version__
from naoloc.app.interrupt import exit_code, interruptible
from naoloc.config import Config, load_config
from naoloc.errors import NaolocError, NotBuiltError

EXIT_INTERNAL = 70  # sysexits.h EX_SOFTWARE: an unexpected exception (a bug)
_MAX_MESSAGE = 500  # characters of an unexpected exception's message printed on stderr
_MAX_LINE = 1000  # characters of an error line (with its notes) printed on stderr

VERBS: dict[str, str] = {
    "survey": "Algorithm 3: walk closed laps, record images and odometry poses (MCAP)",
    "build-map": "Algorithm 4: features -> histograms -> GCS -> neuron poses (map .npz)",
    "localize": "the robot's pose in the map from a short look (or the paper's 1-2 images)",
    "go-home": "walk back to the map origin on the live pose",
    "track": "the pose at every camera frame while the robot walks (JSON lines)",
    "evaluate": "measure localization error with the paper or random protocol",
    "serve": "serve a simulated robot as a virtual NAOqi",
    "demo": "survey -> build map -> localize in the default simulated room",
    "check": "connect and read camera, odometry, joints and battery; nothing walks",
    "replay": "re-run a recorded localization (--record) without a robot; the same estimate",
}


def _pose(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def _positive(text: str) -> float:
    value = _pose(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive number")
    return value


def _count(low: int, high: int) -> Any:
    """An argparse type: an integer in ``[low, high]`` (a usage error otherwise)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{value} is outside [{low}, {high}]")
        return value

    return parse


CONFIG_HELP = "a YAML file, or a shipped config: paper_room, lab_room, nao"
LIVE_PORT = 8765


def _add_format(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--format", choices=("naoloc", "ros2"), default="naoloc",
        help="ros2: also write NAME.ros2.mcap beside the file, as ROS 2 messages (CDR: "
        "sensor_msgs/Image and CameraInfo, nav_msgs/Odometry, tf2_msgs/TFMessage, "
        "geometry_msgs/PoseWithCovarianceStamped) that ros2 bag and Foxglove read",
    )  # fmt: skip


def _add_live(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--live", nargs="?", type=int, const=LIVE_PORT, default=None, metavar="PORT",
        help=f"stream to Foxglove over a WebSocket on 127.0.0.1:PORT (default {LIVE_PORT})",
    )  # fmt: skip


def build_parser() -> argparse.ArgumentParser:
    """The argparse parser for every verb."""
    parser = argparse.ArgumentParser(
        prog="naoloc",
        description="A NAO learns a room and finds itself in it from what its camera sees.",
    )
    parser.add_argument("--version", action="version", version=f"naoloc {__version__}")
    sub = parser.add_subparsers(dest="verb", metavar="VERB", required=True)

    def add(verb: str, config: bool = True) -> argparse.ArgumentParser:
        p = sub.add_parser(verb, help=VERBS[verb], description=VERBS[verb])
        if config:
            p.add_argument("-c", "--config", required=True, metavar="CFG", help=CONFIG_HELP)
        return p

    p = add("survey")
    p.add_argument(
        "-o", "--output", required=True, metavar="DATASET.mcap", type=Path,
        help="the dataset to write (its resolved config goes beside it)",
    )  # fmt: skip
    _add_format(p)
    _add_live(p)
    p = add("build-map")
    p.add_argument(
        "-d", "--dataset", required=True, metavar="DATASET.mcap", type=Path,
        help="a survey's dataset",
    )  # fmt: skip
    p.add_argument(
        "-o", "--output", required=True, metavar="MAP.npz", type=Path,
        help="the map to write (a picture of it goes beside it)",
    )  # fmt: skip
    p.add_argument(
        "--keep-unchecked", action="store_true",
        help="keep a map that failed a check, marked unchecked (localize says so)",
    )  # fmt: skip
    for verb in ("localize", "go-home", "track"):
        p = add(verb)
        p.add_argument(
            "-m", "--map", required=True, metavar="MAP.npz", type=Path, help="a built map"
        )  # fmt: skip
        p.add_argument(
            "--at", nargs=3, type=_pose, metavar=("X", "Y", "THETA"),
            help="teleport there first (simulator only), in the ROOM frame (m, rad: from the "
            "simulated room's corner, not the map's origin; results are in the map frame and "
            "the JSON's `at` echoes it in both)",
        )  # fmt: skip
        p.add_argument("--png", type=Path, default=None, help="write a picture of the result")
        p.add_argument(
            "--record", type=Path, default=None, metavar="FILE.mcap",
            help="record every observation (pictures, floor lines, odometry) and estimate as "
            "they are made; `naoloc replay` re-runs the localization from it",
        )  # fmt: skip
        _add_format(p)
        _add_live(p)
        if verb == "track":
            p.add_argument(
                "--to", nargs=2, type=_pose, metavar=("X", "Y"), default=None,
                help="walk to this point (map frame, m) while tracking; default: stand",
            )  # fmt: skip
            p.add_argument(
                "--duration", type=_positive, default=20.0, metavar="S",
                help="robot seconds to track at most (default 20)",
            )  # fmt: skip
    p = add("evaluate")
    p.add_argument(
        "--protocol", choices=("paper", "random", "anywhere", "changed"), default="random",
        help="changed: anywhere, in the room with world.room.changes (default: 30 %% of the "
        "furniture moved up to 0.5 m, 2 boxes added); the map is of the room as surveyed",
    )  # fmt: skip
    p.add_argument("-n", type=_count(1, 100_000), default=40, help="test poses (random protocol)")
    p.add_argument("--seed", type=_count(0, 2**63 - 1), default=0, help="seed of the test poses")
    p.add_argument(
        "--workers", type=_count(1, 1024), default=None, help="processes (default: cores)"
    )
    p.add_argument(
        "--studies", default="none", metavar="LIST",
        help="extra studies: none, all, or a comma list of compare,robustness",
    )  # fmt: skip
    p.add_argument(
        "--record", action="store_true",
        help="record each localization's observations in OUTDIR/recordings "
        "(VARIANT_INDEX.mcap; naoloc replay re-runs one without a robot)",
    )  # fmt: skip
    p.add_argument(
        "--executor", choices=("local", "ray"), default="local",
        help="local: a process pool on this machine; ray: tasks on a Ray cluster (extra 'ray')",
    )  # fmt: skip
    p.add_argument(
        "--ray-address", default=None, metavar="ADDR",
        help="Ray cluster to join (e.g. ray://host:10001); default: start a local one",
    )  # fmt: skip
    p.add_argument(
        "-o", "--output", required=True, metavar="OUTDIR", type=Path,
        help="folder for summary.json, report.md, PNGs, surveys and maps "
        "(held while the run lasts: a second evaluate into it fails at once)",
    )  # fmt: skip
    p = add("serve")
    p.add_argument(
        "--listen", default="tcp://127.0.0.1:9559", metavar="URL",
        help="address to serve on (port 0 picks a free one)",
    )  # fmt: skip
    p.add_argument(
        "--transport", choices=("libqi", "zmq", "qimessaging"), default=None,
        help="default: robot.transport of the config",
    )  # fmt: skip
    p.add_argument(
        "--allow-remote", action="store_true",
        help="allow binding to a non-loopback address (zmq needs CURVE keys then; qimessaging "
        "--login over tcps://)",
    )  # fmt: skip
    p.add_argument(
        "--speed", type=_pose, default=1.0, metavar="K",
        help="simulated seconds per wall second (default 1.0, as a NAO)",
    )  # fmt: skip
    p.add_argument(
        "--login", action="store_true",
        help="qimessaging: clients log in (user NAOLOC_SERVE_USER, default nao; password "
        "NAOLOC_SERVE_PASSWORD or typed at a prompt); needed off loopback",
    )  # fmt: skip
    p.add_argument("--tls-cert", type=Path, metavar="PEM", help="qimessaging tcps://: certificate")
    p.add_argument("--tls-key", type=Path, metavar="PEM", help="its key, if not in --tls-cert")
    p.add_argument(
        "--command-timeout", type=_pose, default=None, metavar="S",
        help="stop a velocity walk whose client is silent this long (default 0.4 s; 0 = never, "
        "as NAOqi)",
    )  # fmt: skip
    p.add_argument(
        "--trace", type=Path, default=None, metavar="FILE",
        help="append one line per call a client makes ('<caller> <Service>.<method>')",
    )  # fmt: skip
    _add_live(p)
    p = add("demo", config=False)
    p.add_argument("-c", "--config", default="paper_room", metavar="CFG", help=CONFIG_HELP)
    p.add_argument(
        "-o", "--output", type=Path, default=Path("runs/demo"), metavar="OUTDIR",
        help="folder for the dataset, the map and the pictures",
    )  # fmt: skip
    p = add("replay", config=False)
    p.add_argument("recording", type=Path, metavar="FILE.mcap", help="a --record recording")
    p.add_argument(
        "-m", "--map", required=True, metavar="MAP.npz", type=Path, help="the map to replay in"
    )  # fmt: skip
    p.add_argument(
        "-c", "--config", default=None, metavar="CFG",
        help="the filter's tuning (localize.filter); default: the recording's own config",
    )  # fmt: skip
    p = add("check")
    p.add_argument(
        "--nod", action="store_true",
        help="also nod the head (HeadPitch 0.15 rad down and back); nothing else moves",
    )  # fmt: skip
    return parser


def _run_verb(verb: str, args: argparse.Namespace, cfg: Config) -> dict[str, Any]:
    module_name = f"naoloc.app.commands.{verb.replace('-', '_')}"
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as err:
        if err.name == module_name:
            raise NotBuiltError(f"'naoloc {verb}' is not built yet") from None
        raise
    result: dict[str, Any] = module.run(args, cfg)
    return result


def one_line(text: object, limit: int = _MAX_MESSAGE) -> str:
    """``text`` as one terminal line: newlines folded, at most ``limit`` characters."""
    line = " ".join(str(text).split())
    return line if len(line) <= limit else line[: limit - 3] + "..."


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``naoloc`` console script. Returns the exit code.

    The last line of defence: a naoloc error is one line on stderr (exit 1); any other
    exception is one line naming it and a hint (exit :data:`EXIT_INTERNAL`), with the
    traceback only when the environment sets ``NAOLOC_DEBUG=1``.
    """
    parser = build_parser()
    words = list(sys.argv[1:] if argv is None else argv)
    if words and not words[0].startswith("-") and words[0] not in VERBS:
        close = difflib.get_close_matches(words[0], list(VERBS), n=1, cutoff=0.6)
        if close:  # exit 2, as argparse's own "invalid choice"
            parser.error(f"unknown verb {words[0]!r}; did you mean {close[0]!r}?")
    args = parser.parse_args(words)
    verb: str = args.verb
    with interruptible():
        return _guarded(verb, args)


def _with_notes(text: str, err: BaseException) -> str:
    """``text`` and the error's notes (``add_note``) on one line."""
    notes = [str(n).replace("\n", " ") for n in getattr(err, "__notes__", ())]
    return "; ".join([text, *notes])


def _guarded(verb: str, args: argparse.Namespace) -> int:
    try:
        return _main(verb, args)
    except Exception as err:  # the last line of defence: a bug, never a bare traceback
        if os.environ.get("NAOLOC_DEBUG") == "1":
            traceback.print_exc()
        what = one_line(f"{type(err).__name__}: {err}" if str(err) else type(err).__name__)
        print(
            f"naoloc {verb}: internal error: {what} (a bug: please report it; "
            "NAOLOC_DEBUG=1 shows the traceback)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


def _main(verb: str, args: argparse.Namespace) -> int:
    try:
        config_src = getattr(args, "config", None)
        cfg = load_config(config_src)
        result = _run_verb(verb, args, cfg)
    except KeyboardInterrupt as err:
        print(_with_notes(f"naoloc {verb}: interrupted", err), file=sys.stderr)
        return exit_code(err)
    except NaolocError as err:
        carried = getattr(err, "result", None)
        if not isinstance(carried, dict):
            text = _with_notes(f"naoloc {verb}: error: {err}", err)
            print(one_line(text, _MAX_LINE), file=sys.stderr)
            return 1
        # localize with no estimate, check with something missing: the result line still
        # ends stdout (no pose in it; what is missing), and the verb's own exit code
        sys.stdout.write(json.dumps(carried, separators=(", ", ": ")) + "\n")
        sys.stdout.flush()
        print(f"naoloc {verb}: {err}", file=sys.stderr)
        return int(getattr(err, "exit_code", 1))
    except OSError as err:  # a path that cannot be read or written
        where = f": {err.filename}" if err.filename else ""
        text = f"naoloc {verb}: error: {err.strerror or err}{where}"
        print(one_line(_with_notes(text, err), _MAX_LINE), file=sys.stderr)
        return 1
    sys.stdout.write(json.dumps(result, separators=(", ", ": ")) + "\n")
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
