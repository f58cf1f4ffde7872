"""Progress bars on stderr, shown only when stderr is a terminal."""

from __future__ import annotations

import sys
import time
from typing import TextIO

_CLEAR = "\r\x1b[K"  # back to the line's start and erase it: a shorter redraw leaves no tail
_WIDTH = 160  # characters of a bar line at most


class Progress:
    """A minimal progress bar: ``with Progress(total, "survey") as bar: bar.update()``.

    The count never shows past its total: a run that takes more steps than expected
    grows the total with it. :meth:`note` prints a status line above the bar, which is
    redrawn below it, so status lines and the bar never overwrite each other.

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
        self._note = ""

    def update(self, n: int = 1, note: str = "") -> None:
        """Advance by ``n`` steps (``note``, when given, replaces the text after the bar);
        redraws at most 10 times a second, and always on the last step."""
        self.count += n
        if self.total and self.count > self.total:
            self.total = self.count  # never "160/150"
        if note:
            self._note = note
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self._last_draw < 0.1 and (not self.total or self.count < self.total):
            return
        self._draw(now)

    def note(self, text: str) -> None:
        """A status line printed above the bar (the bar is redrawn below it)."""
        if not self.enabled:
            return
        self.stream.write(f"{_CLEAR}{self.label}: {text}\n")
        self._draw(time.monotonic())

    def line(self) -> str:
        """The bar's text as drawn now (without the control characters)."""
        elapsed = time.monotonic() - self._start
        if self.total:
            frac = min(1.0, self.count / self.total)
            bar = "#" * int(frac * 30)
            text = f"{self.label} [{bar:<30}] {self.count}/{self.total} {elapsed:5.1f}s"
        elif self.count:
            text = f"{self.label} {self.count} {elapsed:5.1f}s"
        else:
            text = f"{self.label} {elapsed:5.1f}s"
        return f"{text} {self._note}".rstrip()[:_WIDTH]

    def _draw(self, now: float) -> None:
        self._last_draw = now
        self.stream.write(_CLEAR + self.line())
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
