"""Output files that appear whole or not at all.

A command writes each output under a temporary name in the output's own folder and moves
it into place with :func:`os.replace` (atomic on POSIX) only once every output of the run
exists. A run that fails or is interrupted before that leaves the previous outputs, and
the config copy that describes them, exactly as they were. A command that fills a whole
folder (``evaluate``) holds :func:`folder_lock` on it, so two runs never mix their files.
An output path that names something other than a regular file (a device node, a FIFO, a
folder) is refused before anything is written: the move would replace it.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, TYPE_CHECKING

from naoloc.errors import OutputBusy
from naoloc.safe_yaml import refuse_non_regular

if TYPE_CHECKING:
    from naoloc.config import Config

LOCK_NAME = ".naoloc.lock"


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

    Raises:
        ConfigError: A final path exists and is not a regular file.
    """
    for p in paths:
        refuse_non_regular(p)
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


@contextmanager
def folder_lock(folder: Path, what: str) -> Iterator[Path]:
    """Hold ``folder`` (created) for this process, or fail at once if another one holds it.

    The lock is an OS file lock on ``folder/.naoloc.lock`` (``flock`` on POSIX,
    ``msvcrt.locking`` on Windows): the OS releases it when the holder ends, also on a
    crash or a kill, so a stale lock never blocks a later run. The file stays; it holds
    the last holder's process id, which the error names.

    Args:
        folder: The output folder.
        what: The command, for the message (e.g. ``"naoloc evaluate"``).

    Yields:
        ``folder``.

    Raises:
        OutputBusy: Another process holds the folder.
    """
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / LOCK_NAME
    handle = open(path, "a+", encoding="utf-8")  # noqa: SIM115 - held for the block
    try:
        if not _try_lock(handle):
            handle.seek(0)
            holder = handle.read().strip() or "unknown"
            raise OutputBusy(
                f"{folder} is in use by another naoloc run (pid {holder}); "
                f"wait for it or give {what} another output folder"
            )
        handle.seek(0)
        handle.truncate()
        handle.write(f"{os.getpid()}\n")
        handle.flush()
        yield folder
    finally:
        with contextlib.suppress(OSError):
            _unlock(handle)
        handle.close()


def _try_lock(handle: IO[str]) -> bool:
    """Take an exclusive lock on ``handle`` without waiting; False if another holds it."""
    try:
        import fcntl
    except ImportError:  # Windows
        import msvcrt

        handle.seek(0)
        try:
            msvcrt.locking(handle.fileno(), msvcrt.LK_NBLCK, 1)  # type: ignore[attr-defined]
        except OSError:
            return False
        return True
    try:
        fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except (BlockingIOError, PermissionError):
        return False
    return True


def _unlock(handle: IO[str]) -> None:
    try:
        import fcntl
    except ImportError:  # Windows
        import msvcrt

        handle.seek(0)
        msvcrt.locking(handle.fileno(), msvcrt.LK_UNLCK, 1)  # type: ignore[attr-defined]
        return
    fcntl.flock(handle.fileno(), fcntl.LOCK_UN)


def config_path_for(output: Path) -> Path:
    """Where the resolved config of an output file goes: ``NAME.config.yaml`` beside it."""
    return output.with_name(output.stem + ".config.yaml")


def write_resolved_config(cfg: Config, path: Path) -> Path:
    """Write the resolved config (without secrets) as YAML at ``path``, atomically.

    Call it once the output the copy describes is written, so that a failed run never
    leaves a config copy that does not match the output beside it. Creates the folder.
    """
    return atomic_write_text(path, cfg.to_yaml())
