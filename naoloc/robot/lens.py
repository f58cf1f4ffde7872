"""A camera's lens: focal length, principal point and radial distortion.

NAO's top camera, calibrated at VGA (a naoqi_driver calibration file), has a focal length
of about 557 px, its principal point at about (309, 231) and a radial distortion k1 of
about -0.055: a straight floor-wall line bows, and points near the image's edge sit up to
about 8 px (VGA) nearer the centre than a pinhole would put them. :data:`NAO_LENS` is that
calibration; the simulator's ``nao`` camera profile images through it and naoloc undoes it
(floor lines, keypoints) wherever pixels become rays. :func:`lens_for` picks the lens a
config's camera has: NAO's when the world's camera realism has lens distortion (the
default, and a real NAO), none (an ideal pinhole) when it is off.

Pixel coordinates follow OpenCV's keypoint convention: the centre of pixel column ``i`` is
at ``u = i``. Parameters are stored at VGA (640 x 480) and scaled to any resolution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

VGA = (640, 480)
_ITERATIONS = 6


@dataclass(frozen=True)
class Lens:
    """A radially distorted pinhole: ``x_d = x_u (1 + k1 (x_u^2 + y_u^2))``.

    Attributes:
        fx: Focal length along x at VGA, px.
        fy: Focal length along y at VGA, px.
        cx: Principal point column at VGA, px (OpenCV convention).
        cy: Principal point row at VGA, px.
        k1: Radial distortion coefficient (normalized image coordinates).
    """

    fx: float
    fy: float
    cx: float
    cy: float
    k1: float

    def at(self, width: int, height: int) -> tuple[float, float, float, float]:
        """``(fx, fy, cx, cy)`` in px at ``width x height`` (the sensor is binned, not cropped)."""
        sx, sy = width / VGA[0], height / VGA[1]
        return (
            self.fx * sx,
            self.fy * sy,
            self.cx * sx + (sx - 1.0) / 2.0,
            self.cy * sy + (sy - 1.0) / 2.0,
        )

    def normalized(
        self, u: np.ndarray, v: np.ndarray, width: int, height: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """Undistorted normalized coordinates ``(x, y)`` (x right, y down) of pixels ``(u, v)``."""
        fx, fy, cx, cy = self.at(width, height)
        xd = (np.asarray(u, np.float64) - cx) / fx
        yd = (np.asarray(v, np.float64) - cy) / fy
        if self.k1 == 0.0:
            return xd, yd
        xu, yu = xd, yd
        for _ in range(_ITERATIONS):  # invert x_d = x_u (1 + k1 r_u^2) by fixed-point iteration
            f = 1.0 + self.k1 * (xu * xu + yu * yu)
            xu, yu = xd / f, yd / f
        return xu, yu

    def to_pinhole(
        self, xy: np.ndarray, width: int, height: int, hfov: float, vfov: float
    ) -> np.ndarray:
        """Pixels ``(n, 2)`` moved to where an ideal pinhole of ``hfov x vfov`` (principal point
        at the image centre, as :class:`naoloc.robot.keyframe.CameraInfo` models it) sees them."""
        pts = np.asarray(xy, np.float64).reshape(-1, 2)
        if self == pinhole_lens(hfov, vfov):
            return pts.astype(np.float32)
        x, y = self.normalized(pts[:, 0], pts[:, 1], width, height)
        fx = (width / 2.0) / math.tan(hfov / 2.0)
        fy = (height / 2.0) / math.tan(vfov / 2.0)
        return np.stack([fx * x + width / 2.0, fy * y + height / 2.0], axis=1).astype(np.float32)

    def to_dict(self) -> dict[str, float]:
        """JSON-able parameters (VGA)."""
        return {"fx": self.fx, "fy": self.fy, "cx": self.cx, "cy": self.cy, "k1": self.k1}

    @classmethod
    def from_dict(cls, value: Any) -> Lens | None:
        """The lens of :meth:`to_dict`, or None when ``value`` is not a valid one."""
        if not isinstance(value, dict):
            return None
        try:
            fx, fy, cx, cy, k1 = (float(value[k]) for k in ("fx", "fy", "cx", "cy", "k1"))
        except (KeyError, TypeError, ValueError):
            return None
        if not all(math.isfinite(a) for a in (fx, fy, cx, cy, k1)):
            return None
        if not (10.0 < fx < 1e5 and 10.0 < fy < 1e5 and abs(k1) < 1.0):
            return None
        if not (0.0 <= cx <= VGA[0] and 0.0 <= cy <= VGA[1]):
            return None
        return cls(fx, fy, cx, cy, k1)


#: NAO's calibrated top camera at VGA (naoqi_driver's calibration file).
NAO_LENS = Lens(557.0, 557.0, 309.0, 231.0, -0.055)


def pinhole_lens(hfov: float, vfov: float) -> Lens:
    """The ideal pinhole of a field of view (principal point at the image centre)."""
    return Lens(
        (VGA[0] / 2.0) / math.tan(hfov / 2.0),
        (VGA[1] / 2.0) / math.tan(vfov / 2.0),
        (VGA[0] - 1) / 2.0,  # the image centre in OpenCV's pixel convention
        (VGA[1] - 1) / 2.0,
        0.0,
    )


def render_fov(lens: Lens, margin: float = 1.01) -> tuple[float, float]:
    """The symmetric pinhole field of view (rad) a simulator renders so that every pixel of
    ``lens`` samples inside the render (with a relative ``margin``)."""
    u = np.array([0.0, VGA[0] - 1.0, 0.0, VGA[0] - 1.0, lens.cx, lens.cx, 0.0, VGA[0] - 1.0])
    v = np.array([0.0, 0.0, VGA[1] - 1.0, VGA[1] - 1.0, 0.0, VGA[1] - 1.0, lens.cy, lens.cy])
    x, y = lens.normalized(u, v, *VGA)
    # pixel edges, not centres: half a pixel further out
    half_x = float(np.max(np.abs(x))) + 0.5 / lens.fx
    half_y = float(np.max(np.abs(y))) + 0.5 / lens.fy
    return 2.0 * math.atan(half_x * margin), 2.0 * math.atan(half_y * margin)


def lens_for(distortion: bool, hfov: float, vfov: float) -> Lens:
    """The lens of a camera: NAO's calibration when the camera distorts, else a pinhole.

    Args:
        distortion: Whether the camera has NAO's lens (a real NAO, the simulator's ``nao``
            camera profile) or is an ideal pinhole (the ``ideal`` profile).
        hfov: The camera's nominal horizontal field of view (rad), for the pinhole.
        vfov: Its vertical field of view (rad).
    """
    return NAO_LENS if distortion else pinhole_lens(hfov, vfov)
