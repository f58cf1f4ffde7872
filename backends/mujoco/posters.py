"""Poster and surface images for the simulated room: procedural from a seed, or photographs.

Procedural posters are unique and rich in visual features (gradients, filled and outlined
shapes, lines, text, fine noise), so A-KAZE finds plenty of keypoints on each of them;
walls and floor get low-contrast textures that yield few keypoints, like painted walls.
Every image is ``(height, width, 3)`` uint8 RGB with row 0 at the top.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from naoloc.errors import ConfigError

_WORDS = (
    "ROBOT", "NAO", "ROOM", "MAP", "VISION", "NEURAL", "CELL", "GROW", "LAB", "EXIT",
    "WELCOME", "SCIENCE", "2024", "HOME", "WALK", "LOOK", "POSTER", "ART", "DATA", "PLAN",
    "NORTH", "SOUTH", "EAST", "WEST", "LIGHT", "COLOR", "SHAPE", "TEXT", "FEATURE", "KAZE",
)  # fmt: skip
_FONTS = (
    cv2.FONT_HERSHEY_SIMPLEX,
    cv2.FONT_HERSHEY_DUPLEX,
    cv2.FONT_HERSHEY_COMPLEX,
    cv2.FONT_HERSHEY_TRIPLEX,
    cv2.FONT_HERSHEY_SCRIPT_SIMPLEX,
)
_PHOTO_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".webp")


def _color(rng: np.random.Generator) -> tuple[int, int, int]:
    c = rng.integers(0, 256, 3)
    return (int(c[0]), int(c[1]), int(c[2]))


def procedural_poster(width: int, height: int, rng: np.random.Generator) -> np.ndarray:
    """Draw one unique feature-rich poster.

    Args:
        width: Image width in pixels.
        height: Image height in pixels.
        rng: The random generator that makes this poster unique.

    Returns:
        ``(height, width, 3)`` uint8 RGB image.
    """
    # Background: a linear gradient between two random colours in a random direction.
    c0 = rng.uniform(0, 255, 3).astype(np.float32)
    c1 = rng.uniform(0, 255, 3).astype(np.float32)
    ang = rng.uniform(0, 2 * np.pi)
    corners = np.empty((2, 2, 3), np.float32)
    for j in range(2):
        for i in range(2):
            t = min(1.0, max(0.0, 0.5 + (np.cos(ang) * (i - 0.5) + np.sin(ang) * (j - 0.5))))
            corners[j, i] = c0 + (c1 - c0) * np.float32(t)
    gradient = cv2.resize(corners, (width, height), interpolation=cv2.INTER_LINEAR)
    img = np.ascontiguousarray(np.clip(gradient, 0, 255).astype(np.uint8))
    scale = min(width, height)
    # Filled shapes.
    for _ in range(int(rng.integers(8, 16))):
        kind = int(rng.integers(0, 4))
        center = (int(rng.integers(0, width)), int(rng.integers(0, height)))
        size = int(rng.uniform(0.04, 0.22) * scale)
        thick = -1 if rng.random() < 0.6 else int(rng.integers(2, 6))
        color = _color(rng)
        if kind == 0:
            cv2.circle(img, center, size, color, thick, cv2.LINE_AA)
        elif kind == 1:
            p2 = (center[0] + size, center[1] + int(size * rng.uniform(0.4, 1.6)))
            cv2.rectangle(img, center, p2, color, thick, cv2.LINE_AA)
        elif kind == 2:
            n = int(rng.integers(3, 7))
            pts = np.array(center) + rng.normal(0, size, (n, 2))
            cv2.fillPoly(img, [pts.astype(np.int32)], color, cv2.LINE_AA)
        else:
            axes = (size, max(2, int(size * rng.uniform(0.3, 1.0))))
            cv2.ellipse(
                img, center, axes, float(rng.uniform(0, 180)), 0, 360, color, thick, cv2.LINE_AA
            )
    # Lines and stripes.
    for _ in range(int(rng.integers(4, 10))):
        p1 = (int(rng.integers(0, width)), int(rng.integers(0, height)))
        p2 = (int(rng.integers(0, width)), int(rng.integers(0, height)))
        cv2.line(img, p1, p2, _color(rng), int(rng.integers(1, 5)), cv2.LINE_AA)
    # Text: a title and a few smaller words.
    for i in range(int(rng.integers(3, 6))):
        word = _WORDS[int(rng.integers(0, len(_WORDS)))]
        font = _FONTS[int(rng.integers(0, len(_FONTS)))]
        fscale = scale / 512.0 * (rng.uniform(1.6, 2.6) if i == 0 else rng.uniform(0.7, 1.4))
        thick = max(1, int(fscale * 2.2))
        (tw, th), _ = cv2.getTextSize(word, font, fscale, thick)
        x = int(rng.integers(0, max(1, width - tw)))
        y = int(rng.integers(th + 2, max(th + 3, height - 2)))
        cv2.putText(img, word, (x, y), font, fscale, _color(rng), thick, cv2.LINE_AA)
    # A checker or dot pattern patch: strong corners.
    cell = max(4, int(scale * rng.uniform(0.02, 0.05)))
    pw, ph = int(rng.integers(3, 7)) * cell, int(rng.integers(3, 7)) * cell
    x0, y0 = int(rng.integers(0, max(1, width - pw))), int(rng.integers(0, max(1, height - ph)))
    ca, cb = _color(rng), _color(rng)
    for j in range(ph // cell):
        for i in range(pw // cell):
            col = ca if (i + j) % 2 == 0 else cb
            p1 = (x0 + i * cell, y0 + j * cell)
            cv2.rectangle(img, p1, (p1[0] + cell - 1, p1[1] + cell - 1), col, -1)
    # A frame, then fine noise (like print texture).
    cv2.rectangle(img, (0, 0), (width - 1, height - 1), _color(rng), max(2, scale // 64))
    noise = rng.integers(-10, 11, img.shape, dtype=np.int16)  # uniform, std about 6
    return cv2.add(img, noise, dtype=cv2.CV_8U)


def photo_posters(folder: str, count: int, size: tuple[int, int], seed: int) -> list[np.ndarray]:
    """Load ``count`` posters from a folder of photographs (reused in a seeded order if few).

    Args:
        folder: Directory with .png/.jpg/.jpeg/.bmp/.webp files.
        count: Number of posters wanted.
        size: ``(width, height)`` of each returned image in pixels.
        seed: Seed of the order in which photographs are assigned.

    Returns:
        ``count`` RGB images of the given size.

    Raises:
        ConfigError: When the folder is missing, empty or holds an unreadable image.
    """
    path = Path(folder)
    if not path.is_dir():
        raise ConfigError(f"world.room.poster_dir: {folder} is not a directory")
    files = sorted(p for p in path.iterdir() if p.suffix.lower() in _PHOTO_SUFFIXES)
    if not files:
        raise ConfigError(
            f"world.room.poster_dir: no images ({', '.join(_PHOTO_SUFFIXES)}) in {folder}"
        )
    order = np.random.default_rng(seed).permutation(max(count, len(files))) % len(files)
    out = []
    for k in order[:count]:
        bgr = cv2.imread(str(files[int(k)]), cv2.IMREAD_COLOR)
        if bgr is None:
            raise ConfigError(f"world.room.poster_dir: cannot read image {files[int(k)]}")
        out.append(cv2.resize(bgr, size, interpolation=cv2.INTER_AREA)[..., ::-1].copy())
    return out


def plaster_texture(size: int, base_rgb: tuple[int, int, int], seed: int) -> np.ndarray:
    """A painted-wall texture: a flat colour with soft low-contrast blotches.

    Args:
        size: Side of the square texture in pixels.
        base_rgb: Paint colour, 0-255.
        seed: Seed of the blotches.

    Returns:
        ``(size, size, 3)`` uint8 RGB image.
    """
    rng = np.random.default_rng(seed)
    noise: np.ndarray = rng.normal(0, 1, (size // 16, size // 16)).astype(np.float32)
    noise = cv2.resize(noise, (size, size), interpolation=cv2.INTER_CUBIC)
    noise = cv2.GaussianBlur(noise, (0, 0), size / 32)
    noise = noise * (4.0 / max(1e-6, float(noise.std())))
    img = np.array(base_rgb, np.float32)[None, None, :] + noise[..., None]
    return np.clip(img, 0, 255).astype(np.uint8)


def floor_texture(size: int, seed: int) -> np.ndarray:
    """A parquet floor: planks of slightly different wood tones with soft grain.

    Args:
        size: Side of the square texture in pixels (covers 1 m x 1 m of floor).
        seed: Seed of the tones and grain.

    Returns:
        ``(size, size, 3)`` uint8 RGB image.
    """
    rng = np.random.default_rng(seed)
    planks = 4
    img = np.zeros((size, size, 3), np.float32)
    width = size // planks
    for i in range(planks):
        tone = np.array([150, 110, 70], np.float32) * rng.uniform(0.85, 1.1)
        img[:, i * width : (i + 1) * width] = tone
        img[:, i * width : i * width + 2] *= 0.8  # the gap between planks
    grain: np.ndarray = rng.normal(0, 1, (size, size // 8)).astype(np.float32)
    grain = cv2.resize(grain, (size, size), interpolation=cv2.INTER_LINEAR)
    grain = cv2.GaussianBlur(grain, (0, 0), 2.0)
    img += 6.0 * grain[..., None]
    return np.clip(img, 0, 255).astype(np.uint8)
