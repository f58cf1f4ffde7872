"""Local features behind one interface: A-KAZE (default), ORB or SIFT.

A-KAZE and ORB give binary descriptors (uint8 bytes, compared by Hamming distance);
SIFT gives float32 descriptors (compared by Euclidean distance). An image without
keypoints yields empty arrays, never an error.

A-KAZE's threshold adapts: an image with fewer than ``min_keypoints`` keypoints (a blank
wall, a dim room) is described at the threshold divided by sqrt(10), again and again, down
to :data:`AKAZE_FLOOR`. In the default honest world the top camera's QVGA frames give a
median of 8 keypoints at OpenCV's default 0.001 and 106 at 0.0001 (docs/history/RESULTS.md). The
scale space does not depend on the threshold, so this is done in one pass: the image is
described once at the floor and the keypoints whose response exceeds the first threshold
of that ladder to keep ``min_keypoints`` are kept (the same keypoints and descriptors as a
pass per threshold for 41 of 43 survey images; the others differ by one keypoint; about
2.4x faster on the honest world's images, ``tools/bench_localize.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from naoloc.errors import DependencyNotInstalled, FeatureError
from naoloc.robot.lens import Lens

FEATURE_KINDS = ("akaze", "orb", "sift")
# Descriptor width in bytes (binary) or values (SIFT) per kind, OpenCV defaults.
DESCRIPTOR_WIDTH = {"akaze": 61, "orb": 32, "sift": 128}
AKAZE_FLOOR = 3e-5  # lowest adaptive A-KAZE threshold (below it, sensor noise is detected)
AKAZE_STEP = 10**0.5  # threshold divisor per retry


@dataclass(frozen=True, slots=True)
class Features:
    """Keypoints and descriptors of one image.

    Attributes:
        xy: ``(n, 2)`` float32 keypoint positions in pixels (x right, y down).
        descriptors: ``(n, d)`` uint8 (binary kinds) or float32 (SIFT) descriptors.
        response: ``(n,)`` float32 detector responses (larger is stronger).
    """

    xy: np.ndarray
    descriptors: np.ndarray
    response: np.ndarray

    def __len__(self) -> int:
        return int(self.xy.shape[0])


def empty_features(kind: str) -> Features:
    """A :class:`Features` with no keypoints for a feature kind."""
    dtype = np.float32 if kind == "sift" else np.uint8
    return Features(
        np.zeros((0, 2), np.float32),
        np.zeros((0, DESCRIPTOR_WIDTH[kind]), dtype),
        np.zeros((0,), np.float32),
    )


def to_pinhole(
    feats: Features, lens: Lens | None, width: int, height: int, hfov: float, vfov: float
) -> Features:
    """The features with their keypoints where an ideal pinhole of ``hfov x vfov`` sees them.

    The map and the localizer model cameras as pinholes (:class:`naoloc.robot.keyframe.CameraInfo`);
    keypoints found in a distorted image (NAO's lens) are moved there first.

    Args:
        feats: Features of a ``width x height`` image taken through ``lens``.
        lens: The camera's lens (None: the image is a pinhole's already).
        width: Image width, px.
        height: Image height, px.
        hfov: The pinhole's horizontal field of view, rad.
        vfov: Its vertical field of view, rad.
    """
    if lens is None or len(feats) == 0:
        return feats
    xy = lens.to_pinhole(feats.xy, width, height, hfov, vfov)
    return Features(xy, feats.descriptors, feats.response)


class FeatureExtractor:
    """Detect and describe keypoints with one OpenCV detector, built once.

    Args:
        kind: ``akaze``, ``orb`` or ``sift``.
        max_features: Keep at most this many keypoints (strongest first); 0 keeps all.
        akaze_threshold: A-KAZE detector threshold (OpenCV default 0.001).
        min_keypoints: A-KAZE only: describe an image again with a lower threshold while
            it has fewer keypoints than this (0: a fixed threshold).

    Raises:
        FeatureError: On an unknown kind.
        DependencyNotInstalled: When this OpenCV build lacks the detector (OpenCV 5).
    """

    def __init__(
        self,
        kind: str = "akaze",
        max_features: int = 0,
        akaze_threshold: float = 0.001,
        min_keypoints: int = 0,
    ):
        if kind not in FEATURE_KINDS:
            raise FeatureError(f"unknown feature kind {kind!r}; valid: {', '.join(FEATURE_KINDS)}")
        import cv2

        self.kind = kind
        self.max_features = int(max_features)
        self.akaze_threshold = float(akaze_threshold)
        self.min_keypoints = int(min_keypoints) if kind == "akaze" else 0
        self._floor: Any = None  # adaptive A-KAZE's detector at the floor, made once
        ladder, t = [self.akaze_threshold], self.akaze_threshold / AKAZE_STEP
        while t >= AKAZE_FLOOR * 0.999:
            ladder.append(t)
            t /= AKAZE_STEP
        self._thresholds = tuple(ladder)  # adaptive A-KAZE's thresholds, highest first
        self.binary = kind != "sift"
        if kind == "akaze":
            if not hasattr(cv2, "AKAZE_create"):
                raise DependencyNotInstalled(
                    "this OpenCV has no A-KAZE (OpenCV 5 moved it); "
                    "pip install 'opencv-python-headless==4.14.0.94'"
                )
            self._detector: Any = cv2.AKAZE_create(threshold=self.akaze_threshold)
        elif kind == "orb":
            self._detector = cv2.ORB_create(nfeatures=self.max_features or 500)  # type: ignore[attr-defined]
        else:
            self._detector = cv2.SIFT_create(nfeatures=self.max_features)  # type: ignore[attr-defined]

    def params(self) -> dict[str, Any]:
        """JSON-able parameters that reproduce this extractor."""
        return {
            "kind": self.kind,
            "max_features": self.max_features,
            "akaze_threshold": self.akaze_threshold,
            "min_keypoints": self.min_keypoints,
        }

    @property
    def thresholds(self) -> tuple[float, ...]:
        """Adaptive A-KAZE's thresholds, the configured one first, down to the floor."""
        return self._thresholds

    def _floor_detector(self) -> Any:
        """The detector that describes an image once: the ladder's lowest threshold."""
        if not self.min_keypoints:
            return self._detector
        if self._floor is None:
            import cv2

            self._floor = cv2.AKAZE_create(threshold=self._thresholds[-1])  # type: ignore[attr-defined]
        return self._floor

    def extract(self, gray: np.ndarray) -> Features:
        """Keypoints and descriptors of one grey image.

        Args:
            gray: ``(h, w)`` uint8 image (a BGR ``(h, w, 3)`` image is converted).

        Returns:
            The features; empty arrays when the image has no keypoints.

        Raises:
            FeatureError: When the image is not a 2-D or 3-channel uint8 array.
        """
        import cv2

        img = np.asarray(gray)
        if img.ndim == 3 and img.shape[2] == 3:
            img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
        if img.ndim != 2 or img.dtype != np.uint8 or min(img.shape) < 1:
            raise FeatureError(f"expected a 2-D uint8 image, got {img.dtype} {img.shape}")
        try:
            kps, desc = self._floor_detector().detectAndCompute(img, None)
        except cv2.error as err:
            raise FeatureError(f"{self.kind} extraction failed: {str(err).strip()[:120]}") from None
        if desc is None or not kps:
            return empty_features(self.kind)
        xy = np.array([kp.pt for kp in kps], dtype=np.float32).reshape(-1, 2)
        response = np.array([kp.response for kp in kps], dtype=np.float32)
        if self.min_keypoints:
            for t in self._thresholds[:-1]:  # the first threshold that keeps enough
                keep = np.flatnonzero(response > t)
                if keep.size >= self.min_keypoints:
                    xy, desc, response = xy[keep], desc[keep], response[keep]
                    break
        if self.max_features and len(kps) > self.max_features:
            keep = np.sort(np.argsort(-response, kind="stable")[: self.max_features])
            xy, desc, response = xy[keep], desc[keep], response[keep]
        dtype = np.uint8 if self.binary else np.float32
        return Features(xy, np.ascontiguousarray(desc, dtype=dtype), response)
