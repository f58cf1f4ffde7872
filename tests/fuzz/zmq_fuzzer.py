"""A bounded, seeded random fuzzer for the zmq virtual NAOqi (``naoloc serve --transport zmq``).

Sends garbage, truncated, mutated and type-confused messages from a raw DEALER socket,
reads every reply it gets, and reports what it sent. Used by ``tests/test_fuzz_zmq.py``
and ``tools/bench_fuzz.py``.
"""

from __future__ import annotations

import random
import struct
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import msgpack
import zmq

from naoloc.backends.naoqi import wire

SERVICES = ["ALMotion", "ALVideoDevice", "ALRobotPosture", "NaolocWatchdog", "NaolocSim", "X"]
METHODS = [
    "getRobotPosition", "moveTo", "setAngles", "subscribeCamera", "getImageRemote",
    "unsubscribe", "stopMove", "ping", "true_pose", "__init__", "_private", "x" * 200,
]  # fmt: skip
KINDS: list[Any] = ["hello", "ping", "call", "bye", "ok", "err", [], {}, {"a": 1}, 3, None, b"k"]


def _value(rng: random.Random, depth: int = 0) -> Any:
    """A random msgpack-able value (no ext types)."""
    pick = rng.randrange(10 if depth < 4 else 6)
    if pick == 0:
        return None
    if pick == 1:
        return rng.random() < 0.5
    if pick == 2:
        return rng.choice([0, -1, 1, 2**31, -(2**63), 2**64 - 1, rng.randrange(-1000, 1000)])
    if pick == 3:
        return rng.choice([0.0, -0.0, 1e308, float("nan"), float("inf"), rng.uniform(-10, 10)])
    if pick == 4:
        return "".join(chr(rng.randrange(32, 0x2FF)) for _ in range(rng.randrange(12)))
    if pick == 5:
        return rng.randbytes(rng.randrange(16))
    if pick in (6, 7):
        return [_value(rng, depth + 1) for _ in range(rng.randrange(5))]
    return {
        str(_value(rng, depth + 1))[:8]: _value(rng, depth + 1) for _ in range(rng.randrange(4))
    }


def _header(rng: random.Random) -> dict[Any, Any]:
    header: dict[Any, Any] = {
        "k": rng.choice(KINDS),
        "i": rng.choice([rng.randrange(1 << 20), -5, "1", 1.5, [1], None, 2**64 - 1]),
    }
    if rng.random() < 0.7:
        header["s"] = rng.choice([*SERVICES, 5, [], ""])
        header["m"] = rng.choice([*METHODS, None, {}])
        header["a"] = rng.choice([[_value(rng) for _ in range(rng.randrange(5))], "x", 7])
    for key in rng.sample(["v", "e", "x", "k", "i"], rng.randrange(2)):
        header[key] = _value(rng)
    return header


def _garbage(rng: random.Random) -> list[bytes]:
    return [rng.randbytes(rng.randrange(64)) for _ in range(rng.randrange(1, 4))]


def _type_confused(rng: random.Random) -> list[bytes]:
    return [msgpack.packb(_header(rng), use_bin_type=True)]


def _mutated(rng: random.Random) -> list[bytes]:
    args = [_value(rng) for _ in range(rng.randrange(4))]
    header = {"k": "call", "i": rng.randrange(1 << 20), "s": rng.choice(SERVICES)}
    header.update({"m": rng.choice(METHODS), "a": args})
    try:
        frames = [bytes(f) for f in wire.encode(header)]
    except Exception:
        return _garbage(rng)
    head = bytearray(frames[0])
    for _ in range(rng.randrange(1, 4)):
        at = rng.randrange(len(head))
        head[at] = rng.randrange(256)
    if rng.random() < 0.3:
        head = head[: rng.randrange(len(head))]
    return [bytes(head), *frames[1:]]


def _structural(rng: random.Random) -> list[bytes]:
    pick = rng.randrange(7)
    ok = msgpack.packb({"k": "ping", "i": 1})
    if pick == 0:  # declared sizes far beyond the bytes sent
        return [
            rng.choice([b"\xdd\xff\xff\xff\xff", b"\xdb\xff\xff\xff\xff", b"\xdf\xff\xff\xff\xff"])
        ]
    if pick == 1:  # deep nesting
        return [b"\x83\xa1k\xa4call\xa1i\x01\xa1a" + b"\x91" * rng.randrange(30, 3000) + b"\xc0"]
    if pick == 2:  # too many frames
        return [ok] + [b"x"] * rng.randrange(wire.MAX_FRAMES, wire.MAX_FRAMES + 4)
    if pick == 3:  # bad or reused buffer references
        ref = msgpack.ExtType(wire.EXT_BUFFER, struct.pack(">I", rng.randrange(4)))
        return [
            msgpack.packb({"k": "call", "i": 2, "s": "ALMotion", "m": "x", "a": [ref, ref]}),
            b"b",
        ]
    if pick == 4:  # an empty message body (only the routing frame reaches the server)
        return [b""]
    if pick == 5:  # a header over the limit: rarely, 1 MB each (the unit tests cover it too)
        size = wire.MAX_HEADER_BYTES + 1 if rng.random() < 0.02 else rng.randrange(64)
        return [b"\x00" * size]
    return [ok, b"orphan"]


GENERATORS: list[Callable[[random.Random], list[bytes]]] = [
    _garbage, _type_confused, _type_confused, _mutated, _mutated, _structural,
]  # fmt: skip


@dataclass
class FuzzReport:
    """What one fuzz run did.

    Attributes:
        sent: Messages sent.
        replies: Replies received.
        bytes_sent: Total bytes sent.
    """

    sent: int = 0
    replies: int = 0
    bytes_sent: int = 0


def fuzz_zmq(url: str, messages: int, seed: int) -> FuzzReport:
    """Send ``messages`` random malformed messages to the zmq server at ``url``.

    Replies are read as they come (and counted); the DEALER socket is recreated every
    500 messages so that the server also sees many clients come and go.
    """
    rng = random.Random(seed)
    report = FuzzReport()
    ctx = zmq.Context()
    try:
        sock = None
        for n in range(messages):
            if n % 500 == 0:
                if sock is not None:
                    sock.close(0)
                sock = ctx.socket(zmq.DEALER)
                sock.setsockopt(zmq.LINGER, 0)
                sock.setsockopt(zmq.SNDHWM, 0)
                sock.connect(url)
            assert sock is not None
            frames = rng.choice(GENERATORS)(rng)
            sock.send_multipart(frames)
            report.sent += 1
            report.bytes_sent += sum(len(f) for f in frames)
            while sock.poll(0):
                sock.recv_multipart()
                report.replies += 1
        if sock is not None:
            while sock.poll(500):  # until the server has caught up
                sock.recv_multipart()
                report.replies += 1
            sock.close(0)
    finally:
        ctx.destroy(linger=0)
    return report


def zmq_hello(url: str, timeout_ms: int = 3000) -> list[str]:
    """One valid ``hello`` from a fresh socket: the services the server lists (watchdog check)."""
    ctx = zmq.Context()
    try:
        sock = ctx.socket(zmq.DEALER)
        sock.setsockopt(zmq.LINGER, 0)
        sock.connect(url)
        sock.send_multipart(wire.encode({"k": "hello", "i": 1}))
        if not sock.poll(timeout_ms):
            raise TimeoutError(f"no answer to hello from {url} within {timeout_ms} ms")
        reply = wire.decode_reply(sock.recv_multipart())
        return list(reply["v"]["services"])
    finally:
        ctx.destroy(linger=0)
