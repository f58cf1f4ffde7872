"""Frames: NAOqi arrays, colorspace layouts and the bytes/bytearray/str variants of libqi."""

from __future__ import annotations

import numpy as np
import pytest

from naoloc.constants import COLORSPACE_LAYERS
from naoloc.errors import RobotError
from naoloc.robot.image import Frame, frame_from_naoqi, frame_to_naoqi, from_rgb, to_bgr, to_gray


def _rgb(h: int = 24, w: int = 32) -> np.ndarray:
    rng = np.random.default_rng(0)
    return rng.integers(0, 256, (h, w, 3), dtype=np.uint8)


@pytest.mark.parametrize("cs", sorted(COLORSPACE_LAYERS))
def test_layouts_have_documented_layers(cs: int) -> None:
    out = from_rgb(_rgb(), cs)
    assert out.shape == (24, 32, COLORSPACE_LAYERS[cs]) and out.dtype == np.uint8
    assert to_bgr(out, cs).shape == (24, 32, 3)
    assert to_gray(out, cs).shape == (24, 32)


def test_rgb_bgr_exact() -> None:
    rgb = _rgb()
    np.testing.assert_array_equal(to_bgr(from_rgb(rgb, 11), 11)[..., ::-1], rgb)
    np.testing.assert_array_equal(to_bgr(from_rgb(rgb, 13), 13)[..., ::-1], rgb)


@pytest.mark.parametrize("kind", [bytes, bytearray, "str"])
def test_frame_round_trip_accepts_libqi_buffer_types(kind: object) -> None:
    pixels = _rgb()
    frame = Frame(pixels, 11, 12.345678, 0, (0.49, 0.38, -0.49, -0.38))
    arr = frame_to_naoqi(frame)
    raw = arr[6]
    arr[6] = raw.decode("latin-1") if kind == "str" else kind(raw)  # type: ignore[operator]
    back = frame_from_naoqi(arr)
    np.testing.assert_array_equal(back.pixels, pixels)
    assert back.stamp == pytest.approx(12.345678, abs=1e-6)
    assert (back.width, back.height, back.camera) == (32, 24, 0)


def test_wrong_byte_count_and_repr_text_are_errors() -> None:
    arr = frame_to_naoqi(Frame(_rgb(), 11, 0.0, 0, (0, 0, 0, 0)))
    arr[6] = arr[6][:-1]
    with pytest.raises(RobotError, match="bytes"):
        frame_from_naoqi(arr)
    arr[6] = "b'\\xff\\x00'"
    with pytest.raises(RobotError, match="qi.Buffer"):
        frame_from_naoqi(arr)
    with pytest.raises(RobotError, match="no image"):
        frame_from_naoqi(None)  # type: ignore[arg-type]
