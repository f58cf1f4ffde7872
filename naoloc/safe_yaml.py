"""Bounded input: YAML config files (no bombs, no recursion, no NaN, no duplicate keys),
and the regular files every input is read from.

:func:`open_regular` opens an input only when it is a regular file (a device node, a
FIFO or a folder gets a one-line refusal, and opening never waits for a FIFO's writer);
:func:`refuse_non_regular` is its counterpart for outputs (an output never replaces a
device node). Readers then read no more than their format's limit.

:func:`load_yaml` reads at most :data:`MAX_CONFIG_BYTES` bytes and parses them with a
``yaml.SafeLoader`` that refuses, while composing, more than :data:`MAX_NODES` nodes and
nesting deeper than :data:`MAX_DEPTH`; before anything is constructed it counts what the
aliases expand to (a "billion laughs" file is a few hundred bytes that expand to 10**9
values) and refuses more than :data:`MAX_EXPANDED` values or a recursive alias. Integers
with more than :data:`MAX_INT_CHARS` characters are never converted (Python refuses more
than 4300 digits with a ValueError; a seed never needs more than 64 bits). A mapping
that names a key twice is refused (YAML says keys are unique; PyYAML keeps the last).

:func:`check_values` walks plain data (from YAML or a dict) and names the key path of the
first value that is not finite, too long or too deep. :func:`short_repr` never formats
more than a bounded part of a value, so an error message stays short and cheap.
"""

from __future__ import annotations

import math
import os
import reprlib
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any, Final

import yaml

from naoloc.errors import ConfigError, NaolocError

_KINDS: Final = (
    (stat.S_ISDIR, "a folder"), (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"),
)  # fmt: skip


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def open_regular(path: Path, what: str, error: type[NaolocError] = ConfigError) -> IO[bytes]:
    """Open ``path`` for reading if it is a regular file (never waits on a FIFO).

    Args:
        path: The input.
        what: What it should be, for messages (e.g. ``"config file"``).
        error: The error type raised.

    Raises:
        NaolocError: (``error``) ``path: no such <what>``, ``path: is a folder, not a
            <what>``, ``path: is a FIFO, not a <what>``, or why it cannot be read.
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise error(f"{path}: no such {what}") from None
    except IsADirectoryError:
        raise error(f"{path}: is a folder, not a {what}") from None
    except OSError as err:
        raise error(f"{path}: cannot read: {err.strerror or err}") from None
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        raise error(f"{path}: is {_kind(mode)}, not a {what}")
    if hasattr(os, "set_blocking"):
        os.set_blocking(fd, True)
    return os.fdopen(fd, "rb")


def refuse_non_regular(path: Path, error: type[NaolocError] = ConfigError) -> None:
    """Refuse an output path that exists and is not a regular file (a device, a FIFO...).

    Outputs are written beside and moved into place, which would replace a device node
    with a file.
    """
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return  # missing (or a dangling link): a new file
    if not stat.S_ISREG(mode):
        raise error(f"{path}: is {_kind(mode)}; naoloc writes only regular files")


MAX_CONFIG_BYTES: Final = 256 * 1024
MAX_NODES: Final = 20_000
MAX_EXPANDED: Final = 100_000
MAX_DEPTH: Final = 64
MAX_INT_CHARS: Final = 20
MAX_STR_CHARS: Final = 4096
INT_LIMIT: Final = 2**63

_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxlist, _REPR.maxtuple, _REPR.maxdict = 2, 4, 4, 4
_REPR.maxstring, _REPR.maxother, _REPR.maxlong = 40, 40, 40


def short_repr(value: Any, limit: int = 80) -> str:
    """A repr of ``value`` of at most ``limit`` characters, computed in bounded time."""
    text = _REPR.repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


class _Refused(yaml.MarkedYAMLError):
    """A YAML document over one of the limits (reported like a YAML syntax error)."""

    def __init__(self, problem: str, mark: Any) -> None:
        super().__init__(problem=problem, problem_mark=mark)


class BadScalar:
    """Stands for a scalar that cannot be converted (so the error can name its key path).

    Attributes:
        problem: What is wrong, e.g. "an integer of 5000 digits is too long (at most 20)".
    """

    def __init__(self, problem: str) -> None:
        self.problem = problem

    def __repr__(self) -> str:
        return f"<{self.problem}>"


class _BoundedLoader(yaml.SafeLoader):
    """A SafeLoader that counts nodes and nesting while it composes."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._nodes = 0
        self._depth = 0

    def construct_mapping(self, node: Any, deep: bool = False) -> Any:
        seen: set[Any] = set()
        for key_node, _ in node.value if isinstance(node, yaml.MappingNode) else ():
            if isinstance(key_node, yaml.ScalarNode) and key_node.tag != "tag:yaml.org,2002:merge":
                if key_node.value in seen:
                    raise _Refused(
                        f"the key {short_repr(key_node.value, 40)} appears twice",
                        key_node.start_mark,
                    )
                seen.add(key_node.value)
        return super().construct_mapping(node, deep=deep)

    def compose_node(self, parent: Any, index: Any) -> Any:
        self._nodes += 1
        if self._nodes > MAX_NODES:
            raise _Refused(f"more than {MAX_NODES} values", self.peek_event().start_mark)
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise _Refused(
                    f"nested deeper than {MAX_DEPTH} levels", self.peek_event().start_mark
                )
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


def _construct_int(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> Any:
    chars = len(str(node.value))
    if chars > MAX_INT_CHARS:
        return BadScalar(f"an integer of {chars} digits is too long (at most {MAX_INT_CHARS})")
    return yaml.SafeLoader.construct_yaml_int(loader, node)


def _construct_timestamp(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> Any:
    try:
        return yaml.SafeLoader.construct_yaml_timestamp(loader, node)
    except (ValueError, OverflowError) as err:
        return BadScalar(f"bad date {short_repr(node.value, 40)}: {err}")


_BoundedLoader.add_constructor("tag:yaml.org,2002:int", _construct_int)
_BoundedLoader.add_constructor("tag:yaml.org,2002:timestamp", _construct_timestamp)


def _children(node: yaml.Node) -> Iterator[yaml.Node]:
    if isinstance(node, yaml.SequenceNode):
        yield from node.value
    elif isinstance(node, yaml.MappingNode):
        for key, value in node.value:
            yield key
            yield value


def _expanded(
    node: yaml.Node, level: int, memo: dict[int, tuple[int, int]], active: set[int]
) -> int:
    """Values ``node`` stands for once every alias is expanded; checks depth and cycles."""
    key = id(node)
    if key in memo:
        size, height = memo[key]
        if level + height > MAX_DEPTH:
            raise _Refused(f"aliases nest deeper than {MAX_DEPTH} levels", node.start_mark)
        return size
    if key in active:
        raise _Refused("recursive alias (an anchor used inside itself)", node.start_mark)
    if level > MAX_DEPTH:
        raise _Refused(f"aliases nest deeper than {MAX_DEPTH} levels", node.start_mark)
    active.add(key)
    size, height = 1, 0
    for child in _children(node):
        size += _expanded(child, level + 1, memo, active)
        height = max(height, memo[id(child)][1] + 1)
        if size > MAX_EXPANDED:
            raise _Refused(
                f"aliases expand to more than {MAX_EXPANDED} values (a YAML alias bomb?)",
                node.start_mark,
            )
    active.discard(key)
    memo[key] = (size, height)
    return size


def read_text(path: Path) -> str:
    """The text of a config file of at most :data:`MAX_CONFIG_BYTES` bytes.

    Raises:
        ConfigError: Missing, unreadable, not a regular file, too large, not UTF-8.
    """
    try:
        with open_regular(path, "config file") as stream:
            raw = stream.read(MAX_CONFIG_BYTES + 1)
    except OSError as err:
        raise ConfigError(f"{path}: cannot read: {err.strerror or err}") from None
    if len(raw) > MAX_CONFIG_BYTES:
        raise ConfigError(f"{path}: too large for a config file (over {MAX_CONFIG_BYTES} bytes)")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ConfigError(f"{path}: not UTF-8 text (byte {err.start})") from None


def load_yaml(text: str, source: str) -> Any:
    """Parse one YAML document within the limits of this module.

    Raises:
        ConfigError: ``source: line N: problem`` for bad YAML or a document over a limit.
    """
    loader = None
    try:
        loader = _BoundedLoader(text)  # the reader refuses control characters already here
        node = loader.get_single_node()
        if node is None:
            return None
        _expanded(node, 0, {}, set())
        return loader.construct_document(node)
    except yaml.reader.ReaderError as err:  # control characters, bad encodings
        code = f"#x{err.character:04x}" if isinstance(err.character, int) else "a character"
        raise ConfigError(f"{source}: character {err.position}: {code}: {err.reason}") from None
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" line {mark.line + 1}:" if mark is not None else ""
        problem = getattr(err, "problem", None) or getattr(err, "reason", None) or "invalid YAML"
        raise ConfigError(f"{source}:{where} {' '.join(str(problem).split())[:160]}") from None
    except (ValueError, TypeError, OverflowError, RecursionError) as err:  # e.g. 2001-02-30
        reason = " ".join(str(err).split())[:160]
        raise ConfigError(
            f"{source}: cannot read a value: {type(err).__name__}: {reason}"
        ) from None
    finally:
        if loader is not None:
            loader.dispose()


def _path(parts: list[str]) -> str:
    return ".".join(parts) or "<root>"


def check_values(
    data: Any, source: str, parts: list[str] | None = None, *, model: Any = None
) -> None:
    """Refuse non-finite numbers, over-long integers and strings, and deep nesting.

    Args:
        data: Plain data: dicts, lists, tuples, scalars.
        source: The file (or ``<dict>``) named first in the message.
        parts: Key path of ``data`` (for recursion).
        model: A pydantic model class ``data`` is for: also :func:`check_numbers`.

    Raises:
        ConfigError: ``source: key.path: problem`` for the first bad value.
    """
    if model is not None:
        check_values(data, source)
        check_numbers(data, model, source)
        return
    parts = parts or []
    if len(parts) > MAX_DEPTH:
        raise ConfigError(f"{source}: {_path(parts[:3])}...: nested deeper than {MAX_DEPTH} levels")
    if isinstance(data, dict):
        if len(data) > MAX_EXPANDED:
            raise ConfigError(f"{source}: {_path(parts)}: more than {MAX_EXPANDED} values")
        for key, value in data.items():
            name = key if isinstance(key, str) else short_repr(key, 40)
            check_values(key, source, [*parts, f"<key {name[:40]}>"])
            check_values(value, source, [*parts, name[:60]])
    elif isinstance(data, list | tuple):
        if len(data) > MAX_EXPANDED:
            raise ConfigError(f"{source}: {_path(parts)}: more than {MAX_EXPANDED} values")
        for index, value in enumerate(data):
            check_values(value, source, [*parts, str(index)])
    elif isinstance(data, BadScalar):
        raise ConfigError(f"{source}: {_path(parts)}: {data.problem}")
    elif isinstance(data, bool):
        return
    elif isinstance(data, int):
        if not -INT_LIMIT <= data < INT_LIMIT:
            raise ConfigError(f"{source}: {_path(parts)}: integer out of the 64-bit range")
    elif isinstance(data, float):
        if not math.isfinite(data):
            raise ConfigError(f"{source}: {_path(parts)}: {data} is not a finite number")
    elif isinstance(data, str) and len(data) > MAX_STR_CHARS:
        raise ConfigError(
            f"{source}: {_path(parts)}: a string of {len(data)} characters is too long "
            f"(at most {MAX_STR_CHARS})"
        )


MAX_COUNT: Final = 1_000_000  # any integer setting but a seed (counts, sizes, iterations)


def check_numbers(data: Any, model: Any, source: str, parts: list[str] | None = None) -> None:
    """Refuse a boolean where ``model`` (a pydantic model class) expects a number, and an
    integer setting over :data:`MAX_COUNT` (seeds excepted): ``step_m: true`` would read
    as 1.0 m, and a count of 10**12 never finishes.

    Raises:
        ConfigError: ``source: key.path: problem``.
    """
    import typing

    fields = getattr(model, "model_fields", None)
    if fields is None or not isinstance(data, dict):
        return
    parts = parts or []
    for name, value in data.items():
        field = fields.get(name)
        if field is None:
            continue
        where = _path([*parts, str(name)])
        kinds = set(typing.get_args(field.annotation)) or {field.annotation}
        inner = {a for k in kinds for a in typing.get_args(k)} | kinds
        numeric = bool(inner & {int, float}) and bool not in inner
        values = value if isinstance(value, list | tuple) else [value]
        if numeric and any(isinstance(v, bool) for v in values):
            raise ConfigError(f"{source}: {where}: a number is expected, got a boolean")
        if not str(name).endswith("seed") and any(
            isinstance(v, int) and not isinstance(v, bool) and abs(v) > MAX_COUNT for v in values
        ):
            raise ConfigError(f"{source}: {where}: {short_repr(value, 40)} is over {MAX_COUNT}")
        sub = next((k for k in kinds if hasattr(k, "model_fields")), None)
        if sub is not None:
            check_numbers(value, sub, source, [*parts, str(name)])
