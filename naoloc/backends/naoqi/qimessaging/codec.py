"""The qi binary format: encode and decode values of a signature.

Everything is little-endian. Integers and floats at their width, bool one byte,
strings and raw buffers as a u32 length then the bytes, lists and maps as a u32 count
then the elements (key, value pairs), tuples and structs as their members in order,
optionals as a bool then the value when present, dynamic values as their signature
(a string) then the value, objects as a MetaObject, service and object ids and (with
the ObjectPtrUID capability) a 20-byte uid.

Decoding trusts nothing: every count is checked against the bytes that remain, nesting
is limited, and truncated input raises :class:`~naoloc.errors.ProtocolError`. Raw
buffers decode as zero-copy ``memoryview`` slices of the received payload; large raw
buffers are encoded as separate parts (no copy) for a scatter send.
"""

from __future__ import annotations

import functools
import struct
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final

from naoloc.backends.naoqi.qimessaging.signature import (
    FIXED_SIZE,
    MAX_DEPTH,
    Sig,
    infer,
    parse,
)
from naoloc.errors import ProtocolError

MAX_ZERO_SIZE_ITEMS: Final = 1 << 16  # elements of a type that takes no bytes (e.g. "()")
_BIG_RAW: Final = 32 * 1024  # raw buffers at least this big are sent without a copy

_FORMAT: Final = {
    "b": "?", "c": "b", "C": "B", "w": "h", "W": "H", "i": "i", "I": "I",
    "l": "q", "L": "Q", "f": "f", "d": "d",
}  # fmt: skip
_U32 = struct.Struct("<I")

METAOBJECT_SIGNATURE: Final = (
    "({I(Issss[(ss)<MetaMethodParameter,name,description>]s)<MetaMethod,uid,returnSignature,"
    "name,parametersSignature,description,parameters,returnDescription>}"
    "{I(Iss)<MetaSignal,uid,name,signature>}{I(Iss)<MetaProperty,uid,name,signature>}s)"
    "<MetaObject,methods,signals,properties,description>"
)
UID_SIZE: Final = 20


@dataclass(frozen=True)
class ObjectRef:
    """An object on the wire (signature ``o``): its description and address.

    Attributes:
        meta: The decoded MetaObject tuple (methods, signals, properties, description).
        service: Service id that hosts it.
        object: Its object id within the service.
        uid: 20-byte object uid ("" when the peer did not send one).
    """

    meta: tuple[Any, ...]
    service: int
    object: int
    uid: bytes = b""


class Writer:
    """An output buffer that keeps large raw buffers as separate, uncopied parts."""

    __slots__ = ("buf", "parts", "size")

    def __init__(self) -> None:
        self.buf = bytearray()
        self.parts: list[bytes | bytearray | memoryview] = []
        self.size = 0

    def raw(self, data: bytes | bytearray | memoryview) -> None:
        """Append a buffer; big ones are referenced, not copied."""
        if len(data) >= _BIG_RAW:
            if self.buf:
                self.parts.append(self.buf)
                self.size += len(self.buf)
                self.buf = bytearray()
            self.parts.append(data)
            self.size += len(data)
        else:
            self.buf += data

    def finish(self) -> tuple[list[bytes | bytearray | memoryview], int]:
        """The parts in order and their total size."""
        if self.buf:
            self.parts.append(self.buf)
            self.size += len(self.buf)
            self.buf = bytearray()
        return self.parts, self.size

    def getvalue(self) -> bytes:
        """Everything as one bytes object (copies)."""
        parts, _ = self.finish()
        return b"".join(parts)


Encoder = Callable[[Any, Writer, int, bool], None]
Decoder = Callable[[memoryview, int, int, bool], tuple[Any, int]]


def _depth(depth: int) -> int:
    if depth > 2 * MAX_DEPTH:
        raise ProtocolError(f"value nested deeper than {2 * MAX_DEPTH}")
    return depth + 1


# ---------------------------------------------------------------------------- encoding
@functools.lru_cache(maxsize=1024)
def encoder(sig: Sig) -> Encoder:
    """A function ``(value, writer, depth, object_uid)`` writing values of ``sig``."""
    kind = sig.kind
    if kind in _FORMAT:
        packer = struct.Struct("<" + _FORMAT[kind])
        integer = kind not in "bfd"
        boolean = kind == "b"

        def enc_fixed(value: Any, w: Writer, depth: int, uid: bool) -> None:
            if boolean and not isinstance(value, bool | int):
                raise ProtocolError(f"expected a bool, got {type(value).__name__}")
            if integer and not isinstance(value, int):
                if isinstance(value, float) and value.is_integer():
                    value = int(value)
                else:
                    value = _index(value, kind)
            try:
                w.buf += packer.pack(value)
            except struct.error as err:
                raise ProtocolError(f"cannot encode {value!r} as {kind!r}: {err}") from None

        return enc_fixed
    if kind == "s":
        return _enc_string
    if kind == "r":
        return _enc_raw
    if kind in "vX":
        return _enc_void
    if kind == "m":
        return _enc_dynamic
    if kind == "o":
        return _enc_object
    if kind in "[#":
        return _list_encoder(sig.items[0])
    if kind == "{":
        key, val = encoder(sig.items[0]), encoder(sig.items[1])

        def enc_map(value: Any, w: Writer, depth: int, uid: bool) -> None:
            if not isinstance(value, dict):
                raise ProtocolError(f"expected a dict for {sig}, got {type(value).__name__}")
            depth = _depth(depth)
            w.buf += _U32.pack(len(value))
            for k, v in value.items():
                key(k, w, depth, uid)
                val(v, w, depth, uid)

        return enc_map
    if kind == "+":
        inner = encoder(sig.items[0])

        def enc_optional(value: Any, w: Writer, depth: int, uid: bool) -> None:
            w.buf.append(0 if value is None else 1)
            if value is not None:
                inner(value, w, _depth(depth), uid)

        return enc_optional
    members = [encoder(s) for s in sig.items]
    fields = sig.fields

    def enc_tuple(value: Any, w: Writer, depth: int, uid: bool) -> None:
        if isinstance(value, dict) and fields:
            value = [value[f] for f in fields]
        if not isinstance(value, list | tuple) or len(value) != len(members):
            raise ProtocolError(f"expected {len(members)} values for {sig}, got {value!r:.80}")
        depth = _depth(depth)
        for enc, v in zip(members, value, strict=True):
            enc(v, w, depth, uid)

    return enc_tuple


def _index(value: Any, kind: str) -> int:
    try:
        return int(value.__index__())
    except (AttributeError, TypeError):
        raise ProtocolError(f"cannot encode {value!r:.60} as {kind!r}") from None


def _list_encoder(item_sig: Sig) -> Encoder:
    if item_sig.kind in _FORMAT:
        code = _FORMAT[item_sig.kind]

        def enc_scalar_list(value: Any, w: Writer, depth: int, uid: bool) -> None:
            if not isinstance(value, list | tuple):
                value = _as_list(value)
            try:
                w.buf += struct.pack(f"<I{len(value)}{code}", len(value), *value)
            except struct.error:
                item = encoder(item_sig)
                w.buf += _U32.pack(len(value))
                for v in value:
                    item(v, w, depth, uid)

        return enc_scalar_list
    item = encoder(item_sig)

    def enc_list(value: Any, w: Writer, depth: int, uid: bool) -> None:
        if not isinstance(value, list | tuple):
            value = _as_list(value)
        depth = _depth(depth)
        w.buf += _U32.pack(len(value))
        for v in value:
            item(v, w, depth, uid)

    return enc_list


def _as_list(value: Any) -> list[Any]:
    tolist = getattr(value, "tolist", None)
    if callable(tolist):
        result = tolist()
        if isinstance(result, list):
            return result
    raise ProtocolError(f"expected a list, got {type(value).__name__}")


def _enc_string(value: Any, w: Writer, depth: int, uid: bool) -> None:
    if isinstance(value, str):
        data = value.encode("utf-8", "surrogateescape")
    elif isinstance(value, bytes | bytearray | memoryview):
        data = bytes(value)
    else:
        raise ProtocolError(f"expected a string, got {type(value).__name__}")
    w.buf += _U32.pack(len(data))
    w.buf += data


def _enc_raw(value: Any, w: Writer, depth: int, uid: bool) -> None:
    if isinstance(value, str):
        value = value.encode("utf-8")
    elif not isinstance(value, bytes | bytearray | memoryview):
        try:
            value = memoryview(value)  # numpy arrays and other buffers, without a copy
        except TypeError:
            raise ProtocolError(f"expected bytes, got {type(value).__name__}") from None
    if isinstance(value, memoryview) and (value.ndim != 1 or value.itemsize != 1):
        value = value.cast("B") if value.c_contiguous else memoryview(value.tobytes())
    w.buf += _U32.pack(len(value))
    w.raw(value)


def _enc_void(value: Any, w: Writer, depth: int, uid: bool) -> None:
    return None


def _enc_dynamic(value: Any, w: Writer, depth: int, uid: bool) -> None:
    if isinstance(value, Dynamic):
        sig, value = value.sig, value.value
    elif isinstance(value, ObjectRef):
        sig = parse("o")
    else:
        if not isinstance(value, bool | int | float | str | list | tuple | dict | bytes):
            tolist = getattr(value, "tolist", None)
            if callable(tolist) and not isinstance(value, bytearray | memoryview):
                value = tolist()
        sig = infer(value)
    _enc_string(str(sig), w, depth, uid)
    encoder(sig)(value, w, _depth(depth), uid)


def _enc_object(value: Any, w: Writer, depth: int, uid: bool) -> None:
    if not isinstance(value, ObjectRef):
        raise ProtocolError(f"expected an object reference, got {type(value).__name__}")
    encoder(parse(METAOBJECT_SIGNATURE))(value.meta, w, depth, uid)
    w.buf += struct.pack("<II", value.service, value.object)
    if uid:
        w.buf += value.uid.ljust(UID_SIZE, b"\0")[:UID_SIZE]


@dataclass(frozen=True)
class Dynamic:
    """A value sent as a dynamic (``m``) with an explicit signature instead of an inferred one."""

    sig: Sig
    value: Any


def encode(sig: Sig | str, value: Any, *, object_uid: bool = True) -> Writer:
    """Encode ``value`` as ``sig``; returns the :class:`Writer` holding the parts.

    Raises:
        ProtocolError: The value does not fit the signature.
    """
    parsed = parse(sig) if isinstance(sig, str) else sig
    w = Writer()
    encoder(parsed)(value, w, 0, object_uid)
    return w


def encode_bytes(sig: Sig | str, value: Any, *, object_uid: bool = True) -> bytes:
    """Encode ``value`` as ``sig`` into one bytes object."""
    return encode(sig, value, object_uid=object_uid).getvalue()


# ---------------------------------------------------------------------------- decoding
@functools.lru_cache(maxsize=1024)
def decoder(sig: Sig) -> Decoder:
    """A function ``(buffer, position, depth, object_uid) -> (value, new position)``."""
    kind = sig.kind
    if kind in _FORMAT:
        unpacker = struct.Struct("<" + _FORMAT[kind])
        size = unpacker.size

        def dec_fixed(buf: memoryview, pos: int, depth: int, uid: bool) -> tuple[Any, int]:
            return unpacker.unpack_from(buf, pos)[0], pos + size

        return dec_fixed
    if kind == "s":
        return _dec_string
    if kind == "r":
        return _dec_raw
    if kind in "vX":
        return _dec_void
    if kind == "m":
        return _dec_dynamic
    if kind == "o":
        return _dec_object
    if kind in "[#":
        return _list_decoder(sig.items[0])
    if kind == "{":
        key, val = decoder(sig.items[0]), decoder(sig.items[1])
        pair_size = max(1, sig.items[0].min_size + sig.items[1].min_size)

        def dec_map(buf: memoryview, pos: int, depth: int, uid: bool) -> tuple[Any, int]:
            count, pos = _count(buf, pos, pair_size, sig)
            depth = _depth(depth)
            out: dict[Any, Any] = {}
            for _ in range(count):
                k, pos = key(buf, pos, depth, uid)
                v, pos = val(buf, pos, depth, uid)
                out[_hashable(k)] = v
            return out, pos

        return dec_map
    if kind == "+":
        inner = decoder(sig.items[0])

        def dec_optional(buf: memoryview, pos: int, depth: int, uid: bool) -> tuple[Any, int]:
            if pos >= len(buf):
                raise ProtocolError("truncated optional value")
            if not buf[pos]:
                return None, pos + 1
            return inner(buf, pos + 1, _depth(depth), uid)

        return dec_optional
    fields = sig.fields if sig.fields and len(sig.fields) == len(sig.items) else ()
    if sig.items and all(s.kind in _FORMAT for s in sig.items):
        packed = struct.Struct("<" + "".join(_FORMAT[s.kind] for s in sig.items))

        def dec_flat(buf: memoryview, pos: int, depth: int, uid: bool) -> tuple[Any, int]:
            values = packed.unpack_from(buf, pos)
            return (NamedStruct(values, fields) if fields else values), pos + packed.size

        return dec_flat
    members = [decoder(s) for s in sig.items]

    def dec_tuple(buf: memoryview, pos: int, depth: int, uid: bool) -> tuple[Any, int]:
        depth = _depth(depth)
        out = []
        for dec in members:
            v, pos = dec(buf, pos, depth, uid)
            out.append(v)
        return (NamedStruct(out, fields) if fields else tuple(out)), pos

    return dec_tuple


class NamedStruct(tuple[Any, ...]):
    """A decoded struct whose signature names its fields (``(ss)<Name,a,b>``): a tuple
    that also knows ``fields`` (qi's Python binding gives such structs as dicts)."""

    fields: tuple[str, ...]

    def __new__(cls, values: Any, fields: tuple[str, ...]) -> NamedStruct:
        made = super().__new__(cls, values)
        made.fields = fields
        return made

    def as_dict(self) -> dict[str, Any]:
        """``{field: value}``."""
        return dict(zip(self.fields, self, strict=True))


def _hashable(key: Any) -> Any:
    if isinstance(key, list):
        return tuple(_hashable(k) for k in key)
    if isinstance(key, memoryview):
        return key.tobytes()
    if isinstance(key, dict):
        raise ProtocolError("a map key cannot be a map")
    return key


def _count(buf: memoryview, pos: int, item_size: int, sig: Sig) -> tuple[int, int]:
    (count,) = _U32.unpack_from(buf, pos)
    pos += 4
    limit = (len(buf) - pos) // item_size if item_size else MAX_ZERO_SIZE_ITEMS
    if count > limit:
        raise ProtocolError(f"{sig} claims {count} elements, more than the payload holds")
    return count, pos


def _list_decoder(item_sig: Sig) -> Decoder:
    if item_sig.kind in _FORMAT:
        code, size = _FORMAT[item_sig.kind], FIXED_SIZE[item_sig.kind]

        def dec_scalar_list(buf: memoryview, pos: int, depth: int, uid: bool) -> tuple[Any, int]:
            count, pos = _count(buf, pos, size, item_sig)
            values = list(struct.unpack_from(f"<{count}{code}", buf, pos))
            return values, pos + count * size

        return dec_scalar_list
    item = decoder(item_sig)
    size = item_sig.min_size
    list_sig = Sig("[", (item_sig,))

    def dec_list(buf: memoryview, pos: int, depth: int, uid: bool) -> tuple[Any, int]:
        count, pos = _count(buf, pos, size, list_sig)
        depth = _depth(depth)
        out = []
        for _ in range(count):
            v, pos = item(buf, pos, depth, uid)
            out.append(v)
        return out, pos

    return dec_list


def _dec_bytes(buf: memoryview, pos: int) -> tuple[memoryview, int]:
    (size,) = _U32.unpack_from(buf, pos)
    pos += 4
    if size > len(buf) - pos:
        raise ProtocolError(f"a string or buffer of {size} bytes overruns the payload")
    return buf[pos : pos + size], pos + size


def _dec_string(buf: memoryview, pos: int, depth: int, uid: bool) -> tuple[Any, int]:
    data, pos = _dec_bytes(buf, pos)
    raw = bytes(data)
    try:
        return raw.decode("utf-8"), pos
    except UnicodeDecodeError:
        return raw, pos  # NAOqi may put binary in strings


def _dec_raw(buf: memoryview, pos: int, depth: int, uid: bool) -> tuple[Any, int]:
    return _dec_bytes(buf, pos)


def _dec_void(buf: memoryview, pos: int, depth: int, uid: bool) -> tuple[Any, int]:
    return None, pos


def _dec_dynamic(buf: memoryview, pos: int, depth: int, uid: bool) -> tuple[Any, int]:
    text, pos = _dec_bytes(buf, pos)
    try:
        sig = parse(bytes(text).decode("ascii"))
    except UnicodeDecodeError:
        raise ProtocolError("a dynamic value's signature is not ASCII") from None
    return decoder(sig)(buf, pos, _depth(depth), uid)


def _dec_object(buf: memoryview, pos: int, depth: int, uid: bool) -> tuple[Any, int]:
    meta, pos = decoder(parse(METAOBJECT_SIGNATURE))(buf, pos, _depth(depth), uid)
    service, obj = struct.unpack_from("<II", buf, pos)
    pos += 8
    object_uid = b""
    if uid:
        if len(buf) - pos < UID_SIZE:
            raise ProtocolError("truncated object uid")
        object_uid = bytes(buf[pos : pos + UID_SIZE])
        pos += UID_SIZE
    return ObjectRef(meta, service, obj, object_uid), pos


def decode(
    sig: Sig | str,
    data: bytes | bytearray | memoryview,
    *,
    object_uid: bool = True,
    exact: bool = True,
) -> Any:
    """Decode one value of ``sig`` from ``data``.

    Args:
        sig: The signature (parsed or text).
        data: The payload.
        object_uid: Objects carry a 20-byte uid (the ObjectPtrUID capability).
        exact: Reject bytes left over after the value.

    Raises:
        ProtocolError: Truncated, oversized, malformed or (``exact``) trailing data.
    """
    parsed = parse(sig) if isinstance(sig, str) else sig
    buf = data if isinstance(data, memoryview) else memoryview(data)
    try:
        value, end = decoder(parsed)(buf, 0, 0, object_uid)
    except struct.error:
        raise ProtocolError(f"truncated payload for signature {str(parsed)[:60]}") from None
    except RecursionError:
        raise ProtocolError("value nested too deeply") from None
    if exact and end != len(buf):
        raise ProtocolError(f"{len(buf) - end} unexpected bytes after a {str(parsed)[:60]} value")
    return value
