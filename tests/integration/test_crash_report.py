"""A native crash in the test runner is reported with its test and thread (tests/conftest.py).

A test run in a child process aborts (SIGABRT) on a worker thread, as libzmq or a GL driver
would; ``tools/show_test_crash.py`` then names the test and shows the thread's frames.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.tools import load_tool

TOOL = Path(__file__).resolve().parents[2] / "tools" / "show_test_crash.py"
pytestmark = pytest.mark.skipif(not TOOL.is_file(), reason="needs the checkout's tools/")


def summary(text: str) -> list[str]:
    """tools/show_test_crash.py's report of a crash log."""
    lines: list[str] = load_tool("show_test_crash").summary(text)
    return lines


BOOM = """
import faulthandler, threading, time

def test_quiet():
    pass

def _worker_that_aborts():
    faulthandler._sigabrt()

def test_aborts_on_a_thread():
    threading.Thread(target=_worker_that_aborts, name="worker").start()
    time.sleep(30)
"""


def _run(tmp_path: Path, source: str) -> tuple[subprocess.CompletedProcess[str], Path]:
    shutil.copy(Path(__file__).parents[1] / "conftest.py", tmp_path / "conftest.py")
    (tmp_path / "test_boom.py").write_text(source)
    log = tmp_path / "crash.log"
    env = dict(os.environ, NAOLOC_TEST_CRASH_LOG=str(log))
    child = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_boom.py"],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    return child, log


def test_an_abort_on_a_thread_names_the_test_and_the_thread(tmp_path: Path) -> None:
    child, log = _run(tmp_path, BOOM)
    assert child.returncode == -signal.SIGABRT, child.stdout[-2000:] + child.stderr[-2000:]
    report = summary(log.read_text())
    assert report[0].startswith("show_test_crash: Fatal Python error: Aborted"), report
    assert "test_boom.py::test_aborts_on_a_thread (test 2)" in report[0], report
    assert any("_worker_that_aborts" in line for line in report[2:]), report
    assert not any("test_aborts_on_a_thread" in line for line in report[2:]), report


def test_a_run_that_ends_reports_no_crash(tmp_path: Path) -> None:
    child, log = _run(tmp_path, "def test_fine():\n    pass\n")
    assert child.returncode == 0, child.stdout[-2000:]
    assert summary(log.read_text()) == [
        "show_test_crash: the test run ended without a native crash"
    ]


def test_a_killed_run_names_the_last_test_started() -> None:
    report = summary("naoloc-test: a.py::one\nnaoloc-test: a.py::two\n")
    assert report == [
        "show_test_crash: no faulthandler dump; the run stopped (killed?) after 2 tests, "
        "in or after: a.py::two"
    ]
