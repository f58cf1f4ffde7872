"""Ray casting of a box room in numpy: four walls, floor and ceiling.

Each pixel's ray (pinhole camera, principal point at the image centre) is intersected
with the six planes of the room; the nearest hit picks the surface and its texture
coordinates. Textures are sampled bilinearly from the atlas mip level that matches the
pixel's footprint on the surface (trilinear between two levels), so far and grazing
walls do not alias into spurious keypoints.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from naoloc.backends.fake.textures import MIP_LEVELS, Atlas

# Brightness of each surface (south, east, north, west, floor, ceiling): a fixed light.
_SHADE = np.array([1.0, 0.92, 0.97, 0.88, 0.85, 0.97], np.float32)


class RoomRenderer:
    """Renders RGB images of a textured box room.

    Args:
        atlas: The room textures (see :func:`naoloc.backends.fake.textures.make_atlas`).
        size: Inner room size ``(x, y)`` in metres, room frame.
        wall_height: Wall height in metres.
    """

    def __init__(self, atlas: Atlas, size: tuple[float, float], wall_height: float) -> None:
        self._atlas = atlas
        self._size = (float(size[0]), float(size[1]))
        self._height = float(wall_height)
        regions = atlas.regions
        self._x0 = np.array([r.x0 for r in regions], np.float64)
        self._y0 = np.array([r.y0 for r in regions], np.float64)
        self._w = np.array([r.width for r in regions], np.float64)
        self._h = np.array([r.height for r in regions], np.float64)
        self._ppm = np.array([r.ppm for r in regions], np.float64)
        self._rays: dict[tuple[int, int, float, float], tuple[np.ndarray, np.ndarray]] = {}
        # ray directions (optical frame, z = 1) and their norms, per image size and FOV

    def _camera_rays(
        self, width: int, height: int, hfov: float, vfov: float
    ) -> tuple[np.ndarray, np.ndarray]:
        key = (width, height, hfov, vfov)
        if key not in self._rays:
            fx = (width / 2.0) / math.tan(hfov / 2.0)
            fy = (height / 2.0) / math.tan(vfov / 2.0)
            u = (np.arange(width) + 0.5 - width / 2.0) / fx
            v = (np.arange(height) + 0.5 - height / 2.0) / fy
            uu, vv = np.meshgrid(u, v)
            dirs = np.stack([uu.ravel(), vv.ravel(), np.ones(uu.size)], axis=1)
            self._rays[key] = (dirs, np.linalg.norm(dirs, axis=1))
        return self._rays[key]

    def render(
        self, cam_in_room: np.ndarray, width: int, height: int, hfov: float, vfov: float
    ) -> np.ndarray:
        """Render one image.

        Args:
            cam_in_room: 4x4 pose of the camera's optical frame (OpenCV: z forward, x right,
                y down) in the room frame, metres.
            width: Image width in pixels.
            height: Image height in pixels.
            hfov: Horizontal field of view in radians.
            vfov: Vertical field of view in radians.

        Returns:
            ``(height, width, 3)`` uint8 RGB image.
        """
        dirs_cam, dnorm = self._camera_rays(width, height, hfov, vfov)
        focal = 0.5 * ((width / 2.0) / math.tan(hfov / 2.0) + (height / 2.0) / math.tan(vfov / 2.0))
        rot = cam_in_room[:3, :3]
        origin = cam_in_room[:3, 3]
        sx, sy = self._size
        sz = self._height
        ox = min(max(origin[0], 1e-6), sx - 1e-6)
        oy = min(max(origin[1], 1e-6), sy - 1e-6)
        oz = min(max(origin[2], 1e-6), sz - 1e-6)
        d = dirs_cam @ rot.T
        dx, dy, dz = d[:, 0], d[:, 1], d[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            tx = np.where(dx > 0, (sx - ox) / dx, np.where(dx < 0, -ox / dx, np.inf))
            ty = np.where(dy > 0, (sy - oy) / dy, np.where(dy < 0, -oy / dy, np.inf))
            tz = np.where(dz > 0, (sz - oz) / dz, np.where(dz < 0, -oz / dz, np.inf))
        ts = np.stack([tx, ty, tz])
        axis = np.argmin(ts, axis=0)
        t = np.take_along_axis(ts, axis[None], axis=0)[0]
        px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
        surf = np.where(
            axis == 0,
            np.where(dx > 0, 1, 3),
            np.where(axis == 1, np.where(dy > 0, 2, 0), np.where(dz > 0, 5, 4)),
        )
        # Texture coordinates in metres: u to the right seen from inside, v down from the top.
        down = sz - pz
        u = np.select([surf == 0, surf == 1, surf == 2, surf == 3], [sx - px, sy - py, px, py], px)
        v = np.where(surf <= 3, down, py)
        ppm = self._ppm[surf]
        tu = np.clip(u * ppm - 0.5, 0, self._w[surf] - 1) + self._x0[surf]
        tv = np.clip(v * ppm - 0.5, 0, self._h[surf] - 1) + self._y0[surf]
        # Footprint of a pixel on the surface, in texels: distance * angle / cos(incidence).
        comp = np.choose(axis, [np.abs(dx), np.abs(dy), np.abs(dz)])
        cos_inc = np.maximum(comp / dnorm, 0.2)
        texels = t * dnorm / focal * ppm / cos_inc
        level = np.clip(np.log2(np.maximum(texels, 1e-6)), 0, MIP_LEVELS - 1)
        lo = np.floor(level).astype(np.int64)
        frac = (level - lo).astype(np.float32)
        out = np.zeros((height * width, 3), np.float32)
        for lvl in range(int(lo.min()), min(int(lo.max()) + 2, MIP_LEVELS)):
            weight = np.where(lo == lvl, 1.0 - frac, 0.0) + np.where(lo + 1 == lvl, frac, 0.0)
            if not np.any(weight > 0):
                continue
            scale = 2.0**lvl
            mx = ((tu + 0.5) / scale - 0.5).astype(np.float32).reshape(height, width)
            my = ((tv + 0.5) / scale - 0.5).astype(np.float32).reshape(height, width)
            img = cv2.remap(
                self._atlas.levels[lvl], mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
            )
            out += img.reshape(-1, 3).astype(np.float32) * weight[:, None].astype(np.float32)
        out *= _SHADE[surf][:, None]
        return out.reshape(height, width, 3).clip(0, 255).astype(np.uint8)


def apply_realism(
    rgb: np.ndarray,
    rng: np.random.Generator,
    noise_std: float,
    blur_px: float,
    exposure: float,
    jpeg_quality: int | None,
) -> np.ndarray:
    """Degrade a rendered image like a cheap camera: exposure, blur, noise, JPEG.

    Args:
        rgb: ``(h, w, 3)`` uint8 RGB.
        rng: Seeded generator for the pixel noise.
        noise_std: Gaussian noise standard deviation in 0-255 units (0 = off).
        blur_px: Gaussian blur sigma in pixels (0 = off).
        exposure: Brightness gain (1 = unchanged).
        jpeg_quality: JPEG round-trip quality 5-100, or None for none.

    Returns:
        The degraded ``(h, w, 3)`` uint8 RGB image.
    """
    img = rgb
    if exposure != 1.0:
        img = (img.astype(np.float32) * exposure).clip(0, 255).astype(np.uint8)
    if blur_px > 0:
        img = cv2.GaussianBlur(img, (0, 0), blur_px)
    if noise_std > 0:
        noisy = img.astype(np.float32) + rng.normal(0, noise_std, img.shape).astype(np.float32)
        img = noisy.clip(0, 255).astype(np.uint8)
    if jpeg_quality is not None:
        ok, buf = cv2.imencode(".jpg", img[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, jpeg_quality])
        decoded = cv2.imdecode(buf, cv2.IMREAD_COLOR) if ok else None
        if decoded is not None:
            img = np.ascontiguousarray(decoded[..., ::-1])
    return img
