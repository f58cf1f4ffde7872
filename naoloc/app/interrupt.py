"""SIGINT and SIGTERM end a command cleanly, also in background jobs.

A shell that starts a job with ``&`` (non-interactive) sets SIGINT to ``SIG_IGN``, and
Python then leaves it ignored; a plain ``kill`` sends SIGTERM, which Python does not turn
into an exception at all. :func:`interruptible` installs handlers for both that raise
:class:`Interrupted` (a ``KeyboardInterrupt``), so every ``finally`` runs: the robot is
stopped and partial outputs are kept. The exit code is ``128 + signal number`` (130 for
SIGINT, 143 for SIGTERM). While that cleanup runs, a second signal is ignored; a third
one ends the process at once with the default action.
"""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType


class Interrupted(KeyboardInterrupt):
    """SIGINT or SIGTERM arrived.

    Attributes:
        signum: The signal number.
    """

    def __init__(self, signum: int) -> None:
        super().__init__(f"signal {signum}")
        self.signum = signum


def exit_code(err: KeyboardInterrupt) -> int:
    """The shell's exit code for an interrupt: 128 + signal number (130 for Ctrl-C)."""
    return 128 + int(getattr(err, "signum", signal.SIGINT))


@contextmanager
def interruptible() -> Iterator[None]:
    """Make SIGINT and SIGTERM raise :class:`Interrupted` inside the block, then restore.

    Outside the main thread (where Python cannot set handlers) this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[int] = []

    def handler(signum: int, frame: FrameType | None) -> None:
        received.append(signum)
        if len(received) == 1:
            raise Interrupted(signum)
        if len(received) >= 3:  # cleanup hangs: give the user the default action back
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)

    old_int = signal.signal(signal.SIGINT, handler)
    old_term = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old_int)
        signal.signal(signal.SIGTERM, old_term)
