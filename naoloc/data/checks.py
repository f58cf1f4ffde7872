"""Checks a survey dataset's contents pass before naoloc trusts them.

Every function raises ``ValueError`` with a short phrase naming the field and the problem;
:mod:`naoloc.data.dataset` prefixes the file (and frame) and turns it into a
:class:`naoloc.errors.DatasetError`. Images are sized from their PNG ``IHDR`` or JPEG
``SOF`` header, before any pixel is decoded, so a small file that would inflate to
gigabytes (a "PNG bomb") is refused at once.
"""

from __future__ import annotations

import json
import math
import struct
from typing import Any

from naoloc.geometry import Pose2D
from naoloc.robot.keyframe import CameraInfo, check_camera

# Decoded pixels of one frame at most (NAO's largest image, 2560 x 1920 x 3, is 14.7 MB).
MAX_FRAME_BYTES = 64 * 2**20
MAX_JSON_BYTES = {"keyframe": 64 * 2**10, "metadata": 16 * 2**20}
MAX_JSON_DEPTH = 32
MAX_POSE_M = 1e6  # any coordinate beyond a thousand kilometres is garbage

_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_PNG_CHANNELS = {0: 1, 2: 3, 3: 3, 4: 4, 6: 4}  # colour type -> channels as OpenCV decodes
# JPEG start-of-frame markers: C0-CF except DHT (C4), JPG (C8) and DAC (CC).
_SOF = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}
_STANDALONE = frozenset(range(0xD0, 0xD9)) | {0x01}


def image_header(payload: bytes) -> tuple[int, int, int]:
    """``(width, height, decoded bytes)`` of a PNG or JPEG from its header alone.

    Raises:
        ValueError: Empty, neither PNG nor JPEG, or a header that does not parse.
    """
    if not payload:
        raise ValueError("the image is empty (0 bytes)")
    if payload.startswith(_PNG_SIGNATURE):
        return _png_header(payload)
    if payload.startswith(b"\xff\xd8"):
        return _jpeg_header(payload)
    raise ValueError("the image is neither PNG nor JPEG")


def _png_header(data: bytes) -> tuple[int, int, int]:
    if len(data) < 33 or data[12:16] != b"IHDR":
        raise ValueError("the PNG has no IHDR header")
    width, height, depth, colour = struct.unpack(">IIBB", data[16:26])
    if colour not in _PNG_CHANNELS or depth not in (1, 2, 4, 8, 16):
        raise ValueError(f"the PNG header is invalid (bit depth {depth}, colour type {colour})")
    sample = 2 if depth == 16 else 1
    return width, height, width * height * _PNG_CHANNELS[colour] * sample


def _jpeg_header(data: bytes) -> tuple[int, int, int]:
    i, n = 2, len(data)
    while i < n:
        if data[i] != 0xFF:
            raise ValueError(f"the JPEG has a bad marker at byte {i}")
        while i < n and data[i] == 0xFF:  # fill bytes
            i += 1
        if i >= n:
            break
        marker = data[i]
        i += 1
        if marker in _STANDALONE:
            continue
        if marker == 0xDA or marker == 0xD9 or i + 2 > n:
            break  # scan data (or the end) before any frame header
        (length,) = struct.unpack(">H", data[i : i + 2])
        if length < 2:
            raise ValueError(f"the JPEG has a bad segment length at byte {i}")
        if marker in _SOF:
            if i + 8 > n:
                break
            precision, height, width, components = struct.unpack(">BHHB", data[i + 2 : i + 8])
            sample = 2 if precision > 8 else 1
            return width, height, width * height * max(1, components) * sample
        i += length
    raise ValueError("the JPEG has no frame (SOF) header")


def check_image(payload: bytes, camera: CameraInfo) -> None:
    """Refuse an image whose header disagrees with the camera or would decode too large.

    Raises:
        ValueError: Empty, unknown format, size other than the camera's, or too big.
    """
    width, height, decoded = image_header(payload)
    if width == 0 or height == 0:
        raise ValueError(f"the image header says {width} x {height} px")
    if (width, height) != (camera.width, camera.height):
        raise ValueError(
            f"the image header says {width} x {height} px, the camera info "
            f"{camera.width} x {camera.height}"
        )
    if decoded > MAX_FRAME_BYTES:
        raise ValueError(f"the image would decode to {decoded} bytes (limit {MAX_FRAME_BYTES})")


def parse_json(data: bytes, what: str, kind: str = "keyframe") -> Any:
    """JSON from bytes, size- and depth-capped.

    Raises:
        ValueError: Too big, too deeply nested, or not JSON.
    """
    limit = MAX_JSON_BYTES[kind]
    if len(data) > limit:
        raise ValueError(f"{what} is {len(data)} bytes (limit {limit})")
    try:
        value = json.loads(data)
    except RecursionError:
        raise ValueError(f"{what} is nested too deeply") from None
    except (ValueError, UnicodeDecodeError):
        raise ValueError(f"{what} is not valid JSON") from None
    if _depth(value) > MAX_JSON_DEPTH:
        raise ValueError(f"{what} is nested deeper than {MAX_JSON_DEPTH} levels")
    return value


def _depth(value: Any) -> int:
    deepest, stack = 0, [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict | list):
            deepest = max(deepest, depth)
            if depth <= MAX_JSON_DEPTH:
                children = item.values() if isinstance(item, dict) else item
                stack.extend((c, depth + 1) for c in children)
    return deepest


def number(value: Any, what: str, lo: float = -math.inf, hi: float = math.inf) -> float:
    """A finite JSON number in ``[lo, hi]`` (booleans are not numbers)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{what} must be a number, got {_kind(value)}")
    out = float(value)
    if not math.isfinite(out):
        raise ValueError(f"{what} is {out}, not a finite number")
    if not lo <= out <= hi:
        raise ValueError(f"{what} is {out:g}, outside [{lo:g}, {hi:g}]")
    return out


def integer(value: Any, what: str, lo: int, hi: int) -> int:
    """A JSON integer in ``[lo, hi]``."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{what} must be an integer, got {_kind(value)}")
    if not lo <= value <= hi:
        raise ValueError(f"{what} is {_short(value)}, outside [{lo}, {hi}]")
    return value


def pose(value: Any, what: str) -> Pose2D:
    """``[x, y, theta]``: finite, metres within :data:`MAX_POSE_M`, radians."""
    if not isinstance(value, list) or len(value) != 3:
        raise ValueError(f"{what} must be [x, y, theta], got {_kind(value)}")
    x, y = (number(v, what, -MAX_POSE_M, MAX_POSE_M) for v in value[:2])
    return Pose2D(x, y, number(value[2], what, -MAX_POSE_M, MAX_POSE_M))


def pose_or_none(value: Any, what: str) -> Pose2D | None:
    """:func:`pose`, or None for a JSON null."""
    return None if value is None else pose(value, what)


def camera(value: Any, what: str = "camera") -> CameraInfo:
    """A camera record ``{width, height, hfov, vfov, index}`` checked by ``check_camera``."""
    if not isinstance(value, dict):
        raise ValueError(f"{what} must be an object, got {_kind(value)}")
    try:
        cam = CameraInfo(
            integer(value.get("width"), f"{what}.width", -(2**63), 2**63),
            integer(value.get("height"), f"{what}.height", -(2**63), 2**63),
            number(value.get("hfov"), f"{what}.hfov"),
            number(value.get("vfov"), f"{what}.vfov"),
            integer(value.get("index", 0), f"{what}.index", -(2**63), 2**63),
        )
        return check_camera(cam)
    except ValueError as err:
        message = str(err)
        raise ValueError(message if message.startswith(what) else f"{what}: {message}") from None


def survey_meta(meta: Any) -> dict[str, Any]:
    """The survey meta: an object whose known keys have the right types.

    Raises:
        ValueError: Not an object, or a known key (camera, origin_room_pose, room_size_m,
            frames_per_lap, complete, frames) of the wrong type.
    """
    if not isinstance(meta, dict):
        raise ValueError(f"the survey meta must be an object, got {_kind(meta)}")
    if meta.get("camera") is not None:
        camera(meta["camera"], "meta.camera")
    pose_or_none(meta.get("origin_room_pose"), "meta.origin_room_pose")
    size = meta.get("room_size_m")
    if size is not None:
        if not isinstance(size, list) or len(size) != 2:
            raise ValueError(f"meta.room_size_m must be [x, y], got {_kind(size)}")
        for v in size:
            number(v, "meta.room_size_m", 1e-3, MAX_POSE_M)
    if meta.get("frames_per_lap") is not None:
        integer(meta["frames_per_lap"], "meta.frames_per_lap", 1, 10**7)
    if "complete" in meta and not isinstance(meta["complete"], bool):
        raise ValueError(f"meta.complete must be true or false, got {_kind(meta['complete'])}")
    if meta.get("frames") is not None:
        integer(meta["frames"], "meta.frames", 0, 10**9)
    return meta


def _kind(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, int | float):
        return _short(value)
    if isinstance(value, str):
        return "a string"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    if isinstance(value, dict):
        return "an object"
    return type(value).__name__


def _short(value: int | float) -> str:
    text = repr(value)
    return text if len(text) <= 24 else f"a {len(text)}-digit number"
