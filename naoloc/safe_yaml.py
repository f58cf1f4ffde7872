"""Bounded YAML loading and value checks for config files (no bombs, no recursion, no NaN).

:func:`load_yaml` reads at most :data:`MAX_CONFIG_BYTES` bytes and parses them with a
``yaml.SafeLoader`` that refuses, while composing, more than :data:`MAX_NODES` nodes and
nesting deeper than :data:`MAX_DEPTH`; before anything is constructed it counts what the
aliases expand to (a "billion laughs" file is a few hundred bytes that expand to 10**9
values) and refuses more than :data:`MAX_EXPANDED` values or a recursive alias. Integers
with more than :data:`MAX_INT_CHARS` characters are never converted (Python refuses more
than 4300 digits with a ValueError; a seed never needs more than 64 bits).

:func:`check_values` walks plain data (from YAML or a dict) and names the key path of the
first value that is not finite, too long or too deep. :func:`short_repr` never formats
more than a bounded part of a value, so an error message stays short and cheap.
"""

from __future__ import annotations

import math
import reprlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any, Final

import yaml

from naoloc.errors import ConfigError

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
        with path.open("rb") as stream:
            if not path.is_file():
                raise ConfigError(f"{path}: not a regular file")
            raw = stream.read(MAX_CONFIG_BYTES + 1)
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such config file") from None
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


def check_values(data: Any, source: str, parts: list[str] | None = None) -> None:
    """Refuse non-finite numbers, over-long integers and strings, and deep nesting.

    Args:
        data: Plain data: dicts, lists, tuples, scalars.
        source: The file (or ``<dict>``) named first in the message.
        parts: Key path of ``data`` (for recursion).

    Raises:
        ConfigError: ``source: key.path: problem`` for the first bad value.
    """
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
