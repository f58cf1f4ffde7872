"""Conformance: ALVideoDevice semantics (image array layout, handles, metadata)."""

from __future__ import annotations

from types import ModuleType

import numpy as np
import pytest

from naoloc.constants import (
    COLORSPACE_LAYERS,
    COLORSPACE_NAMES,
    RESOLUTION_NAMES,
    RESOLUTIONS,
    kQQVGA,
    kQVGA,
    kRGBColorSpace,
    kTopCamera,
    kVGA,
)
from naoloc.errors import HandleError, RobotError
from naoloc.image import frame_from_naoqi
from naoloc.robot import Robot

DEFAULT_RESOLUTIONS = (kQQVGA, kQVGA, kVGA)
DEFAULT_COLORSPACES = tuple(sorted(COLORSPACE_LAYERS))


def _claimed(factory: ModuleType) -> list[tuple[int, int]]:
    resolutions = getattr(factory, "RESOLUTIONS", DEFAULT_RESOLUTIONS)
    colorspaces = getattr(factory, "COLORSPACES", DEFAULT_COLORSPACES)
    return [(r, c) for r in resolutions for c in colorspaces]


def test_image_array_for_every_claimed_format(robot: Robot, factory: ModuleType) -> None:
    hfov = robot.video.getHorizontalFOV(kTopCamera)
    vfov = robot.video.getVerticalFOV(kTopCamera)
    assert 0.6 < hfov < 1.3 and 0.5 < vfov < hfov, (hfov, vfov)
    for resolution, colorspace in _claimed(factory):
        what = f"{RESOLUTION_NAMES[resolution]}/{COLORSPACE_NAMES[colorspace]}"
        handle = robot.video.subscribeCamera("conf", kTopCamera, resolution, colorspace, 30)
        try:
            value = robot.video.getImageRemote(handle)
        finally:
            assert robot.video.unsubscribe(handle) is True, what
        width, height = RESOLUTIONS[resolution]
        layers = COLORSPACE_LAYERS[colorspace]
        assert len(value) == 12, what
        assert [int(v) for v in value[:4]] == [width, height, layers, colorspace], what
        assert int(value[4]) >= 0 and 0 <= int(value[5]) < 1_000_000, what
        assert isinstance(value[6], bytes | bytearray | str), what
        assert len(value[6]) == width * height * layers, what
        assert int(value[7]) == kTopCamera, what
        left, top, right, bottom = (float(v) for v in value[8:12])
        assert left == pytest.approx(hfov / 2, abs=0.02) and right == pytest.approx(-left), what
        assert top == pytest.approx(vfov / 2, abs=0.02) and bottom == pytest.approx(-top), what
        frame = frame_from_naoqi(value)
        assert frame.pixels.shape == (height, width, layers), what
        if width >= 160:
            assert float(np.std(frame.gray())) > 5.0, f"{what}: a blank image"


def test_subscription_metadata_and_unique_handles(robot: Robot) -> None:
    video = robot.video
    first = video.subscribeCamera("conf", kTopCamera, kQVGA, kRGBColorSpace, 15)
    second = video.subscribeCamera("conf", kTopCamera, kQQVGA, kRGBColorSpace, 15)
    try:
        assert isinstance(first, str) and isinstance(second, str)
        assert first != second
        assert video.getResolution(first) == kQVGA
        assert video.getResolution(second) == kQQVGA
        assert video.getColorSpace(first) == kRGBColorSpace
        early = frame_from_naoqi(video.getImageRemote(first))
        late = frame_from_naoqi(video.getImageRemote(first))
        assert late.stamp >= early.stamp
    finally:
        video.unsubscribe(first)
        video.unsubscribe(second)


def test_unknown_and_unsubscribed_handles_raise_naming_the_handle(robot: Robot) -> None:
    video = robot.video
    with pytest.raises(RobotError, match="no-such-handle"):
        video.getImageRemote("no-such-handle")
    handle = video.subscribeCamera("conf_gone", kTopCamera, kQQVGA, kRGBColorSpace, 30)
    assert video.unsubscribe(handle) is True
    with pytest.raises(RobotError, match=handle) as info:
        video.getImageRemote(handle)
    assert isinstance(info.value, HandleError | RobotError)
    assert video.unsubscribe(handle) is False
