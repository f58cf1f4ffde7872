"""naoloc's QiMessaging format: header, signatures, binary values, against libqi's bytes.

The byte strings marked "libqi" were captured from the real ``qi`` 3.1.5 package on
loopback (a libqi client calling a libqi service), so they pin our encoder and decoder
to what libqi actually sends.
"""

from __future__ import annotations

import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from naoloc.backends.naoqi.qimessaging import capability, codec, message, meta, signature
from naoloc.errors import ProtocolError

# libqi: the capability map its client sends to authenticate (service 0, action 8).
LIBQI_AUTH_REQUEST = bytes.fromhex(
    "0600000012000000436c69656e74536572766572536f636b65740100000062010c0000004d6573736167"
    "65466c6167730100000062010f0000004d6574614f626a65637443616368650100000062000c0000004f"
    "626a6563745074725549440100000062011300000052656c6174697665456e64706f696e745552490100"
    "000062011500000052656d6f746543616e63656c61626c6543616c6c73010000006201"
)
# libqi: dyn([1, "a", 2.5, {"k": True}]) for a method taking a Dynamic.
LIBQI_DYNAMIC_LIST = (
    b"\x03\x00\x00\x00[m]\x04\x00\x00\x00\x01\x00\x00\x00l\x01\x00\x00\x00\x00\x00\x00\x00"
    b"\x01\x00\x00\x00s\x01\x00\x00\x00a\x01\x00\x00\x00d\x00\x00\x00\x00\x00\x00\x04@"
    b"\x04\x00\x00\x00{mm}\x01\x00\x00\x00\x01\x00\x00\x00s\x01\x00\x00\x00k"
    b"\x01\x00\x00\x00b\x01"
)
# libqi: ints(1, -2, 3, True) for (UInt8, Int16, UInt64, Bool); mp({"a": 1, "b": 2}).
LIBQI_INTS = bytes.fromhex("01feff030000000000000001")
LIBQI_MAP = bytes.fromhex("02000000010000006101000000010000006202000000")
# libqi: the error a Python service's RuntimeError("boom") becomes (a dynamic string).
LIBQI_ERROR = b"\x01\x00\x00\x00s\x12\x00\x00\x00RuntimeError: boom"


def test_header_round_trip_and_layout() -> None:
    head = message.pack_header(7, 12, message.CALL, 0, 2, 1, 100)
    assert len(head) == message.HEADER_SIZE
    assert head[:4] == bytes.fromhex("42dead42")  # big-endian magic
    assert struct.unpack_from("<II", head, 4) == (7, 12)  # little-endian fields
    h = message.unpack_header(head)
    assert (h.id, h.size, h.type, h.flags, h.service, h.object, h.action) == (
        7, 12, message.CALL, 0, 2, 1, 100,
    )  # fmt: skip


@pytest.mark.parametrize(
    ("mutate", "needle"),
    [
        (lambda b: b[:10], "truncated"),
        (lambda b: b"\x00\x00\x00\x00" + b[4:], "bad magic"),
        (lambda b: b[:12] + b"\x05\x00" + b[14:], "version"),
        (lambda b: b[:14] + b"\x09" + b[15:], "unknown message type"),
        (lambda b: b[:15] + b"\x80" + b[16:], "flags"),
        (lambda b: b[:8] + struct.pack("<I", 60 * 1024 * 1024) + b[12:], "limit"),
    ],
)
def test_bad_headers_are_refused_with_one_line(mutate: object, needle: str) -> None:
    head = message.pack_header(1, 0, message.CALL, 0, 1, 1, 100)
    with pytest.raises(ProtocolError, match=needle) as info:
        message.unpack_header(mutate(head))  # type: ignore[operator]
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(
    "text",
    [
        "i", "[s]", "{sm}", "(iiiiiiridddd)", "+d", "#m", "[{s[(ii)]}]",
        codec.METAOBJECT_SIGNATURE, meta.SERVICE_INFO_SIGNATURE, "(s)<Structure,field>",
    ],
)  # fmt: skip
def test_signatures_parse_and_print_back(text: str) -> None:
    assert str(signature.parse(text)) == text


@pytest.mark.parametrize(
    "bad", ["", "[i", "{i}", "(i", "q", "ii", "(i)<A,b", "[" * 40 + "i" + "]" * 40]
)
def test_bad_signatures_are_refused(bad: str) -> None:
    with pytest.raises(ProtocolError):
        signature.parse(bad)


def test_our_encoder_writes_libqi_bytes() -> None:
    assert codec.encode_bytes("{sm}", capability.client_request()) == LIBQI_AUTH_REQUEST
    assert codec.encode_bytes("m", [1, "a", 2.5, {"k": True}]) == LIBQI_DYNAMIC_LIST
    assert codec.encode_bytes("(CwLb)", (1, -2, 3, True)) == LIBQI_INTS
    assert codec.encode_bytes("({si})", ({"a": 1, "b": 2},)) == LIBQI_MAP
    assert codec.decode("m", LIBQI_ERROR) == "RuntimeError: boom"


def test_our_decoder_reads_libqi_bytes() -> None:
    assert codec.decode("{sm}", LIBQI_AUTH_REQUEST) == capability.LOCAL
    assert codec.decode("m", LIBQI_DYNAMIC_LIST) == [1, "a", 2.5, {"k": True}]
    assert codec.decode("(CwLb)", LIBQI_INTS) == (1, -2, 3, True)


VALUES = [
    ("b", True), ("c", -128), ("C", 255), ("w", -32768), ("W", 65535),
    ("i", -(2**31)), ("I", 2**32 - 1), ("l", -(2**63)), ("L", 2**64 - 1),
    ("f", 1.5), ("d", 0.1), ("s", "héllo"), ("[d]", [0.1, 0.2]), ("[s]", ["a", ""]),
    ("{si}", {"a": 1}), ("(isd)", (1, "x", 2.0)), ("(i)<S,f>", (3,)), ("+i", None),
    ("+i", 5), ("m", {"k": [1, (2.0, "z")]}), ("[[i]]", [[1], [], [2, 3]]), ("v", None),
    ("{i[m]}", {1: [None, True]}),
]  # fmt: skip


@pytest.mark.parametrize(("sig", "value"), VALUES)
def test_every_type_round_trips(sig: str, value: object) -> None:
    assert codec.decode(sig, codec.encode_bytes(sig, value)) == value


def test_raw_buffers_are_zero_copy_both_ways() -> None:
    image = bytes(range(256)) * 900  # 230 400 bytes, a QVGA RGB frame
    w = codec.encode("(ir)", (1, image))
    parts, size = w.finish()
    assert size == 4 + 4 + len(image) and any(p is image for p in parts)  # not copied
    payload = bytearray(b"".join(parts))
    value = codec.decode("(ir)", payload)
    assert isinstance(value[1], memoryview) and value[1].obj is payload  # a view
    assert bytes(value[1]) == image


def test_objects_carry_metaobject_ids_and_uid() -> None:
    mo = meta.build([("val", "()", "i")], signals=[("sig", "(i)")]).to_wire()
    ref = codec.ObjectRef(mo, 2, 3, b"u" * 20)
    back = codec.decode("o", codec.encode_bytes("o", ref))
    assert (back.service, back.object, back.uid) == (2, 3, b"u" * 20)
    parsed = meta.MetaObject.from_wire(back.meta)
    assert [m.name for m in parsed.overloads("val")] == ["val"] and parsed.signal("sig") == 101


@pytest.mark.parametrize(
    ("sig", "data", "needle"),
    [
        ("[i]", struct.pack("<I", 2**31), "elements"),
        ("s", struct.pack("<I", 1000) + b"abc", "overruns"),
        ("r", struct.pack("<I", 2**32 - 1), "overruns"),
        ("(ii)", b"\x01\x02", "truncated"),
        ("i", b"\x01\x00\x00\x00\x00", "unexpected bytes"),
        ("m", struct.pack("<I", 1) + b"q", "unknown signature"),
        ("[()]", struct.pack("<I", 2**32 - 1), "elements"),
        (
            "m",
            (struct.pack("<I", 1) + b"m") * 500 + struct.pack("<I", 1) + b"i" + b"\0" * 4,
            "deep",
        ),
    ],
)
def test_hostile_payloads_fail_with_one_line(sig: str, data: bytes, needle: str) -> None:
    with pytest.raises(ProtocolError, match=needle) as info:
        codec.decode(sig, data)
    assert "\n" not in str(info.value)


def test_values_that_do_not_fit_the_signature_are_refused() -> None:
    for sig, value in [("i", 2**40), ("s", 3), ("[i]", 5), ("(ii)", (1,)), ("C", -1)]:
        with pytest.raises(ProtocolError):
            codec.encode_bytes(sig, value)


SIGS = ["m", "[m]", "{sm}", "(iiiiiiridddd)", "[(sIsI[s]ss)]", codec.METAOBJECT_SIGNATURE, "o"]


@settings(max_examples=400, deadline=None)
@given(data=st.binary(max_size=300), which=st.sampled_from(SIGS))
def test_random_bytes_never_crash_the_decoder(data: bytes, which: str) -> None:
    try:
        codec.decode(which, data)
    except ProtocolError as err:
        assert "\n" not in str(err)


@settings(max_examples=200, deadline=None)
@given(
    value=st.recursive(
        st.none()
        | st.booleans()
        | st.integers(-(2**63), 2**63 - 1)
        | st.floats(allow_nan=False)
        | st.text(max_size=20),
        lambda children: (
            st.lists(children, max_size=4)
            | st.dictionaries(st.text(max_size=5), children, max_size=4)
        ),
        max_leaves=20,
    )
)
def test_dynamic_values_round_trip(value: object) -> None:
    assert codec.decode("m", codec.encode_bytes("m", value)) == value


def test_capability_login_states() -> None:
    done = codec.decode("{sm}", codec.encode_bytes("{sm}", capability.server_reply({})))
    assert capability.check_reply(done)["ObjectPtrUID"] is False  # the peer did not offer it
    refused = capability.server_reply({}, capability.STATE_ERROR, "wrong user or password")
    with pytest.raises(ProtocolError, match="refused: wrong user"):
        capability.check_reply(codec.decode("{sm}", codec.encode_bytes("{sm}", refused)))
    request = capability.client_request("nao", "secret")
    assert (request["auth_user"], request["auth_token"]) == ("nao", "secret")


def test_numpy_images_go_out_as_raw_without_a_copy() -> None:
    np = pytest.importorskip("numpy")
    image = np.arange(240 * 320 * 3, dtype=np.uint8).reshape(240, 320, 3)
    parts, size = codec.encode("r", image).finish()
    assert size == 4 + image.nbytes
    assert any(isinstance(p, memoryview) and p.obj is image for p in parts)
    assert bytes(codec.decode("r", b"".join(parts))) == image.tobytes()
    strided = image[:, ::2]  # not contiguous: copied once, still right
    assert bytes(codec.decode("r", codec.encode_bytes("r", strided))) == strided.tobytes()
    assert codec.decode("m", codec.encode_bytes("m", np.float64(1.5))) == 1.5
    assert codec.decode("m", codec.encode_bytes("m", np.array([1, 2]))) == [1, 2]
