"""Run a script written for the old NAOqi Python SDK on Python 3: ``python -m naoloc.run``.

    python -m naoloc.run [--url tcp://nao.local:9559] script.py [script arguments...]

The script runs as ``__main__`` (its folder first on ``sys.path``, its own arguments in
``sys.argv``) with the old SDK's top-level modules importable: ``naoqi`` (``ALProxy``,
``ALBroker``, ``ALModule``, see :mod:`naoloc.backends.naoqi.oldsdk`), ``motion``,
``almath`` (in part) and ``vision_definitions``, all over naoloc.qi (pure Python, no
libqi, any OS). ``--url`` is the robot that ``ALProxy(name)`` reaches when the script
made no ALBroker (default ``$NAOLOC_NAOQI_URL``, else ``tcp://127.0.0.1:9559``).

Nothing is installed: outside this launcher ``import naoqi`` is untouched. When
Aldebaran's own ``naoqi`` is importable, it wins (a notice says so) unless
``--shim`` asks for naoloc's. Python-2-only syntax in a script is not translated.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import runpy
import sys
from pathlib import Path

SHIM = Path(__file__).resolve().parent / "backends" / "naoqi" / "sdk"
URL_ENV = "NAOLOC_NAOQI_URL"


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m naoloc.run",
        description="Run an old-SDK NAO script (from naoqi import ALProxy) on Python 3.",
    )
    parser.add_argument("--url", help="the robot for ALProxy(name) without a broker")
    parser.add_argument(
        "--shim", action="store_true", help="use naoloc's naoqi even if the official one exists"
    )
    parser.add_argument("script", help="the script to run")
    parser.add_argument("args", nargs=argparse.REMAINDER, help="the script's own arguments")
    return parser


def official_naoqi() -> str | None:
    """Where Aldebaran's ``naoqi`` module is, if it is importable (None otherwise)."""
    spec = importlib.util.find_spec("naoqi")
    if spec is None or spec.origin is None:
        return None
    origin = Path(spec.origin).resolve()
    return None if SHIM in origin.parents else str(origin)


def main(argv: list[str] | None = None) -> int:
    """Run the script; its exit code (2 for a script that cannot be found)."""
    args = _parser().parse_args(argv)
    script = Path(args.script)
    if not script.is_file():
        print(f"naoloc.run: no script at {script}", file=sys.stderr)
        return 2
    if args.url:
        os.environ[URL_ENV] = args.url
    official = None if args.shim else official_naoqi()
    sys.path.insert(0, str(script.resolve().parent))
    if official is None:
        sys.path.insert(1, str(SHIM))
    else:
        print(f"naoloc.run: using the official naoqi at {official}", file=sys.stderr)
    sys.argv = [str(script), *args.args]
    try:
        runpy.run_path(str(script), run_name="__main__")
    except SystemExit as done:
        code = done.code
        if code is None:
            return 0
        if isinstance(code, int):
            return code
        print(code, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
