"""Progress bars on stderr, shown only when stderr is a terminal."""

from __future__ import annotations

import sys
import time
from typing import TextIO


class Progress:
    """A minimal progress bar: ``with Progress(total, "survey") as bar: bar.update()``.

    Args:
        total: Number of steps expected (0 or None for an open-ended counter).
        label: Text in front of the bar.
        stream: Where to draw; stderr by default.
        enabled: Force on or off; default: on when ``stream`` is a terminal.
    """

    def __init__(
        self,
        total: int | None,
        label: str,
        stream: TextIO | None = None,
        enabled: bool | None = None,
    ) -> None:
        self.total = total or 0
        self.label = label
        self.count = 0
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self._start = time.monotonic()
        self._last_draw = 0.0

    def update(self, n: int = 1, note: str = "") -> None:
        """Advance by ``n`` steps; redraws at most 10 times a second."""
        self.count += n
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self._last_draw < 0.1 and self.count < self.total:
            return
        self._last_draw = now
        elapsed = now - self._start
        if self.total:
            frac = min(1.0, self.count / self.total)
            bar = "#" * int(frac * 30)
            text = f"\r{self.label} [{bar:<30}] {self.count}/{self.total} {elapsed:5.1f}s {note}"
        else:
            text = f"\r{self.label} {self.count} {elapsed:5.1f}s {note}"
        self.stream.write(text[:160])
        self.stream.flush()

    def close(self) -> None:
        """Finish the line."""
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
