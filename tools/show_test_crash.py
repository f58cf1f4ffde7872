"""Print which test a crashed test run was in, and the crashing thread's frames.

Reads the file ``NAOLOC_TEST_CRASH_LOG`` named for the run (tests/conftest.py writes each
test's id there as it starts, and faulthandler's dump on a fatal signal). Prints a few
lines meant to be the last of a CI log::

    python tools/show_test_crash.py /tmp/naoloc-test-crash.log

Exit code 0 always (it reports on a failure, it is not one).
"""

from __future__ import annotations

import sys
from pathlib import Path

PREFIX = "naoloc-test: "
MAX_FRAMES = 14


def summary(text: str) -> list[str]:
    """The report's lines for the log ``text`` (see the module docstring)."""
    lines = text.splitlines()
    fatal = next((i for i, line in enumerate(lines) if line.startswith("Fatal Python error")), None)
    before = lines if fatal is None else lines[:fatal]
    tests = [line[len(PREFIX) :] for line in before if line.startswith(PREFIX)]
    last = tests[-1] if tests else "(none started)"
    if fatal is None:
        if lines and lines[-1] == PREFIX + "the run ended":
            return ["show_test_crash: the test run ended without a native crash"]
        return [
            "show_test_crash: no faulthandler dump; the run stopped (killed?) "
            f"after {len(tests)} tests, in or after: {last}"
        ]
    out = [f"show_test_crash: {lines[fatal]} in test {last} (test {len(tests)})"]
    current = next(
        (i for i in range(fatal, len(lines)) if lines[i].startswith("Current thread")), None
    )
    if current is None:
        out.append("show_test_crash: the dump names no current thread")
        return out
    frames: list[str] = []
    for line in lines[current + 1 :]:
        if not line.strip() or line.startswith(("Thread ", "Extension modules")):
            break
        frames.append(line)
    out.append(f"show_test_crash: the crashing thread ({len(frames)} frames, newest first):")
    out.extend(frames[:MAX_FRAMES])
    if len(frames) > MAX_FRAMES:
        out.append(f"  ... {len(frames) - MAX_FRAMES} more")
    return out


def main(argv: list[str]) -> int:
    """Print the report for the log file ``argv[0]``."""
    if len(argv) != 1:
        print("usage: python tools/show_test_crash.py CRASH_LOG", file=sys.stderr)
        return 0
    path = Path(argv[0])
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as err:
        print(f"show_test_crash: cannot read {path}: {err.strerror}")
        return 0
    print("\n".join(summary(text)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
