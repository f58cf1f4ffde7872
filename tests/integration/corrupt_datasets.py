"""A corpus of broken and hostile survey datasets, generated (nothing binary is checked in).

:func:`corpus` writes every case into a folder and returns ``(name, path, expected)``:
``naoloc build-map -d PATH`` must exit 1 with one stderr line naming PATH and containing
``expected``. Used by tests/test_dataset_corrupt.py on every run, and by
tools/bench_corrupt.py, which prints the time and peak memory of each rejection.
"""

from __future__ import annotations

import json
import struct
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

MAGIC = b"\x89MCAP0\r\n"
WIDTH, HEIGHT = 32, 24
CAMERA = {"width": WIDTH, "height": HEIGHT, "hfov": 1.06, "vfov": 0.83, "index": 0}


def image_bytes(fmt: str = "png", width: int = WIDTH, height: int = HEIGHT) -> bytes:
    """A real PNG or JPEG of a seeded pattern."""
    import cv2

    rng = np.random.default_rng(0)
    pixels = rng.integers(0, 255, (height, width, 3), dtype=np.uint8)
    ok, buf = cv2.imencode(".png" if fmt == "png" else ".jpg", pixels)
    assert ok
    return bytes(buf.tobytes())


def record(index: int, **changes: Any) -> dict[str, Any]:
    """A valid keyframe record, with fields replaced."""
    rec: dict[str, Any] = {
        "index": index,
        "stamp": 0.5 * index,
        "lap": 0,
        "pose": [0.2 * index, 0.0, 0.0],
        "command_pose": [0.2 * index, 0.0, 0.0],
        "odometry": None,
        "true_pose": [1.0 + 0.2 * index, 1.0, 0.0],
        "head_yaw": -1.57,
        "head_pitch": 0.0,
        "camera": dict(CAMERA),
    }
    rec.update(changes)
    return rec


def craft(
    path: Path,
    records: list[Any] | None = None,
    images: dict[int, bytes] | None = None,
    *,
    meta: str = "{}",
    config: str = "{}",
    version: str = "2",
    chunked: bool = True,
    raw_records: list[bytes] | None = None,
    status: bool = True,
) -> Path:
    """Write a dataset the way :class:`naoloc.data.dataset.DatasetWriter` lays it out.

    Args:
        path: The file.
        records: Keyframe records (JSON-able, or bytes written as they are); default three
            valid ones.
        images: Image payload per frame index; default a valid PNG for every record.
        meta: The ``meta`` metadata text.
        config: The ``config`` metadata text.
        version: The format version text.
        chunked: One chunk per frame (today's layout) or unchunked (version 1's).
        raw_records: Keyframe message bodies to add as they are (e.g. not JSON).
        status: Write the ``naoloc.status`` record (version 1 files had none).
    """
    from foxglove.messages import CompressedImage
    from mcap.writer import Writer

    records = [record(i) for i in range(3)] if records is None else records
    if images is None:
        images = {i: image_bytes() for i in range(len(records))}
    with open(path, "wb") as f:
        w = Writer(f, use_chunking=chunked, enable_data_crcs=True)
        w.start(library="corpus")
        sid = w.register_schema("foxglove.CompressedImage", "protobuf", b"")
        jid = w.register_schema("naoloc.Keyframe", "jsonschema", b"{}")
        image_ch = w.register_channel("/camera/image", "protobuf", sid)
        kf_ch = w.register_channel("/naoloc/keyframe", "json", jid)
        header = {"format": "naoloc-survey", "version": version, "config": config, "meta": meta}
        w.add_metadata("naoloc", header)
        for seq, payload in sorted(images.items()):
            msg = bytes(CompressedImage(data=payload, format="png").encode())
            w.add_message(image_ch, seq, msg, seq, sequence=seq)
        bodies = [r if isinstance(r, bytes) else json.dumps(r).encode() for r in records]
        for i, body in enumerate(bodies + (raw_records or [])):
            w.add_message(kf_ch, i, body, i, sequence=i)
            w.flush()
        if status:
            w.add_metadata("naoloc.status", {"complete": "true", "frames": str(len(records))})
        w.finish()
    return path


def png_with_header(width: int, height: int, colour: int = 2) -> bytes:
    """A PNG whose IHDR declares ``width x height`` and whose data is a little deflated zero
    stream: decoders allocate from the header (the "bomb")."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    ihdr = struct.pack(">IIBBBBB", width, height, 8, colour, 0, 0, 0)
    idat = zlib.compress(b"\x00" * (1 << 20), 9)  # first megabyte of rows: zeros
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")


def jpeg_with_header(width: int, height: int) -> bytes:
    """A real JPEG whose SOF0 dimensions are rewritten."""
    data = bytearray(image_bytes("jpeg"))
    at = data.index(b"\xff\xc0")
    data[at + 5 : at + 9] = struct.pack(">HH", height, width)
    return bytes(data)


def record_offsets(data: bytes) -> dict[int, list[int]]:
    """Byte offsets of the top-level records of an MCAP file, by opcode."""
    out: dict[int, list[int]] = {}
    at = len(MAGIC)
    while at + 9 <= len(data) - len(MAGIC):
        opcode, length = struct.unpack_from("<BQ", data, at)
        out.setdefault(opcode, []).append(at)
        at += 9 + length
    return out


def _valid(folder: Path) -> Path:
    """A real dataset written by DatasetWriter (3 frames, chunked, CRCs)."""
    from naoloc.data.dataset import DatasetWriter
    from naoloc.geometry import Pose2D
    from naoloc.robot.keyframe import CameraInfo, Keyframe

    path = folder / "valid.mcap"
    rng = np.random.default_rng(0)
    with DatasetWriter(path, config={}, meta={"origin_room_pose": [1.0, 1.0, 0.0]}) as w:
        for i in range(3):
            image = rng.integers(0, 255, (HEIGHT, WIDTH, 3), dtype=np.uint8)
            w.write(Keyframe(image, Pose2D(0.2 * i, 0, 0), camera=CameraInfo(WIDTH, HEIGHT)))
    return path


def _patched(src: Path, dst: Path, edit: Callable[[bytearray], None]) -> Path:
    data = bytearray(src.read_bytes())
    edit(data)
    dst.write_bytes(bytes(data))
    return dst


def _flip(offset_fraction: float) -> Callable[[bytearray], None]:
    def edit(data: bytearray) -> None:
        data[int(len(data) * offset_fraction)] ^= 0x10

    return edit


def _chunk_bomb(path: Path, declared: int, actual: int) -> Path:
    """A partial file whose one chunk inflates to ``actual`` bytes and declares ``declared``."""
    import zstandard
    from mcap.data_stream import RecordBuilder
    from mcap.records import Chunk, Header, Metadata

    b = RecordBuilder()
    Header(profile="", library="corpus").write(b)
    header = {"format": "naoloc-survey", "version": "2", "config": "{}", "meta": "{}"}
    Metadata(name="naoloc", metadata=header).write(b)
    compressor = zstandard.ZstdCompressor(level=3).compressobj()
    zeros = b"\x00" * (1 << 24)
    parts = [compressor.compress(zeros) for _ in range(actual // len(zeros))]
    data = b"".join(parts) + compressor.flush()
    Chunk(
        compression="zstd", data=data, message_start_time=0, message_end_time=0,
        uncompressed_crc=0, uncompressed_size=declared,
    ).write(b)  # fmt: skip
    path.write_bytes(MAGIC + b.end())
    return path


def corpus(folder: Path) -> list[tuple[str, Path, str]]:
    """Write every corrupt case into ``folder``; returns ``(name, path, expected)``."""
    folder.mkdir(parents=True, exist_ok=True)
    valid = _valid(folder)
    size = valid.stat().st_size
    cases: list[tuple[str, Path, str]] = []

    def add(name: str, expected: str, make: Callable[[Path], Path]) -> None:
        cases.append((name, make(folder / f"{name}.mcap"), expected))

    def frames(expected: str, name: str, **changes: Any) -> None:
        add(name, expected, lambda p: craft(p, [record(0, **changes), record(1), record(2)]))

    # Not MCAP at all.
    add("empty", "not an MCAP file", lambda p: (p.write_bytes(b""), p)[1])
    add("text", "not an MCAP file", lambda p: (p.write_bytes(b"hello " * 40), p)[1])
    add("magic-only", "not an MCAP file", lambda p: (p.write_bytes(MAGIC), p)[1])
    # Flipped bytes and lying lengths in a real, complete dataset.
    for frac in (0.02, 0.1, 0.3, 0.5, 0.7, 0.9, 0.97, 0.995):
        add(f"flip-{frac}", "corrupt MCAP", lambda p, f=frac: _patched(valid, p, _flip(f)))
    add("flip-magic", "not an MCAP file", lambda p: _patched(valid, p, _flip(0.0)))

    def huge_length(data: bytearray) -> None:
        at = record_offsets(bytes(data))[6][0]  # the first chunk record
        data[at + 1 : at + 9] = struct.pack("<Q", 4 * 2**30)

    add("length-4gib", "runs past the end", lambda p: _patched(valid, p, huge_length))
    add("cut-footer", "corrupt MCAP", lambda p: (p.write_bytes(
        valid.read_bytes()[: size - 12] + MAGIC), p)[1])  # fmt: skip
    add("chunk-declares-1gib", "limit", lambda p: _chunk_bomb(p, 2**30, 2**24))
    add("zstd-bomb", "declares 1000", lambda p: _chunk_bomb(p, 1000, 2**28))
    # Metadata.
    add("version-99", "newer than this naoloc", lambda p: craft(p, version="99"))
    add("version-text", "is not a number", lambda p: craft(p, version="one"))
    add("meta-null", "the survey meta must be an object, got null", lambda p: craft(p, meta="null"))
    add("config-list", "config metadata must be an object", lambda p: craft(p, config="[]"))
    add("meta-not-json", "meta is not valid JSON", lambda p: craft(p, meta="{oops"))
    add("meta-room-text", "meta.room_size_m", lambda p: craft(p, meta='{"room_size_m": "big"}'))
    add("meta-camera-nan", "meta.camera", lambda p: craft(
        p, meta=json.dumps({"camera": {**CAMERA, "hfov": float("nan")}})))  # fmt: skip
    add("meta-deep", "nested too deeply", lambda p: craft(p, meta="[" * 100_000 + "]" * 100_000))
    # Camera info and keyframe fields.
    for name, value in (("width-0", 0), ("width-neg", -320), ("width-1e12", 10**12)):
        frames("camera width is", name, camera={**CAMERA, "width": value})
    frames("camera.width must be an integer", "width-float", camera={**CAMERA, "width": 1e12})
    frames("hfov is nan", "hfov-nan", camera={**CAMERA, "hfov": float("nan")})
    frames("camera hfov is 0.0", "hfov-0", camera={**CAMERA, "hfov": 0})
    frames("camera index is 7", "camera-index", camera={**CAMERA, "index": 7})
    frames("camera must be an object, got null", "camera-null", camera=None)
    frames("head_pitch is nan", "pitch-nan", head_pitch=float("nan"))
    frames("head_yaw must be a number, got a string", "yaw-text", head_yaw="abc")
    frames("pose must be [x, y, theta]", "pose-short", pose=[1.0, 2.0])
    frames("pose is inf", "pose-inf", pose=[float("inf"), 0.0, 0.0])
    add("index-text", "index must be an integer", lambda p: craft(
        p, [{**record(0), "index": "zero"}, record(1), record(2)]))  # fmt: skip
    add("record-null", "must be an object, got null", lambda p: craft(p, [None, record(1)]))
    add("record-not-json", "is not valid JSON", lambda p: craft(
        p, [b"{not json", record(1), record(2)], {0: image_bytes(), 1: image_bytes(),
                                                    2: image_bytes()}))  # fmt: skip
    add(
        "record-deep",
        "nested too deeply",
        lambda p: craft(
            p, [b'{"index": 0, "x": ' + b"[" * 20_000 + b"]" * 20_000 + b"}"], {0: image_bytes()}
        ),
    )
    add("record-huge", "limit", lambda p: craft(
        p, [record(0, pad="x" * 200_000)]))  # fmt: skip
    add("index-twice", "appears twice", lambda p: craft(p, [record(0), record(0), record(1)]))
    add("no-image", "has no image", lambda p: craft(p, images={0: image_bytes()}))
    # Frames: too few, and images that lie.
    add("one-frame", "a map needs at least 3", lambda p: craft(p, [record(0)]))
    add("two-frames", "a map needs at least 3", lambda p: craft(p, [record(0), record(1)]))
    add("no-frames", "no frames", lambda p: craft(p, []))

    def with_image(payload: bytes, **cam: Any) -> Callable[[Path], Path]:
        recs = [record(i, camera={**CAMERA, **cam}) for i in range(3)]
        return lambda p: craft(p, recs, {0: payload, 1: image_bytes(), 2: image_bytes()})

    add("image-empty", "the image is empty", with_image(b""))
    add("image-gif", "neither PNG nor JPEG", with_image(b"GIF89a" + b"\x00" * 50))
    add("image-truncated-png", "does not decode", with_image(image_bytes()[:60]))
    add("image-truncated-jpeg", "does not decode", with_image(image_bytes("jpeg")[:200]))
    add("image-size-mismatch", "camera info 32 x 24", with_image(image_bytes("png", 64, 48)))
    add("png-bomb", "30000 x 30000 px, the camera info", with_image(png_with_header(30000, 30000)))
    add("png-bomb-camera", "would decode to", lambda p: craft(
        p, [record(i, camera={**CAMERA, "width": 8000, "height": 8000}) for i in range(3)],
        {i: png_with_header(8000, 8000) for i in range(3)}))  # fmt: skip
    add("jpeg-bomb", "60000 x 60000 px", with_image(jpeg_with_header(60000, 60000)))
    add("image-not-protobuf", "not valid protobuf", lambda p: _raw_image(p, b"\xff" * 40))
    return cases


def _raw_image(path: Path, message: bytes) -> Path:
    """A dataset whose first image message is ``message`` as it is (not a CompressedImage)."""
    from mcap.writer import Writer

    with open(path, "wb") as f:
        w = Writer(f, enable_data_crcs=True)
        w.start(library="corpus")
        sid = w.register_schema("foxglove.CompressedImage", "protobuf", b"")
        jid = w.register_schema("naoloc.Keyframe", "jsonschema", b"{}")
        image_ch = w.register_channel("/camera/image", "protobuf", sid)
        kf_ch = w.register_channel("/naoloc/keyframe", "json", jid)
        header = {"format": "naoloc-survey", "version": "2", "config": "{}", "meta": "{}"}
        w.add_metadata("naoloc", header)
        w.add_message(image_ch, 0, message, 0, sequence=0)
        for i in range(3):
            w.add_message(kf_ch, i, json.dumps(record(i)).encode(), i, sequence=i)
        w.finish()
    return path
