"""NAOqi image arrays from a broken or hostile server: one-line ImageError, never cv2.error.

Sizes, byte counts and colorspaces are checked before anything is allocated; a blank
image (no features) is a valid frame.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from naoloc.constants import COLORSPACE_LAYERS, kYUV422ColorSpace
from naoloc.errors import ImageError, RobotError
from naoloc.robot.image import MAX_SIDE_PX, Frame, frame_from_naoqi, frame_to_naoqi, to_bgr, to_gray


def _array(w: int = 4, h: int = 3, layers: int = 3, cs: int = 11, data: object = None) -> list:
    raw = bytes(w * h * layers) if data is None else data
    return [w, h, layers, cs, 1, 500, raw, 0, 0.49, 0.38, -0.49, -0.38]


@pytest.mark.parametrize(
    ("array", "fragment"),
    [
        (_array(0, 0, 3, data=b""), "size"),
        (_array(0, 3), "size"),
        (_array(-320, 240, data=b""), "size"),
        (_array(10**12, 1, data=b""), "size"),
        (_array(MAX_SIDE_PX + 1, 1, data=b""), "size"),
        (_array(4, 3, 0, data=b""), "layers"),
        (_array(4, 3, 2, cs=11), "layers"),
        (_array(4, 3, 3, cs=99), "colorspace"),
        (_array(4, 3, 3, cs=-1), "colorspace"),
        (_array(data=b"\x00" * 35), "bytes"),
        (_array(data=b"\x00" * 37), "bytes"),
        (_array(data=12), "type"),
        (_array(data=None)[:11], "no image"),
        ([*_array()[:4], float("nan"), *_array()[5:]], "time"),
        ([*_array()[:8], float("inf"), *_array()[9:]], "angle"),
        (["4", 3, 3, 11, *_array()[4:]], "width"),
        ([4.5, 3, 3, 11, *_array()[4:]], "width"),
        ([True, 3, 3, 11, *_array()[4:]], "width"),
        ([4, 3, 3, 11, 1, 500, bytes(36), "top", 0, 0, 0, 0], "camera"),
        ("not an image array at all", "no image"),
        ({"w": 4}, "no image"),
    ],
)
def test_malformed_arrays_are_one_line_image_errors(array: object, fragment: str) -> None:
    with pytest.raises(ImageError) as info:
        frame_from_naoqi(array)  # type: ignore[arg-type]
    message = str(info.value)
    assert isinstance(info.value, RobotError)
    assert "\n" not in message and len(message) < 300 and fragment in message, message


def test_a_huge_declared_size_is_refused_before_the_bytes_are_touched() -> None:
    class Exploding(bytes):
        def __len__(self) -> int:
            raise AssertionError("the bytes were touched before the size check")

    with pytest.raises(ImageError, match="size"):
        frame_from_naoqi(_array(100_000, 100_000, data=Exploding()))


@pytest.mark.parametrize(
    "pixels",
    [
        np.zeros((0, 0, 3), np.uint8),
        np.zeros((0, 5, 3), np.uint8),
        np.zeros((4, 5), np.uint8),
        np.zeros((4, 5, 3), np.float32),
        np.zeros((4, 5, 1), np.uint8),
    ],
)
def test_empty_or_mis_shaped_pixels_are_image_errors_not_cv2_errors(pixels: np.ndarray) -> None:
    for convert in (to_gray, to_bgr):
        with pytest.raises(ImageError):
            convert(pixels, 11)
    with pytest.raises(ImageError):
        Frame(pixels, 11, 0.0, 0, (0.0, 0.0, 0.0, 0.0))


def test_a_blank_image_is_a_valid_frame() -> None:
    frame = frame_from_naoqi(_array(32, 24))
    assert frame.gray().shape == (24, 32) and not frame.gray().any()


_FUZZ = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
_SCALARS = (
    st.integers(-(2**40), 2**40) | st.floats() | st.none() | st.booleans() | st.text(max_size=4)
)


@_FUZZ
@given(
    st.lists(_SCALARS | st.binary(max_size=64), min_size=0, max_size=14),
    st.integers(0, 13),
    st.binary(max_size=64),
)
def test_random_arrays_decode_or_raise_only_image_error(
    array: list[object], at: int, data: bytes
) -> None:
    if at < len(array):
        array[at] = data
    try:
        frame = frame_from_naoqi(array)
    except ImageError as err:
        assert "\n" not in str(err)
        return
    assert frame.pixels.size == frame.width * frame.height * COLORSPACE_LAYERS[frame.colorspace]


@_FUZZ
@given(
    st.integers(1, 40),
    st.integers(1, 40),
    st.sampled_from(sorted(COLORSPACE_LAYERS)),
    st.integers(-3, 3),
)
def test_valid_arrays_round_trip_and_off_by_some_bytes_are_refused(
    w: int, h: int, cs: int, delta: int
) -> None:
    layers = COLORSPACE_LAYERS[cs]
    if cs == kYUV422ColorSpace:
        w += w % 2  # YUYV pairs pixels: NAOqi's widths are even
    pixels = np.random.default_rng(w * h).integers(0, 256, (h, w, layers), dtype=np.uint8)
    array = frame_to_naoqi(Frame(pixels, cs, 2.5, 1, (0.1, 0.2, -0.1, -0.2)))
    if delta == 0:
        back = frame_from_naoqi(array)
        np.testing.assert_array_equal(back.pixels, pixels)
        assert back.gray().shape == (h, w) and back.bgr().shape == (h, w, 3)
        return
    raw = array[6]
    array[6] = raw[:delta] if delta < 0 else raw + bytes(delta)
    with pytest.raises(ImageError, match="bytes"):
        frame_from_naoqi(array)
