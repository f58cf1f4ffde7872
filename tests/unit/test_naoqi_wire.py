"""The zmq wire codec: round trips, limits, and fuzzed bytes giving only ProtocolError."""

from __future__ import annotations

import contextlib
import struct

import msgpack
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from naoloc.backends.naoqi import wire
from naoloc.errors import ProtocolError


def test_call_round_trip_lifts_buffers_into_raw_frames() -> None:
    image = bytes(range(256)) * 900
    header = {"k": "call", "i": 7, "s": "ALVideoDevice", "m": "x", "a": [1, 2.5, image, [b"ab"]]}
    frames = wire.encode(header)
    assert len(frames) == 3
    assert frames[1] is image  # sent as is, no copy, no escaping
    assert image not in frames[0]
    assert wire.decode_request(frames) == header


def test_reply_round_trip_with_numpy_scalars_and_tuples() -> None:
    value = (np.float64(1.5), np.int32(3), [True, None, "s"], {"a": b"\x00\xff"})
    frames = wire.encode({"k": "ok", "i": 1, "v": value})
    assert wire.decode_reply(frames)["v"] == [1.5, 3, [True, None, "s"], {"a": b"\x00\xff"}]


def test_encode_refuses_objects_it_cannot_send() -> None:
    with pytest.raises(ProtocolError, match="cannot send"):
        wire.encode({"k": "ok", "i": 1, "v": object()})
    with pytest.raises(ProtocolError, match="keys must be strings"):
        wire.encode({"k": "ok", "i": 1, "v": {1: 2}})


@pytest.mark.parametrize(
    ("frames", "message"),
    [
        ([], "1 to"),
        ([b"\x00"] * (wire.MAX_FRAMES + 1), "1 to"),
        ([msgpack.packb([1, 2])], "must be a map"),
        ([msgpack.packb({"k": "nope", "i": 1})], "unknown message kind"),
        ([msgpack.packb({"k": "ping", "i": -1})], "message id"),
        ([msgpack.packb({"k": "ping", "i": True})], "message id"),
        ([msgpack.packb({"k": "ping", "i": 1, "x": 2})], "unexpected keys"),
        ([msgpack.packb({"k": "call", "i": 1, "s": "", "m": "m", "a": []})], "service name"),
        ([msgpack.packb({"k": "call", "i": 1, "s": "S", "m": "m", "a": 3})], "must be a list"),
        ([msgpack.packb({"k": "ping", "i": 1}), b"orphan"], "not referenced"),
        ([msgpack.packb({"k": "ping", "i": 1, "a": msgpack.ExtType(9, b"1234")})], "extension"),
        ([msgpack.packb({"k": "ping", "i": 1}) + b"\x00"], "undecodable"),
        ([b"\xc1"], "undecodable"),
    ],
)
def test_malformed_requests_raise_protocol_error(frames: list[bytes], message: str) -> None:
    with pytest.raises(ProtocolError, match=message):
        wire.decode_request(frames)


def test_buffer_references_are_checked() -> None:
    ref = msgpack.ExtType(wire.EXT_BUFFER, struct.pack(">I", 1))
    head = msgpack.packb({"k": "call", "i": 1, "s": "S", "m": "m", "a": [ref]})
    with pytest.raises(ProtocolError, match="bad buffer reference"):
        wire.decode_request([head, b"only one buffer"])
    twice = msgpack.ExtType(wire.EXT_BUFFER, struct.pack(">I", 0))
    head = msgpack.packb({"k": "call", "i": 1, "s": "S", "m": "m", "a": [twice, twice]})
    with pytest.raises(ProtocolError, match="bad buffer reference"):
        wire.decode_request([head, b"x"])


def test_sizes_and_depth_are_limited() -> None:
    big = b"\x00" * (wire.MAX_BUFFER_BYTES + 1)
    with pytest.raises(ProtocolError, match="exceeds"):
        wire.decode_request([msgpack.packb({"k": "ping", "i": 1}), big])
    with pytest.raises(ProtocolError, match="exceeds"):
        wire.decode_request([b"\x00" * (wire.MAX_HEADER_BYTES + 1)])
    deep: list[object] = []
    for _ in range(wire.MAX_DEPTH + 5):
        deep = [deep]
    head = msgpack.packb({"k": "call", "i": 1, "s": "S", "m": "m", "a": deep})
    with pytest.raises(ProtocolError, match="deeper"):
        wire.decode_request([head])


def test_error_replies_need_type_and_message() -> None:
    good = wire.encode({"k": "err", "i": 3, "e": ["HandleError", "no such handle"]})
    assert wire.decode_reply(good)["e"] == ["HandleError", "no such handle"]
    with pytest.raises(ProtocolError, match="error reply"):
        wire.decode_reply([msgpack.packb({"k": "err", "i": 3, "e": "oops"})])


_FUZZ = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@_FUZZ
@given(st.lists(st.binary(max_size=64), min_size=0, max_size=4))
def test_fuzzed_frames_raise_only_protocol_error(frames: list[bytes]) -> None:
    for decode in (wire.decode_request, wire.decode_reply):
        with contextlib.suppress(ProtocolError):
            decode(frames)


@_FUZZ
@given(st.binary(min_size=1, max_size=8), st.data())
def test_mutated_valid_messages_raise_only_protocol_error(
    patch: bytes, data: st.DataObject
) -> None:
    header = {"k": "call", "i": 5, "s": "ALMotion", "m": "moveTo", "a": [0.1, [b"img"], "x"]}
    frames = wire.encode(header)
    head = bytearray(frames[0])
    at = data.draw(st.integers(min_value=0, max_value=len(head) - 1))
    head[at : at + len(patch)] = patch
    try:
        decoded = wire.decode_request([bytes(head), *frames[1:]])
    except ProtocolError:
        return
    assert isinstance(decoded, dict)
    assert decoded["k"] in wire.REQUEST_KINDS


@pytest.mark.parametrize(
    "header",
    [
        {"k": [], "i": 1},
        {"k": {}, "i": 1},
        {"k": {"a": 1}, "i": 1},
        {"k": b"ping", "i": 1},
        {"k": 3.5, "i": 1},
        {"k": None, "i": 1},
        {"k": "call", "i": 1, "s": ["ALMotion"], "m": "moveTo", "a": []},
        {"k": "call", "i": 1, "s": "ALMotion", "m": {"x": 1}, "a": []},
        {"k": "ping", "i": [1]},
        {"k": "ping", "i": 1.0},
        {"k": "ping", "i": 2**64 - 1},
    ],
)
def test_fields_of_the_wrong_type_raise_protocol_error(header: dict[str, object]) -> None:
    frames = [msgpack.packb(header, use_bin_type=True)]
    for decode in (wire.decode_request, wire.decode_reply):
        with pytest.raises(ProtocolError):
            decode(frames)


def test_non_string_map_keys_and_non_bytes_frames_raise_protocol_error() -> None:
    with pytest.raises(ProtocolError):
        wire.decode_request([msgpack.packb({1: "ping", "i": 1}, strict_types=False)])
    with pytest.raises(ProtocolError):
        wire.decode_request([12345])
    with pytest.raises(ProtocolError):
        wire.decode_request("not a list of frames")  # type: ignore[arg-type]


def test_msgpack_nesting_beyond_the_depth_limit_is_refused_before_recursion() -> None:
    head = b"\x83\xa1k\xa4call\xa1i\x01\xa1a" + b"\x91" * 100_000 + b"\xc0"
    with pytest.raises(ProtocolError):
        wire.decode_request([head])


def test_declared_sizes_larger_than_the_header_are_refused() -> None:
    # an array header claiming 2**32-1 items, a str header claiming 4 GB: no allocation
    for head in (b"\xdd\xff\xff\xff\xff", b"\xdb\xff\xff\xff\xff", b"\xdf\xff\xff\xff\xff"):
        with pytest.raises(ProtocolError):
            wire.decode_request([head])


@pytest.mark.parametrize(
    ("header", "message"),
    [
        ({"k": "welcome", "i": 1, "v": {"services": 5}}, "services"),
        ({"k": "welcome", "i": 1, "v": {"services": [1, 2]}}, "services"),
        ({"k": "welcome", "i": 1, "v": [1]}, "welcome"),
        ({"k": "err", "i": 1, "e": ["x" * 5000, "y"]}, "error reply"),
    ],
)
def test_malformed_replies_raise_protocol_error(header: dict[str, object], message: str) -> None:
    with pytest.raises(ProtocolError, match=message):
        wire.decode_reply([msgpack.packb(header)])


_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-(2**63), 2**63 - 1) | st.floats() | st.text()
    | st.binary(max_size=64),
    lambda kids: st.lists(kids, max_size=4)
    | st.dictionaries(st.text(max_size=8), kids, max_size=4),
    max_leaves=20,
)  # fmt: skip


@_FUZZ
@given(_VALUES)
def test_any_sendable_value_round_trips(value: object) -> None:
    frames = wire.encode({"k": "ok", "i": 9, "v": value})
    decoded = wire.decode_reply(frames)["v"]
    assert msgpack.packb(decoded, use_bin_type=True) == msgpack.packb(value, use_bin_type=True)


@_FUZZ
@given(
    st.dictionaries(
        st.sampled_from(["k", "i", "s", "m", "a", "v", "e", "x"]),
        _VALUES | st.sampled_from(["call", "ping", "hello", "bye", "ok", "err", "welcome"]),
        max_size=6,
    )
)
def test_random_headers_decode_or_raise_only_protocol_error(header: dict[str, object]) -> None:
    frames = [msgpack.packb(header, use_bin_type=True)]
    for decode in (wire.decode_request, wire.decode_reply):
        try:
            decoded = decode(frames)
        except ProtocolError as err:
            assert "\n" not in str(err) and len(str(err)) < 300
            continue
        assert isinstance(decoded["k"], str) and isinstance(decoded["i"], int)
