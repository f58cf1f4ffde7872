"""The zmq transport's wire format: msgpack headers, raw frames for buffers, no pickle.

A message is a ZeroMQ multipart message ``[header, buffer_0, buffer_1, ...]``. The
header is a msgpack map; every ``bytes``-like value inside it is lifted out into its
own raw frame and replaced by the msgpack extension type :data:`EXT_BUFFER` holding
the frame's index as a big-endian uint32. Images therefore cross the wire as one raw
frame, without copies or escaping.

Headers (keys are single letters to keep them small):

* request: ``{"k": "hello" | "ping" | "call" | "bye", "i": id, "s": service,
  "m": method, "a": [args]}`` (``s``, ``m``, ``a`` only for ``call``).
* reply: ``{"k": "ok" | "err" | "pong" | "welcome", "i": id, "v": value,
  "e": [error type, message]}``.

:func:`decode` validates every size and type it reads and raises only
:class:`~naoloc.errors.ProtocolError`.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Any, Final

import msgpack
import numpy as np

from naoloc.errors import NaolocError, ProtocolError

PROTOCOL_VERSION: Final = 1
EXT_BUFFER: Final = 1
MAX_FRAMES: Final = 64
MAX_HEADER_BYTES: Final = 1 << 20
MAX_BUFFER_BYTES: Final = 64 << 20
MAX_DEPTH: Final = 32
MAX_ID: Final = (1 << 63) - 1
MAX_NAME_LEN: Final = 128
MAX_MESSAGE_BYTES: Final = 128 << 20
MAX_ITEMS: Final = 1 << 16
MAX_MAP_ITEMS: Final = 1 << 10
MAX_SERVICES: Final = 256
MAX_ERROR_CHARS: Final = 4096

REQUEST_KINDS: Final = frozenset({"hello", "ping", "call", "bye"})
REPLY_KINDS: Final = frozenset({"ok", "err", "pong", "welcome"})

Buffer = bytes | bytearray | memoryview


def _lift(value: Any, frames: list[Buffer], depth: int) -> Any:
    """Replace bytes-like leaves by buffer references, appending the buffers to ``frames``."""
    if depth > MAX_DEPTH:
        raise ProtocolError(f"value nested deeper than {MAX_DEPTH} levels")
    if value is None or isinstance(value, bool | int | float | str):
        return value
    if isinstance(value, bytes | bytearray | memoryview):
        frames.append(value)
        return msgpack.ExtType(EXT_BUFFER, struct.pack(">I", len(frames) - 1))
    if isinstance(value, list | tuple):
        return [_lift(v, frames, depth + 1) for v in value]
    if isinstance(value, dict):
        out = {}
        for key, item in value.items():
            if not isinstance(key, str):
                raise ProtocolError(f"map keys must be strings, got {type(key).__name__}")
            out[key] = _lift(item, frames, depth + 1)
        return out
    if isinstance(value, np.generic):
        return _lift(value.item(), frames, depth)
    if isinstance(value, np.ndarray):
        return _lift(value.tolist(), frames, depth)
    raise ProtocolError(f"cannot send a value of type {type(value).__name__}")


def encode(header: dict[str, Any]) -> list[Buffer]:
    """Encode a header map into multipart frames ``[msgpack header, *raw buffers]``.

    Raises:
        ProtocolError: For a value that has no wire form (e.g. an arbitrary object).
    """
    buffers: list[Buffer] = []
    lifted = _lift(header, buffers, 0)
    if len(buffers) > MAX_FRAMES - 1:
        raise ProtocolError(f"a message carries at most {MAX_FRAMES - 1} buffers")
    packed: bytes = msgpack.packb(lifted, use_bin_type=True)
    return [packed, *buffers]


def _check_value(value: Any, depth: int) -> None:
    if depth > MAX_DEPTH:
        raise ProtocolError(f"value nested deeper than {MAX_DEPTH} levels")
    if value is None or isinstance(value, bool | int | float | str | bytes):
        return
    if isinstance(value, list):
        for item in value:
            _check_value(item, depth + 1)
        return
    if isinstance(value, dict):
        for key, item in value.items():
            if not isinstance(key, str):
                raise ProtocolError("map keys must be strings")
            _check_value(item, depth + 1)
        return
    raise ProtocolError(f"undecodable value of type {type(value).__name__}")


def _frame_bytes(frame: Any) -> bytes:
    if isinstance(frame, bytes):
        return frame
    if isinstance(frame, bytearray | memoryview):
        return bytes(frame)
    raw = getattr(frame, "bytes", None)  # zmq.Frame
    if isinstance(raw, bytes):
        return raw
    raise ProtocolError(f"a frame must be bytes, got {type(frame).__name__}")


def _frame_len(frame: Any) -> int:
    """Byte length of a frame without copying it (so an oversized one is refused first)."""
    if isinstance(frame, bytes | bytearray):
        return len(frame)
    if isinstance(frame, memoryview):
        return frame.nbytes
    buffer = getattr(frame, "buffer", None)  # zmq.Frame
    if isinstance(buffer, memoryview):
        return buffer.nbytes
    raise ProtocolError(f"a frame must be bytes, got {type(frame).__name__}")


def _unpack(frames: Sequence[Any]) -> tuple[Any, list[bool]]:
    if not isinstance(frames, list | tuple):
        raise ProtocolError(f"a message is a list of frames, got {type(frames).__name__}")
    if not 1 <= len(frames) <= MAX_FRAMES:
        raise ProtocolError(f"a message has 1 to {MAX_FRAMES} frames, got {len(frames)}")
    sizes = [_frame_len(f) for f in frames]
    if sizes[0] > MAX_HEADER_BYTES:
        raise ProtocolError(f"header of {sizes[0]} bytes exceeds {MAX_HEADER_BYTES}")
    for size in sizes[1:]:
        if size > MAX_BUFFER_BYTES:
            raise ProtocolError(f"buffer of {size} bytes exceeds {MAX_BUFFER_BYTES}")
    if sum(sizes) > MAX_MESSAGE_BYTES:
        raise ProtocolError(f"message of {sum(sizes)} bytes exceeds {MAX_MESSAGE_BYTES}")
    head = _frame_bytes(frames[0])
    buffers = [_frame_bytes(f) for f in frames[1:]]
    used = [False] * len(buffers)

    def ext_hook(code: int, data: bytes) -> bytes:
        if code != EXT_BUFFER or len(data) != 4:
            raise ProtocolError(f"unknown msgpack extension {code} of {len(data)} bytes")
        (index,) = struct.unpack(">I", data)
        if index >= len(buffers) or used[index]:
            raise ProtocolError(f"bad buffer reference {index}")
        used[index] = True
        return buffers[index]

    try:
        # Every declared length is capped by the header's own size: a 5-byte header that
        # claims a 4 GB string or 2**32 items is refused before anything is allocated.
        value = msgpack.unpackb(
            head,
            raw=False,
            use_list=True,
            strict_map_key=True,
            ext_hook=ext_hook,
            max_str_len=len(head),
            max_bin_len=len(head),
            max_array_len=min(len(head), MAX_ITEMS),
            max_map_len=min(len(head), MAX_MAP_ITEMS),
            max_ext_len=4,
        )
    except NaolocError:
        raise
    except RecursionError:
        raise ProtocolError(f"value nested deeper than {MAX_DEPTH} levels") from None
    except Exception as err:  # msgpack raises many types: all mean bad bytes
        raise ProtocolError(f"undecodable header: {type(err).__name__}") from None
    return value, used


def _check_id(header: dict[str, Any]) -> None:
    ident = header.get("i")
    if not isinstance(ident, int) or isinstance(ident, bool) or not 0 <= ident <= MAX_ID:
        raise ProtocolError("message id must be an integer in [0, 2**63)")


def _check_name(header: dict[str, Any], key: str, what: str) -> None:
    name = header.get(key)
    if not isinstance(name, str) or not 0 < len(name) <= MAX_NAME_LEN:
        raise ProtocolError(f"{what} must be a non-empty string of at most {MAX_NAME_LEN} chars")


def _decode(frames: Sequence[Any], kinds: frozenset[str]) -> dict[str, Any]:
    header, used = _unpack(frames)
    if not isinstance(header, dict):
        raise ProtocolError(f"header must be a map, got {type(header).__name__}")
    if not all(used):
        raise ProtocolError("a buffer frame is not referenced by the header")
    kind = header.get("k")
    if not isinstance(kind, str) or kind not in kinds:
        shown = kind if isinstance(kind, str) and len(kind) <= MAX_NAME_LEN else None
        what = repr(shown) if shown is not None else f"of type {type(kind).__name__}"
        raise ProtocolError(f"unknown message kind {what}")
    _check_id(header)
    _check_value(header, 0)
    return header


def peek_id(frames: Sequence[Any]) -> int | None:
    """The id of a message that failed to decode, when one can be read; never raises.

    Lets a server answer a malformed request with an error reply instead of silence.
    """
    try:
        header, _ = _unpack(frames)
    except ProtocolError:
        return None
    if not isinstance(header, dict):
        return None
    try:
        _check_id(header)
    except ProtocolError:
        return None
    ident: int = header["i"]
    return ident


def decode_request(frames: Sequence[Any]) -> dict[str, Any]:
    """Decode and validate a client request.

    Returns:
        The header map; ``call`` requests carry ``s`` (service), ``m`` (method) and
        ``a`` (argument list); buffers are ``bytes``.

    Raises:
        ProtocolError: For anything but a well-formed request.
    """
    header = _decode(frames, REQUEST_KINDS)
    allowed = {"k", "i", "s", "m", "a"} if header["k"] == "call" else {"k", "i"}
    extra = set(header) - allowed
    if extra:
        raise ProtocolError(f"unexpected keys {sorted(extra)} in a {header['k']} request")
    if header["k"] == "call":
        _check_name(header, "s", "service name")
        _check_name(header, "m", "method name")
        if not isinstance(header.get("a"), list):
            raise ProtocolError("call arguments must be a list")
    return header


def decode_reply(frames: Sequence[Any]) -> dict[str, Any]:
    """Decode and validate a server reply.

    Returns:
        The header map: ``v`` the value (``ok``, ``welcome``) or ``e`` = [type, message]
        (``err``).

    Raises:
        ProtocolError: For anything but a well-formed reply.
    """
    header = _decode(frames, REPLY_KINDS)
    extra = set(header) - {"k", "i", "v", "e"}
    if extra:
        raise ProtocolError(f"unexpected keys {sorted(extra)} in a reply")
    if header["k"] == "err":
        err = header.get("e")
        if (
            not isinstance(err, list)
            or len(err) != 2
            or not all(isinstance(e, str) and len(e) <= MAX_ERROR_CHARS for e in err)
        ):
            raise ProtocolError("an error reply needs e = [type, message]")
    elif header["k"] == "welcome":
        value = header.get("v")
        if not isinstance(value, dict):
            raise ProtocolError("a welcome reply needs a map value")
        names = value.get("services")
        if (
            not isinstance(names, list)
            or len(names) > MAX_SERVICES
            or not all(isinstance(n, str) and 0 < len(n) <= MAX_NAME_LEN for n in names)
        ):
            raise ProtocolError("a welcome reply needs services = [name, ...]")
    return header
