"""Camera frames: the NAOqi image array as a typed value, and conversions to numpy.

``getImageRemote`` returns ``[width, height, layers, colorspace, sec, usec, bytes,
camera, left, top, right, bottom]`` (angles in radians). Over libqi the bytes may arrive
as ``bytes``, ``bytearray`` or even ``str``; :func:`frame_from_naoqi` accepts all three.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from naoloc.constants import (
    kBGRColorSpace,
    kHSVColorSpace,
    kRGBColorSpace,
    kYUV422ColorSpace,
    kYUVColorSpace,
    kYuvColorSpace,
)
from naoloc.errors import RobotError


@dataclass(frozen=True, slots=True)
class Frame:
    """One camera image with its NAOqi metadata.

    Attributes:
        pixels: ``(height, width, layers)`` uint8 array, row-major as NAOqi sends it.
        colorspace: NAOqi colorspace id.
        stamp: Capture time in seconds (robot clock; simulated time on simulators).
        camera: Camera index (0 top, 1 bottom).
        angles: ``(left, top, right, bottom)`` view angles in radians.
    """

    pixels: np.ndarray
    colorspace: int
    stamp: float
    camera: int
    angles: tuple[float, float, float, float]

    @property
    def width(self) -> int:
        """Width in pixels."""
        return int(self.pixels.shape[1])

    @property
    def height(self) -> int:
        """Height in pixels."""
        return int(self.pixels.shape[0])

    def gray(self) -> np.ndarray:
        """The image as a ``(height, width)`` uint8 luma array."""
        return to_gray(self.pixels, self.colorspace)

    def bgr(self) -> np.ndarray:
        """The image as a ``(height, width, 3)`` uint8 BGR array (OpenCV order)."""
        return to_bgr(self.pixels, self.colorspace)


def frame_bytes(data: Any) -> bytes:
    """Image bytes as any NAOqi sends them: ``bytes``, ``bytearray``, ``str`` (or an array).

    Raises:
        RobotError: For repr text (a server that sent bytes untyped) or another type.
    """
    if isinstance(data, bytes):
        return data
    if isinstance(data, bytearray | memoryview):
        return bytes(data)
    if isinstance(data, str):
        if data.startswith(("b'", 'b"')):
            raise RobotError(
                "frame bytes arrived as repr text; the server must declare image buffers qi.Buffer"
            )
        return data.encode("latin-1")
    if isinstance(data, np.ndarray):
        return data.tobytes()
    raise RobotError(f"frame bytes have unexpected type {type(data).__name__}")


def frame_from_naoqi(value: Sequence[Any]) -> Frame:
    """Decode a NAOqi image array into a :class:`Frame`.

    Raises:
        RobotError: If the array is malformed or its byte count does not match.
    """
    if value is None or len(value) < 12:
        raise RobotError("getImageRemote returned no image (is the camera subscribed?)")
    width, height, layers, colorspace = (int(v) for v in value[:4])
    data = frame_bytes(value[6])
    expected = width * height * layers
    if width <= 0 or height <= 0 or layers <= 0 or len(data) != expected:
        raise RobotError(
            f"image of {width}x{height}x{layers} should have {expected} bytes, got {len(data)}"
        )
    pixels = np.frombuffer(data, dtype=np.uint8).reshape(height, width, layers)
    stamp = float(value[4]) + float(value[5]) * 1e-6
    angles = (float(value[8]), float(value[9]), float(value[10]), float(value[11]))
    return Frame(pixels, colorspace, stamp, int(value[7]), angles)


def frame_to_naoqi(frame: Frame) -> list[Any]:
    """Encode a :class:`Frame` as the NAOqi image array (bytes in slot 6)."""
    sec = int(frame.stamp)
    usec = round((frame.stamp - sec) * 1e6)
    height, width, layers = frame.pixels.shape
    return [
        width, height, layers, frame.colorspace, sec, usec,
        np.ascontiguousarray(frame.pixels).tobytes(), frame.camera, *frame.angles,
    ]  # fmt: skip


def from_rgb(rgb: np.ndarray, colorspace: int) -> np.ndarray:
    """Convert an ``(h, w, 3)`` uint8 RGB image into a NAOqi colorspace layout.

    Returns:
        ``(h, w, layers)`` uint8 array with ``layers = COLORSPACE_LAYERS[colorspace]``.

    Raises:
        RobotError: For a colorspace this function does not produce.
    """
    import cv2

    if colorspace == kRGBColorSpace:
        return np.ascontiguousarray(rgb)
    if colorspace == kBGRColorSpace:
        return np.ascontiguousarray(rgb[..., ::-1])
    if colorspace == kYuvColorSpace:
        return cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)[..., None]
    if colorspace == kYUVColorSpace:
        return cv2.cvtColor(rgb, cv2.COLOR_RGB2YUV)
    if colorspace == kYUV422ColorSpace:
        yuv = cv2.cvtColor(rgb, cv2.COLOR_RGB2YUV)
        out = np.empty((*rgb.shape[:2], 2), np.uint8)
        out[..., 0] = yuv[..., 0]
        # YUYV: even pixels carry U, odd pixels carry V (averaged over the pair).
        u = yuv[..., 1].astype(np.uint16)
        v = yuv[..., 2].astype(np.uint16)
        w2 = rgb.shape[1] // 2 * 2
        out[:, 0:w2:2, 1] = ((u[:, 0:w2:2] + u[:, 1:w2:2]) // 2).astype(np.uint8)
        out[:, 1:w2:2, 1] = ((v[:, 0:w2:2] + v[:, 1:w2:2]) // 2).astype(np.uint8)
        if w2 < rgb.shape[1]:
            out[:, -1, 1] = yuv[:, -1, 1]
        return out
    if colorspace == kHSVColorSpace:
        return cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)
    raise RobotError(f"unsupported colorspace {colorspace}")


def to_gray(pixels: np.ndarray, colorspace: int) -> np.ndarray:
    """Luma of an image in any NAOqi colorspace, ``(h, w)`` uint8."""
    import cv2

    if colorspace in (kYuvColorSpace, kYUV422ColorSpace, kYUVColorSpace):
        return np.ascontiguousarray(pixels[..., 0])
    if colorspace == kRGBColorSpace:
        return cv2.cvtColor(pixels, cv2.COLOR_RGB2GRAY)
    if colorspace == kBGRColorSpace:
        return cv2.cvtColor(pixels, cv2.COLOR_BGR2GRAY)
    return cv2.cvtColor(to_bgr(pixels, colorspace), cv2.COLOR_BGR2GRAY)


def to_bgr(pixels: np.ndarray, colorspace: int) -> np.ndarray:
    """An image in any NAOqi colorspace as ``(h, w, 3)`` uint8 BGR."""
    import cv2

    if colorspace == kBGRColorSpace:
        return pixels
    if colorspace == kRGBColorSpace:
        return np.ascontiguousarray(pixels[..., ::-1])
    if colorspace == kYuvColorSpace:
        return cv2.cvtColor(pixels[..., 0], cv2.COLOR_GRAY2BGR)
    if colorspace == kYUVColorSpace:
        return cv2.cvtColor(pixels, cv2.COLOR_YUV2BGR)
    if colorspace == kYUV422ColorSpace:
        return cv2.cvtColor(np.ascontiguousarray(pixels), cv2.COLOR_YUV2BGR_YUYV)
    if colorspace == kHSVColorSpace:
        return cv2.cvtColor(pixels, cv2.COLOR_HSV2BGR)
    raise RobotError(f"unsupported colorspace {colorspace}")
