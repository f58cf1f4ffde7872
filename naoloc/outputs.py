"""Output files that appear whole or not at all.

A command writes each output under a temporary name in the output's own folder and moves
it into place with :func:`os.replace` (atomic on POSIX) only once every output of the run
exists. A run that fails or is interrupted before that leaves the previous outputs, and
the config copy that describes them, exactly as they were.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


def staging_path(path: Path) -> Path:
    """A temporary sibling of ``path`` with the same suffix (``.NAME.PID.tmp.SUFFIX``).

    The suffix is kept so that writers choosing a format from the name (matplotlib,
    numpy) still do the right thing.
    """
    return path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")


@contextmanager
def staged(*paths: Path) -> Iterator[list[Path]]:
    """Write several outputs under temporary names; move them all into place on success.

    Example::

        with staged(map_path, png_path) as (tmp_map, tmp_png):
            save(tmp_map); plot(tmp_png)
        # both replaced here; on an exception neither is, and the temporaries are gone

    Args:
        paths: The final paths (their folders are created).

    Yields:
        The temporary paths, in the same order.
    """
    temps = [staging_path(p) for p in paths]
    for p in paths:
        p.parent.mkdir(parents=True, exist_ok=True)
    try:
        yield temps
    except BaseException:
        for tmp in temps:
            tmp.unlink(missing_ok=True)
        raise
    try:
        for tmp, final in zip(temps, paths, strict=True):
            os.replace(tmp, final)
    finally:
        for tmp in temps:
            tmp.unlink(missing_ok=True)


def atomic_write_text(path: Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically (temporary file + :func:`os.replace`)."""
    with staged(path) as (tmp,):
        tmp.write_text(text, encoding="utf-8")
    return path
