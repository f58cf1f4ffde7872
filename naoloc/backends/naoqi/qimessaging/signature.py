"""The libqi signature grammar: parse, print, and infer signatures.

Letters: ``b`` bool, ``c``/``C`` int8/uint8, ``w``/``W`` int16/uint16, ``i``/``I``
int32/uint32, ``l``/``L`` int64/uint64, ``f`` float32, ``d`` float64, ``s`` string,
``r`` raw bytes, ``m`` dynamic value, ``o`` object, ``v`` void, ``X`` unknown;
``[x]`` list, ``{kv}`` map, ``(...)`` tuple, ``(...)<Name,field,...>`` struct,
``+x`` optional, ``#x`` variadic arguments (a list on the wire).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, Final

from naoloc.errors import ProtocolError

MAX_SIGNATURE: Final = 4096  # characters
MAX_DEPTH: Final = 32  # nesting of lists, maps, tuples and dynamic values

# Wire sizes of the fixed-size letters (bytes).
FIXED_SIZE: Final = {
    "b": 1, "c": 1, "C": 1, "w": 2, "W": 2, "i": 4, "I": 4,
    "l": 8, "L": 8, "f": 4, "d": 8,
}  # fmt: skip
SCALARS: Final = frozenset(FIXED_SIZE) | frozenset("srmovX")


@dataclass(frozen=True)
class Sig:
    """A parsed signature.

    Attributes:
        kind: The letter (``[``, ``{``, ``(``, ``+``, ``#`` for composites).
        items: Element types: one for lists/optionals, key and value for maps, the
            members of a tuple.
        name: Struct name (from the ``<...>`` annotation), or "".
        fields: Struct field names, or ().
    """

    kind: str
    items: tuple[Sig, ...] = ()
    name: str = ""
    fields: tuple[str, ...] = ()

    def __str__(self) -> str:
        return to_string(self)

    @functools.cached_property
    def min_size(self) -> int:
        """Fewest wire bytes a value of this type takes."""
        if self.kind in FIXED_SIZE:
            return FIXED_SIZE[self.kind]
        if self.kind in "sr[{#":
            return 4
        if self.kind == "m":
            return 4
        if self.kind == "+":
            return 1
        if self.kind == "(":
            return sum(item.min_size for item in self.items)
        return 0


def to_string(sig: Sig) -> str:
    """The signature text of ``sig``."""
    kind = sig.kind
    if kind in SCALARS:
        return kind
    if kind == "[":
        return f"[{to_string(sig.items[0])}]"
    if kind == "{":
        return "{" + to_string(sig.items[0]) + to_string(sig.items[1]) + "}"
    if kind in "+#":
        return kind + to_string(sig.items[0])
    inner = "(" + "".join(to_string(s) for s in sig.items) + ")"
    if sig.name:
        inner += "<" + ",".join((sig.name, *sig.fields)) + ">"
    return inner


@functools.lru_cache(maxsize=1024)
def parse(text: str) -> Sig:
    """Parse one complete signature.

    Raises:
        ProtocolError: Malformed, too long or too deeply nested.
    """
    if len(text) > MAX_SIGNATURE:
        raise ProtocolError(f"signature of {len(text)} characters is over {MAX_SIGNATURE}")
    if not text:
        raise ProtocolError("empty signature")
    sig, end = _parse(text, 0, 0)
    if end != len(text):
        raise ProtocolError(f"trailing characters in signature {text[:60]!r}")
    return sig


def _parse(text: str, pos: int, depth: int) -> tuple[Sig, int]:
    if depth > MAX_DEPTH:
        raise ProtocolError(f"signature nested deeper than {MAX_DEPTH}")
    if pos >= len(text):
        raise ProtocolError(f"truncated signature {text[:60]!r}")
    ch = text[pos]
    if ch in SCALARS:
        return Sig(ch), pos + 1
    if ch in "+#":
        item, pos = _parse(text, pos + 1, depth + 1)
        return Sig(ch, (item,)), pos
    if ch == "[":
        item, pos = _parse(text, pos + 1, depth + 1)
        _expect(text, pos, "]")
        return Sig("[", (item,)), pos + 1
    if ch == "{":
        key, pos = _parse(text, pos + 1, depth + 1)
        value, pos = _parse(text, pos, depth + 1)
        _expect(text, pos, "}")
        return Sig("{", (key, value)), pos + 1
    if ch == "(":
        items: list[Sig] = []
        pos += 1
        while pos < len(text) and text[pos] != ")":
            item, pos = _parse(text, pos, depth + 1)
            items.append(item)
        _expect(text, pos, ")")
        pos += 1
        name: str = ""
        fields: tuple[str, ...] = ()
        if pos < len(text) and text[pos] == "<":
            end = text.find(">", pos)
            if end < 0:
                raise ProtocolError(f"unclosed struct annotation in {text[:60]!r}")
            names = text[pos + 1 : end].split(",")
            name, fields = names[0], tuple(names[1:])
            pos = end + 1
        return Sig("(", tuple(items), name, fields), pos
    raise ProtocolError(f"unknown signature character {ch!r} in {text[:60]!r}")


def _expect(text: str, pos: int, ch: str) -> None:
    if pos >= len(text) or text[pos] != ch:
        raise ProtocolError(f"expected {ch!r} at {pos} in signature {text[:60]!r}")


VOID: Final = Sig("v")
DYNAMIC: Final = Sig("m")
STRING: Final = Sig("s")


def infer(value: Any, depth: int = 0) -> Sig:
    """The signature libqi's Python binding gives a value sent untyped (dynamic).

    bool ``b``, int ``l``, float ``d``, str ``s``, bytes-like ``r``, None ``v``,
    list ``[m]``, tuple ``(m...)``, dict ``{mm}``; numpy scalars and arrays as their
    Python equivalents.

    Raises:
        ProtocolError: A value of another type.
    """
    if depth > MAX_DEPTH:
        raise ProtocolError(f"value nested deeper than {MAX_DEPTH}")
    if isinstance(value, bool):
        return Sig("b")
    if isinstance(value, int):
        return Sig("l")
    if isinstance(value, float):
        return Sig("d")
    if isinstance(value, str):
        return STRING
    if isinstance(value, bytes | bytearray | memoryview):
        return Sig("r")
    if value is None:
        return VOID
    if isinstance(value, list):
        return Sig("[", (DYNAMIC,))
    if isinstance(value, tuple):
        return Sig("(", tuple(DYNAMIC for _ in value))
    if isinstance(value, dict):
        return Sig("{", (DYNAMIC, DYNAMIC))
    tolist = getattr(value, "tolist", None)  # numpy scalars and arrays
    if callable(tolist):
        return infer(tolist(), depth + 1)
    raise ProtocolError(f"cannot send a value of type {type(value).__name__}")
