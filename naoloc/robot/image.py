"""Camera frames: the NAOqi image array as a typed value, and conversions to numpy.

``getImageRemote`` returns ``[width, height, layers, colorspace, sec, usec, bytes,
camera, left, top, right, bottom]`` (angles in radians). Over libqi the bytes may arrive
as ``bytes``, ``bytearray`` or even ``str``; :func:`frame_from_naoqi` accepts all three.

Nothing from the wire is trusted: every field's type, the size (1 to :data:`MAX_SIDE_PX`
pixels a side), the colorspace and its layer count, and the byte count are checked before
any byte is copied or any array is allocated; a failure is a one-line
:class:`~naoloc.errors.ImageError`. A :class:`Frame` checks its pixel array when made, so
no empty or mis-shaped image reaches OpenCV. A blank image is a valid frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from naoloc.constants import (
    COLORSPACE_LAYERS,
    kBGRColorSpace,
    kHSVColorSpace,
    kRGBColorSpace,
    kYUV422ColorSpace,
    kYUVColorSpace,
    kYuvColorSpace,
)
from naoloc.errors import ImageError, RobotError

MAX_SIDE_PX: Final = 4096  # NAO's largest image is k16VGA, 2560 x 1920


def check_pixels(pixels: Any, colorspace: Any) -> None:
    """Check that ``pixels`` is a non-empty ``(h, w, layers)`` uint8 image of ``colorspace``.

    Raises:
        ImageError: One line naming what does not match.
    """
    if not isinstance(colorspace, int) or colorspace not in COLORSPACE_LAYERS:
        raise ImageError(f"unknown colorspace {str(colorspace)[:20]}")
    if not isinstance(pixels, np.ndarray):
        raise ImageError(f"an image must be a numpy array, got {type(pixels).__name__}")
    if pixels.dtype != np.uint8 or pixels.ndim != 3:
        raise ImageError(
            f"an image must be (height, width, layers) uint8, got {pixels.ndim}-d {pixels.dtype}"
        )
    height, width, layers = pixels.shape
    if not (0 < width <= MAX_SIDE_PX and 0 < height <= MAX_SIDE_PX):
        raise ImageError(f"image size {width}x{height} is outside 1..{MAX_SIDE_PX} pixels")
    if layers != COLORSPACE_LAYERS[colorspace]:
        raise ImageError(
            f"colorspace {colorspace} has {COLORSPACE_LAYERS[colorspace]} layers, "
            f"the image {layers}"
        )
    if colorspace == kYUV422ColorSpace and width % 2:
        raise ImageError(f"a YUV422 image needs an even width, got {width}")


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

    def __post_init__(self) -> None:
        check_pixels(self.pixels, self.colorspace)

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


def _byte_count(data: Any) -> int:
    """Length in bytes of image data as NAOqi sends it, without copying it."""
    if isinstance(data, str) and data.startswith(("b'", 'b"')):
        frame_bytes(data)  # raises the repr-text error
    if isinstance(data, bytes | bytearray | str):
        return len(data)
    if isinstance(data, memoryview | np.ndarray):
        return int(data.nbytes)
    raise ImageError(f"frame bytes have unexpected type {type(data).__name__}")


def frame_bytes(data: Any) -> bytes:
    """Image bytes as any NAOqi sends them: ``bytes``, ``bytearray``, ``str`` (or an array).

    Raises:
        ImageError: For repr text (a server that sent bytes untyped) or another type.
    """
    if isinstance(data, bytes):
        return data
    if isinstance(data, bytearray | memoryview):
        return bytes(data)
    if isinstance(data, str):
        if data.startswith(("b'", 'b"')):
            raise ImageError(
                "frame bytes arrived as repr text; the server must declare image buffers qi.Buffer"
            )
        try:
            return data.encode("latin-1")
        except UnicodeEncodeError:
            raise ImageError("frame bytes arrived as text that is not latin-1") from None
    if isinstance(data, np.ndarray):
        return data.tobytes()
    raise ImageError(f"frame bytes have unexpected type {type(data).__name__}")


def _int_field(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise ImageError(f"image {name} must be an integer, got {type(value).__name__}")
    return int(value)


def _real_field(value: Any, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise ImageError(f"image {name} must be a number, got {type(value).__name__}")
    number = float(value)
    if not math.isfinite(number):
        raise ImageError(f"image {name} must be finite, got {number}")
    return number


def frame_from_naoqi(value: Sequence[Any]) -> Frame:
    """Decode a NAOqi image array into a :class:`Frame`.

    Raises:
        ImageError: (a RobotError) If the array is malformed, its size or colorspace is
            impossible, or its byte count does not match width x height x layers.
    """
    if not isinstance(value, list | tuple) or len(value) < 12:
        raise ImageError("getImageRemote returned no image (is the camera subscribed?)")
    width = _int_field(value[0], "width")
    height = _int_field(value[1], "height")
    layers = _int_field(value[2], "layers")
    colorspace = _int_field(value[3], "colorspace")
    if not (0 < width <= MAX_SIDE_PX and 0 < height <= MAX_SIDE_PX):
        raise ImageError(f"image size {width}x{height} is outside 1..{MAX_SIDE_PX} pixels")
    if colorspace not in COLORSPACE_LAYERS:
        raise ImageError(f"unknown colorspace {colorspace}; valid: {sorted(COLORSPACE_LAYERS)}")
    if layers != COLORSPACE_LAYERS[colorspace]:
        raise ImageError(
            f"colorspace {colorspace} has {COLORSPACE_LAYERS[colorspace]} layers, "
            f"the image says {layers}"
        )
    expected = width * height * layers
    count = _byte_count(value[6])
    if count != expected:
        raise ImageError(
            f"image of {width}x{height}x{layers} should have {expected} bytes, got {count}"
        )
    data = frame_bytes(value[6])
    pixels = np.frombuffer(data, dtype=np.uint8).reshape(height, width, layers)
    stamp = _real_field(value[4], "time (s)") + _real_field(value[5], "time (us)") * 1e-6
    camera = _int_field(value[7], "camera")
    angles = (
        _real_field(value[8], "angle left"),
        _real_field(value[9], "angle top"),
        _real_field(value[10], "angle right"),
        _real_field(value[11], "angle bottom"),
    )
    return Frame(pixels, colorspace, stamp, camera, angles)


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
    """Luma of an image in any NAOqi colorspace, ``(h, w)`` uint8.

    Raises:
        ImageError: An empty or mis-shaped image, or an unknown colorspace.
    """
    import cv2

    check_pixels(pixels, colorspace)

    if colorspace in (kYuvColorSpace, kYUV422ColorSpace, kYUVColorSpace):
        return np.ascontiguousarray(pixels[..., 0])
    if colorspace == kRGBColorSpace:
        return cv2.cvtColor(pixels, cv2.COLOR_RGB2GRAY)
    if colorspace == kBGRColorSpace:
        return cv2.cvtColor(pixels, cv2.COLOR_BGR2GRAY)
    return cv2.cvtColor(to_bgr(pixels, colorspace), cv2.COLOR_BGR2GRAY)


def to_bgr(pixels: np.ndarray, colorspace: int) -> np.ndarray:
    """An image in any NAOqi colorspace as ``(h, w, 3)`` uint8 BGR.

    Raises:
        ImageError: An empty or mis-shaped image, or an unknown colorspace.
    """
    import cv2

    check_pixels(pixels, colorspace)

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
