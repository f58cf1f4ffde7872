"""Where a native crash happened: the test and the crashing thread, when CI asks.

pytest's faulthandler dumps every thread on a fatal signal (SIGABRT, SIGSEGV), the main
thread last, so the tail of a CI log shows only pytest's own frames and not the test that
died. With ``NAOLOC_TEST_CRASH_LOG`` set to a file, each test's id is written there as it
starts and the dump goes there too; ``tools/show_test_crash.py FILE`` prints the test and
the crashing thread's frames (``.ci/run`` does when ``make test`` fails).
"""

from __future__ import annotations

import faulthandler
import os
import tempfile
from typing import TextIO

import pytest

_LOG = pytest.StashKey[TextIO]()


@pytest.hookimpl(trylast=True)  # after pytest's own faulthandler plugin has enabled it
def pytest_configure(config: pytest.Config) -> None:
    # TLS clients pin robots' certificates under XDG_CONFIG_HOME: never the user's own.
    os.environ["XDG_CONFIG_HOME"] = tempfile.mkdtemp(prefix="naoloc-test-config-")
    path = os.environ.get("NAOLOC_TEST_CRASH_LOG")
    if not path:
        return
    log = open(path, "w", encoding="utf-8", buffering=1)  # noqa: SIM115 - open for the run
    config.stash[_LOG] = log
    faulthandler.enable(file=log, all_threads=True)


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item: pytest.Item) -> None:
    log = item.config.stash.get(_LOG, None)
    if log is not None:
        log.write(f"naoloc-test: {item.nodeid}\n")


@pytest.hookimpl(tryfirst=True)  # before pytest's plugin puts faulthandler back on stderr
def pytest_unconfigure(config: pytest.Config) -> None:
    log = config.stash.get(_LOG, None)
    if log is not None:
        faulthandler.disable()  # never left writing to a closed (soon reused) descriptor
        log.write("naoloc-test: the run ended\n")
        log.close()
        del config.stash[_LOG]
