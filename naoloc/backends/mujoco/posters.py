"""Poster and surface images for the simulated room: procedural from a seed, or photographs.

Procedural posters are unique and rich in visual features (gradients, filled and outlined
shapes, lines, text, fine noise), so A-KAZE finds plenty of keypoints on each of them;
walls and floor get low-contrast textures that yield few keypoints, like painted walls.
Every image is ``(height, width, 3)`` uint8 RGB with row 0 at the top.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np

from naoloc.backends.simulated.pictures import FONTS
from naoloc.errors import ConfigError

_WORDS = (
    "ROBOT", "NAO", "ROOM", "MAP", "VISION", "NEURAL", "CELL", "GROW", "LAB", "EXIT",
    "WELCOME", "SCIENCE", "2024", "HOME", "WALK", "LOOK", "POSTER", "ART", "DATA", "PLAN",
    "NORTH", "SOUTH", "EAST", "WEST", "LIGHT", "COLOR", "SHAPE", "TEXT", "FEATURE", "KAZE",
)  # fmt: skip
_PHOTO_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".webp")


_LUMA = np.array([0.299, 0.587, 0.114])


def _luma(rgb: np.ndarray) -> float:
    return float(np.dot(np.asarray(rgb, np.float64), _LUMA))


def _color(rng: np.random.Generator, dark: bool | None = None) -> tuple[int, int, int]:
    """A random colour; ``dark`` True/False puts its luminance below 60 / above 175."""
    c = rng.uniform(0, 255, 3)
    if dark is not None:
        target = rng.uniform(5, 60) if dark else rng.uniform(175, 250)
        c = c * (target / max(1.0, _luma(c)))
        if c.max() > 255:  # too bright a hue for the target: blend toward white
            c = c / c.max() * 255
            c = c + (255 - c) * (target - _luma(c)) / max(1.0, 255 - _luma(c))
    c = np.clip(c, 0, 255)
    return (int(c[0]), int(c[1]), int(c[2]))


def _photo_patch(w: int, h: int, rng: np.random.Generator) -> np.ndarray:
    """Multi-scale noise that looks like a blurry photograph: many blobs of full contrast."""
    lum = np.zeros((h, w), np.float32)
    for cell, weight in ((40, 0.55), (14, 0.3), (5, 0.15)):
        small = rng.uniform(0, 1, (h // cell + 2, w // cell + 2)).astype(np.float32)
        lum += weight * cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)
    lum = (lum - float(lum.min())) / max(1e-6, float(lum.max() - lum.min()))
    tint_a = rng.uniform(0, 255, 3).astype(np.float32) * 0.3
    tint_b = rng.uniform(0, 255, 3).astype(np.float32) * 0.3 + 178
    out = tint_a + (tint_b - tint_a) * lum[..., None]
    return np.clip(out, 0, 255).astype(np.uint8)


def procedural_poster(width: int, height: int, rng: np.random.Generator) -> np.ndarray:
    """Draw one unique feature-rich poster.

    Content: a gradient, one or two photograph-like patches of multi-scale noise, a few
    dozen filled and outlined shapes in contrasting tones, a title and a block of small
    text, a checkerboard patch, a frame, and fine print noise.

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
    # Photograph-like patches.
    for _ in range(int(rng.integers(1, 3))):
        pw = int(width * rng.uniform(0.3, 0.55))
        ph = int(height * rng.uniform(0.25, 0.45))
        x0 = int(rng.integers(0, width - pw))
        y0 = int(rng.integers(0, height - ph))
        img[y0 : y0 + ph, x0 : x0 + pw] = _photo_patch(pw, ph, rng)
    # Shapes in contrasting tones.
    for _ in range(int(rng.integers(35, 60))):
        kind = int(rng.integers(0, 4))
        center = (int(rng.integers(0, width)), int(rng.integers(0, height)))
        size = max(3, int(rng.uniform(0.015, 0.1) * scale))
        thick = -1 if rng.random() < 0.7 else int(rng.integers(2, 5))
        under = img[min(center[1], height - 1), min(center[0], width - 1)]
        color = _color(rng, dark=_luma(under) > 120)  # contrast with what is below
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
    # Lines.
    for _ in range(int(rng.integers(3, 8))):
        p1 = (int(rng.integers(0, width)), int(rng.integers(0, height)))
        p2 = (int(rng.integers(0, width)), int(rng.integers(0, height)))
        cv2.line(img, p1, p2, _color(rng), int(rng.integers(2, 5)), cv2.LINE_AA)
    # A title and a block of small text.
    _text(img, rng, 1, scale / 512.0 * rng.uniform(1.6, 2.4))
    _text(img, rng, int(rng.integers(4, 8)), scale / 512.0 * rng.uniform(0.6, 0.9))
    # A checkerboard patch: strong corners.
    cell = max(4, int(scale * rng.uniform(0.02, 0.04)))
    pw, ph = int(rng.integers(4, 8)) * cell, int(rng.integers(3, 6)) * cell
    x0, y0 = int(rng.integers(0, max(1, width - pw))), int(rng.integers(0, max(1, height - ph)))
    ca, cb = _color(rng, dark=True), _color(rng, dark=False)
    for j in range(ph // cell):
        for i in range(pw // cell):
            col = ca if (i + j) % 2 == 0 else cb
            p1 = (x0 + i * cell, y0 + j * cell)
            cv2.rectangle(img, p1, (p1[0] + cell - 1, p1[1] + cell - 1), col, -1)
    # A frame, then fine noise (like print texture).
    cv2.rectangle(img, (0, 0), (width - 1, height - 1), _color(rng), max(2, scale // 64))
    noise = rng.integers(-10, 11, img.shape, dtype=np.int16)  # uniform, std about 6
    return cv2.add(img, noise, dtype=cv2.CV_8U)


def _text(img: np.ndarray, rng: np.random.Generator, lines: int, fscale: float) -> None:
    """Draw ``lines`` lines of random words in one colour that contrasts with the poster."""
    height, width = img.shape[:2]
    font = FONTS[int(rng.integers(0, len(FONTS) - 1))]  # the first four (not PLAIN)
    thick = max(1, int(fscale * 2.0))
    dark = _luma(img.reshape(-1, 3).mean(axis=0)) > 120
    color = _color(rng, dark=dark)
    (_, th), _ = cv2.getTextSize("Ag", font, fscale, thick)
    x = int(rng.integers(0, max(1, width // 3)))
    y = int(rng.integers(th + 2, max(th + 3, height - lines * (th + 6))))
    for _ in range(lines):
        words = [_WORDS[int(rng.integers(0, len(_WORDS)))] for _ in range(int(rng.integers(2, 5)))]
        cv2.putText(img, " ".join(words), (x, y), font, fscale, color, thick, cv2.LINE_AA)
        y += th + max(4, th // 2)


def photo_posters(folder: str, sizes: Sequence[tuple[int, int]], seed: int) -> list[np.ndarray]:
    """Posters from a folder of photographs: a seeded order, each used once before any repeats.

    Args:
        folder: Directory with .png/.jpg/.jpeg/.bmp/.webp files.
        sizes: ``(width, height)`` in pixels of each poster wanted.
        seed: Seed of the order in which photographs are assigned.

    Returns:
        One RGB image per size, resized to it.

    Raises:
        ConfigError: When the folder is missing, empty or holds an unreadable image.
    """
    path = Path(folder)
    if not path.is_dir():
        raise ConfigError(f"world.room.poster_dir: {folder} is not a directory")
    files = sorted(p for p in path.iterdir() if p.suffix.lower() in _PHOTO_SUFFIXES)
    if not files:
        kinds = ", ".join(_PHOTO_SUFFIXES)
        raise ConfigError(f"world.room.poster_dir: no images ({kinds}) in {folder}")
    order = np.random.default_rng(seed).permutation(len(files))
    out = []
    for i, size in enumerate(sizes):
        file = files[int(order[i % len(files)])]
        bgr = cv2.imread(str(file), cv2.IMREAD_COLOR)
        if bgr is None:
            raise ConfigError(f"world.room.poster_dir: cannot read image {file}")
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
