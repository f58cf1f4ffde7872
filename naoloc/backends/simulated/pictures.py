"""Pictures for simulated rooms' walls: real photographs, procedural paintings, frames.

Real photographs come from matplotlib's bundled sample data (``matplotlib.cbook.
get_sample_data``; matplotlib is a dependency): the portrait of Grace Hopper (a US Navy
photograph, public domain) and two elevation models (USGS and NOAA data, public domain)
drawn as shaded-relief maps, as prints of a landscape hang in homes and offices. They are
few, so rooms also use procedural pictures: landscapes, portraits and abstract paintings.
Every image is ``(height, width, 3)`` uint8 RGB with row 0 at the top. numpy, OpenCV and
matplotlib only.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np

#: OpenCV's Hershey fonts the simulated posters' and walls' text is drawn in.
FONTS = (
    cv2.FONT_HERSHEY_SIMPLEX,
    cv2.FONT_HERSHEY_DUPLEX,
    cv2.FONT_HERSHEY_COMPLEX,
    cv2.FONT_HERSHEY_TRIPLEX,
    cv2.FONT_HERSHEY_PLAIN,
)


@functools.lru_cache(maxsize=1)
def sample_photographs() -> tuple[np.ndarray, ...]:
    """The real photographs and maps matplotlib ships (empty if its sample data is missing)."""
    from matplotlib import cbook
    from matplotlib.colors import LightSource

    out: list[np.ndarray] = []
    try:
        bgr = cv2.imread(str(cbook.get_sample_data("grace_hopper.jpg", asfileobj=False)))
        if bgr is not None:
            out.append(np.ascontiguousarray(bgr[..., ::-1]))
        light = LightSource(azdeg=315, altdeg=45)
        import matplotlib as mpl

        for name, key, cmap in (
            ("jacksboro_fault_dem.npz", "elevation", "gist_earth"),
            ("topobathy.npz", "topo", "terrain"),
        ):
            with np.load(cbook.get_sample_data(name, asfileobj=False)) as data:
                z = np.asarray(data[key], np.float64)
            rgb = light.shade(z, cmap=mpl.colormaps[cmap], vert_exag=0.05, blend_mode="soft")
            img = (np.clip(rgb[..., :3], 0, 1) * 255).astype(np.uint8)
            out.append(
                cv2.resize(img, (img.shape[1] * 2, img.shape[0] * 2), interpolation=cv2.INTER_CUBIC)
            )
    except (OSError, ValueError, KeyError):  # a stripped matplotlib install
        pass
    return tuple(out)


def _blobs(rng: np.random.Generator, h: int, w: int, cell: int) -> np.ndarray:
    small = rng.uniform(0, 1, (max(2, h // cell + 2), max(2, w // cell + 2))).astype(np.float32)
    return cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)


def landscape(rng: np.random.Generator, width: int, height: int) -> np.ndarray:
    """A painted landscape: sky gradient, clouds, layered hills, a few trees."""
    top = rng.uniform([90, 140, 190], [150, 190, 240])
    bottom = rng.uniform([190, 200, 210], [240, 235, 230])
    t = np.linspace(0, 1, height, dtype=np.float32)[:, None, None]
    img = np.broadcast_to(top + (bottom - top) * t, (height, width, 3)).astype(np.float32)
    clouds = np.clip(_blobs(rng, height, width, max(4, width // 8)) - 0.55, 0, 1) * 2.0
    img = (img + (255 - img) * clouds[..., None] * (1 - t)).astype(np.float32)
    xs = np.arange(width)
    for layer in range(int(rng.integers(2, 5))):
        base = height * (0.45 + 0.12 * layer + rng.uniform(-0.05, 0.05))
        ridge = base + height * 0.08 * np.cumsum(rng.normal(0, 0.15, width)) / np.sqrt(width / 20)
        ridge = cv2.GaussianBlur(ridge.reshape(1, -1).astype(np.float32), (0, 0), width / 60)[0]
        colour = np.array([60, 110, 60]) * rng.uniform(0.5, 1.3) * (0.7 + 0.1 * layer)
        mask = np.arange(height)[:, None] > ridge[None, xs]
        img[mask] = np.clip(colour, 0, 255)
    img = np.ascontiguousarray(np.clip(img, 0, 255).astype(np.uint8))
    for _ in range(int(rng.integers(1, 4))):  # houses: walls, roofs, windows (corners)
        hw = max(6, int(width * rng.uniform(0.08, 0.18)))
        x, y = int(rng.integers(0, max(1, width - hw))), int(height * rng.uniform(0.65, 0.9))
        wall = tuple(int(c) for c in rng.uniform(150, 245, 3))
        cv2.rectangle(img, (x, y - hw), (x + hw, y), wall, -1)
        roof = np.array(
            [[x - hw // 8, y - hw], [x + hw + hw // 8, y - hw], [x + hw // 2, y - 3 * hw // 2]]
        )
        cv2.fillPoly(img, [roof.astype(np.int32)], (int(rng.integers(90, 170)), 50, 40))
        for k in range(3):
            wx = x + hw // 8 + k * hw // 3
            cv2.rectangle(img, (wx, y - 3 * hw // 4), (wx + hw // 6, y - hw // 2), (40, 50, 70), -1)
    for _ in range(int(rng.integers(4, 12))):  # trees
        x, y = int(rng.integers(0, width)), int(height * rng.uniform(0.6, 0.95))
        r = max(2, int(width * rng.uniform(0.02, 0.05)))
        cv2.line(img, (x, y), (x, y - 2 * r), (70, 50, 30), max(1, r // 3))
        leaf = rng.uniform(20, 110, 3)
        for _ in range(5):
            c = (x + int(rng.integers(-r, r + 1)), y - 2 * r + int(rng.integers(-r, r + 1)))
            cv2.circle(
                img, c, max(2, r * 2 // 3), tuple(int(v) for v in leaf * rng.uniform(0.7, 1.3)), -1
            )
    grass = (rng.normal(0, 14, (height, width)) * (t[..., 0] > 0.6))[..., None]
    noise = rng.normal(0, 4, img.shape) + grass
    return np.clip(img + noise, 0, 255).astype(np.uint8)


def portrait(rng: np.random.Generator, width: int, height: int) -> np.ndarray:
    """A painted portrait: dark background, shoulders, a face with eyes and hair."""
    bg = rng.uniform(20, 90, 3)
    img = np.full((height, width, 3), bg, np.float32)
    img *= (0.7 + 0.6 * _blobs(rng, height, width, max(4, width // 4)))[..., None]
    img = np.ascontiguousarray(np.clip(img, 0, 255).astype(np.uint8))
    cx, s = width // 2, min(width, height)
    stripe = max(3, int(s * rng.uniform(0.04, 0.09)))
    tone = tuple(int(c) for c in np.clip(bg * 1.6 + 20, 0, 255))
    for x in range(0, width, 2 * stripe):  # wallpaper behind the sitter
        cv2.line(img, (x, 0), (x, height), tone, max(1, stripe // 3))
    for _ in range(int(rng.integers(3, 7))):  # a few ornaments
        c = (int(rng.integers(0, width)), int(rng.integers(0, height // 2)))
        cv2.circle(img, c, max(2, s // 25), tuple(int(v) for v in rng.uniform(80, 230, 3)), -1)
    cloth = tuple(int(c) for c in rng.uniform(10, 160, 3))
    cv2.ellipse(img, (cx, height), (int(0.45 * width), int(0.3 * height)), 0, 180, 360, cloth, -1)
    skin = tuple(int(c) for c in np.array([225, 180, 150]) * rng.uniform(0.45, 1.0))
    fy = int(0.42 * height)
    cv2.ellipse(img, (cx, fy), (int(0.17 * s), int(0.23 * s)), 0, 0, 360, skin, -1, cv2.LINE_AA)
    hair = tuple(int(c) for c in rng.uniform(10, 120, 3))
    cv2.ellipse(
        img,
        (cx, fy - int(0.08 * s)),
        (int(0.19 * s), int(0.18 * s)),
        0,
        180,
        360,
        hair,
        -1,
        cv2.LINE_AA,
    )
    for side in (-1, 1):
        eye = (cx + side * int(0.07 * s), fy - int(0.02 * s))
        cv2.circle(img, eye, max(1, int(0.018 * s)), (30, 25, 20), -1, cv2.LINE_AA)
    cv2.ellipse(
        img,
        (cx, fy + int(0.1 * s)),
        (int(0.05 * s), int(0.015 * s)),
        0,
        0,
        180,
        (120, 50, 50),
        max(1, s // 150),
        cv2.LINE_AA,
    )
    for k in range(3):  # buttons and a collar
        cv2.circle(
            img, (cx, int(0.75 * height) + k * s // 14), max(1, s // 60), (230, 220, 200), -1
        )
    blurred = cv2.GaussianBlur(img, (0, 0), max(0.5, s / 500))
    return np.clip(blurred + rng.normal(0, 3, blurred.shape), 0, 255).astype(np.uint8)


def framed(image: np.ndarray, rng: np.random.Generator, width: int, height: int) -> np.ndarray:
    """A picture resized into a frame (wood, black or white) with an optional mat."""
    kind = int(rng.integers(0, 3))
    frame = [(110, 75, 45), (25, 25, 25), (235, 235, 230)][kind]
    border = max(2, int(0.05 * min(width, height)))
    mat = max(0, int(rng.uniform(0.0, 0.12) * min(width, height)))
    out = np.empty((height, width, 3), np.uint8)
    out[:] = frame
    inner = out[border : height - border, border : width - border]
    inner[:] = (240, 238, 230)
    pic = inner[mat : inner.shape[0] - mat, mat : inner.shape[1] - mat]
    ph, pw = pic.shape[:2]
    if ph > 2 and pw > 2:
        pic[:] = cv2.resize(image, (pw, ph), interpolation=cv2.INTER_AREA)
    return out
