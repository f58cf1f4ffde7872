"""``vision_definitions`` of the old NAOqi Python SDK: camera, resolution, colour space ids."""

from __future__ import annotations

from naoloc.constants import (
    kBGRColorSpace,
    kBottomCamera,
    kDepthCamera,
    kHSVColorSpace,
    kQQQQVGA,
    kQQQVGA,
    kQQVGA,
    kQVGA,
    kRGBColorSpace,
    kTopCamera,
    kVGA,
    kYUV422ColorSpace,
    kYUVColorSpace,
    kYuvColorSpace,
)

__all__ = [
    "kBGRColorSpace", "kBottomCamera", "kDepthCamera", "kHSVColorSpace", "kQQQQVGA",
    "kQQQVGA", "kQQVGA", "kQVGA", "kRGBColorSpace", "kTopCamera", "kVGA",
    "kYUV422ColorSpace", "kYUVColorSpace", "kYuvColorSpace",
]  # fmt: skip
