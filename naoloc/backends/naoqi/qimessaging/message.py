"""The 28-byte QiMessaging header and the message kinds.

Layout (libqi's network binary protocol, version 0): magic ``0x42dead42`` big-endian,
then little-endian ``id`` (u32), payload ``size`` (u32), ``version`` (u16), ``type``
(u8), ``flags`` (u8), ``service``, ``object`` and ``action`` (u32 each). The payload
follows, ``size`` bytes in the binary format of :mod:`.codec`.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Final

from naoloc.errors import ProtocolError

MAGIC: Final = 0x42DEAD42
MAGIC_BYTES: Final = MAGIC.to_bytes(4, "big")
HEADER_SIZE: Final = 28
VERSION: Final = 0
MAX_PAYLOAD: Final = 50 * 1024 * 1024  # libqi's default limit, bytes

# Message types.
CALL: Final = 1
REPLY: Final = 2
ERROR: Final = 3
POST: Final = 4
EVENT: Final = 5
CAPABILITY: Final = 6
CANCEL: Final = 7
CANCELLED: Final = 8
TYPE_NAMES: Final = {
    CALL: "call",
    REPLY: "reply",
    ERROR: "error",
    POST: "post",
    EVENT: "event",
    CAPABILITY: "capability",
    CANCEL: "cancel",
    CANCELLED: "cancelled",
}

# Flags.
FLAG_DYNAMIC_PAYLOAD: Final = 0x1  # the payload is a dynamic value, not the declared type
FLAG_RETURN_TYPE: Final = 0x2  # a call payload ends with the wanted return signature
KNOWN_FLAGS: Final = FLAG_DYNAMIC_PAYLOAD | FLAG_RETURN_TYPE

# Well-known addresses.
SERVICE_SERVER: Final = 0  # authentication (object 0, action 8)
SERVICE_DIRECTORY: Final = 1
MAIN_OBJECT: Final = 1
ACTION_AUTHENTICATE: Final = 8

_REST = struct.Struct("<IIHBBIII")


@dataclass(frozen=True, slots=True)
class Header:
    """A decoded header.

    Attributes:
        id: Message id (a reply carries its call's id).
        size: Payload size, bytes.
        type: One of CALL ... CANCELLED.
        flags: FLAG_* bits.
        service: Service id (0 = authentication, 1 = service directory).
        object: Object id inside the service (1 = the service itself).
        action: Method, signal or property id.
    """

    id: int
    size: int
    type: int
    flags: int
    service: int
    object: int
    action: int


def pack_header(
    mid: int, size: int, mtype: int, flags: int, service: int, obj: int, action: int
) -> bytes:
    """The 28 header bytes of one message.

    Raises:
        ProtocolError: A field out of its range or a payload over :data:`MAX_PAYLOAD`.
    """
    if size > MAX_PAYLOAD:
        raise ProtocolError(f"payload of {size} bytes is over the {MAX_PAYLOAD} byte limit")
    try:
        return MAGIC_BYTES + _REST.pack(mid, size, VERSION, mtype, flags, service, obj, action)
    except struct.error as err:
        raise ProtocolError(f"bad message header field: {err}") from None


def unpack_header(data: bytes | bytearray | memoryview, max_payload: int = MAX_PAYLOAD) -> Header:
    """Decode and validate 28 header bytes.

    Raises:
        ProtocolError: Wrong magic, version, type or flags, or a payload over ``max_payload``.
    """
    if len(data) < HEADER_SIZE:
        raise ProtocolError(f"truncated message header ({len(data)} of {HEADER_SIZE} bytes)")
    if bytes(data[:4]) != MAGIC_BYTES:
        raise ProtocolError(f"bad magic {bytes(data[:4]).hex()} (not a QiMessaging peer)")
    mid, size, version, mtype, flags, service, obj, action = _REST.unpack_from(data, 4)
    if version != VERSION:
        raise ProtocolError(f"unsupported protocol version {version}")
    if mtype not in TYPE_NAMES:
        raise ProtocolError(f"unknown message type {mtype}")
    if flags & ~KNOWN_FLAGS:
        raise ProtocolError(f"unknown message flags {flags:#x}")
    if size > max_payload:
        raise ProtocolError(f"payload of {size} bytes is over the {max_payload} byte limit")
    return Header(mid, size, mtype, flags, service, obj, action)
