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
        self._x0 = np.array([r.x0 for r in regions], np.float32)
        self._y0 = np.array([r.y0 for r in regions], np.float32)
        self._w = np.array([r.width for r in regions], np.float32)
        self._h = np.array([r.height for r in regions], np.float32)
        self._ppm = np.array([r.ppm for r in regions], np.float32)
        sx, sy = self._size
        # u = ua * x + ub * y + uc per surface (south, east, north, west, floor, ceiling).
        self._ua = np.array([-1, 0, 1, 0, 1, 1], np.float32)
        self._ub = np.array([0, -1, 0, 1, 0, 0], np.float32)
        self._uc = np.array([sx, sy, 0, 0, 0, 0], np.float32)
        self._rays: dict[tuple[int, int, float, float], tuple[np.ndarray, np.ndarray]] = {}
        # (3, N) ray directions (optical frame, z = 1) and their norms, per image size and FOV

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
            dirs = np.stack([uu.ravel(), vv.ravel(), np.ones(uu.size)]).astype(np.float32)
            self._rays[key] = (dirs, np.linalg.norm(dirs, axis=0))
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
        dirs, dnorm = self._camera_rays(width, height, hfov, vfov)
        focal = 0.5 * ((width / 2.0) / math.tan(hfov / 2.0) + (height / 2.0) / math.tan(vfov / 2.0))
        sx, sy = self._size
        sz = self._height
        origin = cam_in_room[:3, 3]
        ox = min(max(float(origin[0]), 1e-4), sx - 1e-4)
        oy = min(max(float(origin[1]), 1e-4), sy - 1e-4)
        oz = min(max(float(origin[2]), 1e-4), sz - 1e-4)
        dx, dy, dz = cam_in_room[:3, :3].astype(np.float32) @ dirs  # room-frame directions
        with np.errstate(divide="ignore", invalid="ignore"):
            # Distance (in ray units) to the wall each ray points at, per axis (+inf if parallel).
            tx = np.where(dx > 0, np.float32(sx - ox), np.float32(-ox)) / dx
            ty = np.where(dy > 0, np.float32(sy - oy), np.float32(-oy)) / dy
            tz = np.where(dz > 0, np.float32(sz - oz), np.float32(-oz)) / dz
        tx[~np.isfinite(tx) | (tx < 0)] = np.inf
        ty[~np.isfinite(ty) | (ty < 0)] = np.inf
        tz[~np.isfinite(tz) | (tz < 0)] = np.inf
        t = np.minimum(np.minimum(tx, ty), tz)
        hit_x = tx <= t
        hit_y = ~hit_x & (ty <= t)
        hit_wall = hit_x | hit_y
        surf = np.where(
            hit_x,
            np.where(dx > 0, 1, 3),
            np.where(hit_y, np.where(dy > 0, 2, 0), np.where(dz > 0, 5, 4)),
        ).astype(np.intp)
        px, py = ox + t * dx, oy + t * dy
        # Texture coordinates (metres): u to the right seen from inside, v down from the top;
        # u = A px + B py + C per surface, v = sz - pz on walls and py on floor and ceiling.
        u = self._ua[surf] * px + self._ub[surf] * py + self._uc[surf]
        v = np.where(hit_wall, sz - (oz + t * dz), py)
        ppm = self._ppm[surf]
        tu = np.clip(u * ppm - 0.5, 0, self._w[surf] - 1) + self._x0[surf]
        tv = np.clip(v * ppm - 0.5, 0, self._h[surf] - 1) + self._y0[surf]
        # Pixel footprint on the surface in texels: distance / focal / cos(incidence), the mip
        # level is its log2 (trilinear: weight 1 - |level - l| for level l).
        comp = np.abs(np.where(hit_x, dx, np.where(hit_y, dy, dz)))
        cos_inc = np.maximum(comp / dnorm, 0.2)
        texels = t * dnorm * ppm / (focal * cos_inc)
        level = np.clip(np.log2(np.maximum(texels, 1e-6)), 0, MIP_LEVELS - 1)
        out = np.zeros((height * width, 3), np.float32)
        for lvl in range(int(level.min()), min(int(np.ceil(level.max())) + 1, MIP_LEVELS)):
            weight = np.maximum(1.0 - np.abs(level - lvl), 0.0)
            if not np.any(weight > 0):
                continue
            scale = np.float32(2.0**lvl)
            mx = ((tu + 0.5) / scale - 0.5).reshape(height, width)
            my = ((tv + 0.5) / scale - 0.5).reshape(height, width)
            img = cv2.remap(
                self._atlas.levels[lvl], mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
            )
            out += img.reshape(-1, 3) * (weight * _SHADE[surf])[:, None]
        return out.reshape(height, width, 3).clip(0, 255).astype(np.uint8)
