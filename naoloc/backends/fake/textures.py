"""Procedural, seeded room textures packed into one mip-mapped atlas.

``world.room.style: posters``: every wall is a plain painted surface with a skirting
board and ``posters_per_wall`` unique posters (gradients, filled shapes, stripes, checkers,
words drawn with ``cv2.putText``, fine noise) so that A-KAZE finds plenty of keypoints and different
places on the walls look different. ``home`` and ``office`` walls follow the MuJoCo rooms
in 2-D (:func:`make_furnished_wall`): art at 1.2-1.8 m above a band of skirting, sockets,
doors, radiators and blank wall. The floor carries mild tiles, the ceiling is
almost plain.

Surfaces (ids used by :mod:`naoloc.backends.fake.render`), room frame:
    0 south wall (y = 0), 1 east wall (x = size_x), 2 north wall (y = size_y),
    3 west wall (x = 0), 4 floor (z = 0), 5 ceiling (z = wall_height).

A wall texture is indexed by ``u`` (metres to the right as seen from inside the room)
and ``v`` (metres down from the top of the wall), so text is never mirrored.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from naoloc.backends.simulated.pictures import FONTS
from naoloc.config import RoomConfig
from naoloc.errors import BackendError

SURFACES = ("south", "east", "north", "west", "floor", "ceiling")
MIP_LEVELS = 4  # level l has 1 / 2**l of the resolution of level 0
_PAD = 2 ** (MIP_LEVELS + 1)  # replicated border around each region, pixels at level 0
_MAX_ATLAS_SIDE = 30000  # cv2.remap needs source images under 32767 pixels a side

_SYLLABLES = (
    "ka", "to", "mi", "ra", "ne", "su", "lo", "pe", "di", "vu", "bo", "ze", "ha", "qi",
    "nao", "lex", "tor", "min", "gra", "vel", "ost", "pri", "dun", "sal",
)  # fmt: skip


@dataclass(frozen=True, slots=True)
class Region:
    """Where one surface's texture lies in the level-0 atlas.

    Attributes:
        x0: Left column of the texture (excluding the padding), pixels.
        y0: Top row of the texture (excluding the padding), pixels.
        width: Texture width in pixels.
        height: Texture height in pixels.
        ppm: Texture resolution in pixels per metre.
    """

    x0: int
    y0: int
    width: int
    height: int
    ppm: float


@dataclass(frozen=True)
class Atlas:
    """All room textures in one RGB image per mip level.

    Attributes:
        levels: ``MIP_LEVELS`` uint8 RGB images; level ``l`` is level 0 reduced ``2**l`` times.
        regions: One :class:`Region` per surface, in the order of :data:`SURFACES`.
    """

    levels: tuple[np.ndarray, ...]
    regions: tuple[Region, ...]


def _random_colour(rng: np.random.Generator, sat: tuple[float, float], val: tuple[float, float]):
    hsv = np.array(
        [[[rng.uniform(0, 180), rng.uniform(*sat) * 255, rng.uniform(*val) * 255]]], np.float32
    )
    rgb = cv2.cvtColor(hsv.astype(np.uint8), cv2.COLOR_HSV2RGB)[0, 0]
    return tuple(int(c) for c in rgb)


def _smooth_noise(rng: np.random.Generator, h: int, w: int, cell_px: int) -> np.ndarray:
    """Low-frequency noise in [-1, 1], ``(h, w)`` float32."""
    small = rng.uniform(-1, 1, (max(2, h // cell_px + 2), max(2, w // cell_px + 2)))
    return cv2.resize(small.astype(np.float32), (w, h), interpolation=cv2.INTER_CUBIC)


def _word(rng: np.random.Generator) -> str:
    n = int(rng.integers(2, 4))
    word = "".join(_SYLLABLES[int(i)] for i in rng.integers(0, len(_SYLLABLES), n))
    if rng.random() < 0.4:
        word += str(int(rng.integers(1, 99)))
    return word.upper() if rng.random() < 0.5 else word.capitalize()


def _draw_text(rng: np.random.Generator, img: np.ndarray, top: int, bottom: int) -> None:
    w = img.shape[1]
    text = " ".join(_word(rng) for _ in range(int(rng.integers(1, 3))))
    font = FONTS[int(rng.integers(0, len(FONTS)))]
    thickness = max(1, int(rng.integers(1, 4)) * w // 200)
    (tw, th), _ = cv2.getTextSize(text, font, 1.0, thickness)
    scale = min(0.9 * w / max(tw, 1), 0.9 * (bottom - top) / max(th, 1))
    if scale <= 0.05:
        return
    (tw, th), _ = cv2.getTextSize(text, font, scale, thickness)
    x = int(rng.integers(0, max(1, w - tw)))
    y = top + th + int(rng.integers(0, max(1, bottom - top - th)))
    colour = _random_colour(rng, (0.3, 1.0), (0.0, 0.5))
    cv2.putText(img, text, (x, y), font, scale, colour, thickness, cv2.LINE_AA)


def _draw_shape(rng: np.random.Generator, img: np.ndarray, small: bool = False) -> None:
    h, w = img.shape[:2]
    colour = _random_colour(rng, (0.2, 1.0), (0.1, 1.0))
    rel = rng.uniform(0.012, 0.04) if small else rng.uniform(0.04, 0.25)
    size = int(rel * min(w, h)) + 2
    cx, cy = int(rng.integers(0, w)), int(rng.integers(0, h))
    kind = int(rng.integers(0, 6))
    if kind == 0:
        cv2.circle(img, (cx, cy), size, colour, -1, cv2.LINE_AA)
    elif kind == 1:
        cv2.rectangle(img, (cx - size, cy - size // 2), (cx + size, cy + size // 2), colour, -1)
    elif kind == 2:
        k = int(rng.integers(3, 7))
        ang = np.sort(rng.uniform(0, 2 * np.pi, k))
        rad = rng.uniform(0.4, 1.0, k) * size
        pts = np.stack([cx + rad * np.cos(ang), cy + rad * np.sin(ang)], 1).astype(np.int32)
        cv2.fillPoly(img, [pts], colour, cv2.LINE_AA)
    elif kind == 3:
        axes = (size, max(2, int(size * rng.uniform(0.3, 0.9))))
        cv2.ellipse(img, (cx, cy), axes, float(rng.uniform(0, 180)), 0, 360, colour, -1)
    elif kind == 4:
        thick = max(2, size // 6)
        end = (cx + int(rng.integers(-2 * size, 2 * size)), cy + int(rng.integers(-size, size)))
        cv2.line(img, (cx, cy), end, colour, thick, cv2.LINE_AA)
    else:  # a small checker patch
        cell = max(3, size // 4)
        other = _random_colour(rng, (0.0, 0.5), (0.6, 1.0))
        for i in range(4):
            for j in range(4):
                c = colour if (i + j) % 2 == 0 else other
                p0 = (cx + i * cell, cy + j * cell)
                cv2.rectangle(img, p0, (p0[0] + cell - 1, p0[1] + cell - 1), c, -1)


def _fractal(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """Multi-scale value noise in [0, 1], ``(h, w)`` float32: a photograph-like texture."""
    acc = np.zeros((h, w), np.float32)
    for cell, amp in ((48, 1.0), (24, 0.9), (12, 0.8), (6, 0.8), (3, 0.6)):
        acc += amp * _smooth_noise(rng, h, w, cell)
    lo, hi = float(acc.min()), float(acc.max())
    return (acc - lo) / max(hi - lo, 1e-6)


def _photo(rng: np.random.Generator, width: int, height: int) -> np.ndarray:
    """A photograph-like picture: fractal noise through a random colour palette."""
    value = _fractal(rng, height, width)
    bands = ((0.05, 0.25), (0.3, 0.5), (0.55, 0.75), (0.8, 1.0))  # dark to bright
    palette = np.array([_random_colour(rng, (0.2, 0.9), band) for band in bands], np.float32)
    pos = value * 3.0
    idx = np.minimum(pos.astype(np.int32), 2)
    frac = (pos - idx)[..., None]
    return (palette[idx] * (1 - frac) + palette[idx + 1] * frac).clip(0, 255).astype(np.uint8)


def make_poster(rng: np.random.Generator, width: int, height: int) -> np.ndarray:
    """One unique poster, ``(height, width, 3)`` uint8 RGB.

    Three kinds: a graphic (gradient, many shapes, words), a photograph (fractal
    colours with a caption) and a text sheet (lines of words); all framed.

    Args:
        rng: Source of every random choice (seeded by the caller).
        width: Width in pixels.
        height: Height in pixels.
    """
    kind = int(rng.integers(0, 3))
    if kind == 1:
        img = _photo(rng, width, height)
        shapes, texts = int(rng.integers(2, 6)), int(rng.integers(1, 3))
    else:
        c0 = np.array(_random_colour(rng, (0.1, 0.8), (0.5, 1.0)), np.float32)
        c1 = np.array(_random_colour(rng, (0.1, 0.8), (0.3, 1.0)), np.float32)
        ang = rng.uniform(0, 2 * np.pi)
        yy, xx = np.mgrid[0:height, 0:width].astype(np.float32)
        ramp = (np.cos(ang) * xx / max(width, 1) + np.sin(ang) * yy / max(height, 1) + 1) / 2
        img = (c0 + (c1 - c0) * ramp[..., None]).clip(0, 255).astype(np.uint8)
        shapes = int(rng.integers(14, 26)) if kind == 0 else int(rng.integers(3, 7))
        texts = int(rng.integers(2, 5)) if kind == 0 else int(rng.integers(6, 10))
    if kind == 0 and rng.random() < 0.35:  # stripes
        period = max(4, int(rng.uniform(0.04, 0.15) * width))
        colour = _random_colour(rng, (0.2, 1.0), (0.2, 0.9))
        for x in range(int(rng.integers(0, period)), width, period):
            cv2.line(img, (x, 0), (x + height // 3, height), colour, max(1, period // 4))
    for _ in range(shapes):
        _draw_shape(rng, img)
    for _ in range(int(rng.integers(50, 90))):  # small details: keypoints at every place
        _draw_shape(rng, img, small=True)
    for k in range(texts):
        if kind == 2:  # text lines from top to bottom
            top = int(k * height / texts)
            _draw_text(rng, img, top, top + int(0.9 * height / texts))
        else:
            top = int(rng.uniform(0.0, 0.8) * height)
            _draw_text(rng, img, top, min(height, top + int(rng.uniform(0.08, 0.25) * height)))
    noise = rng.normal(0, 5, img.shape)
    img = (img + noise).clip(0, 255).astype(np.uint8)
    frame = max(2, min(width, height) // 40)
    cv2.rectangle(img, (0, 0), (width - 1, height - 1), (30, 30, 30), frame)
    return img


def _draw_fixture(rng: np.random.Generator, img: np.ndarray, cu: int, cv: int, ppm: float) -> None:
    """A small wall fixture (socket, switch, sign or small frame) centred at ``(cu, cv)`` px."""
    kind = int(rng.integers(0, 3))
    if kind == 0:  # socket or switch plate with two holes or a rocker
        half = max(2, int(0.04 * ppm))
        cv2.rectangle(img, (cu - half, cv - half), (cu + half, cv + half), (240, 240, 235), -1)
        cv2.rectangle(img, (cu - half, cv - half), (cu + half, cv + half), (90, 90, 90), 1)
        r = max(1, half // 4)
        cv2.circle(img, (cu - half // 2, cv), r, (40, 40, 40), -1)
        cv2.circle(img, (cu + half // 2, cv), r, (40, 40, 40), -1)
    elif kind == 1:  # a sign with a word
        w, h = max(6, int(rng.uniform(0.15, 0.3) * ppm)), max(4, int(0.08 * ppm))
        sign = np.full((h, w, 3), _random_colour(rng, (0.5, 1.0), (0.5, 1.0)), np.uint8)
        _draw_text(rng, sign, 0, h)
        y0, x0 = max(0, cv - h // 2), max(0, cu - w // 2)
        part = img[y0 : y0 + h, x0 : x0 + w]
        part[:] = sign[: part.shape[0], : part.shape[1]]
    else:  # a small framed picture
        w, h = max(6, int(rng.uniform(0.15, 0.3) * ppm)), max(6, int(rng.uniform(0.15, 0.3) * ppm))
        y0, x0 = max(0, cv - h // 2), max(0, cu - w // 2)
        part = img[y0 : y0 + h, x0 : x0 + w]
        part[:] = make_poster(rng, w, h)[: part.shape[0], : part.shape[1]]


def make_wall(
    rng: np.random.Generator, length_m: float, height_m: float, ppm: float, posters: int
) -> np.ndarray:
    """A painted wall with a skirting board, posters and small fixtures, ``(H, W, 3)`` uint8 RGB.

    Posters hang where the robot's camera (about 0.5 m above the floor) sees them: each
    covers 70-90 % of its slot along the wall and spans heights of roughly 0.12-1.3 m.

    Args:
        rng: Source of every random choice.
        length_m: Wall length in metres (texture width).
        height_m: Wall height in metres (texture height).
        ppm: Pixels per metre.
        posters: Number of posters, spread along the wall in equal slots.
    """
    w, h = max(8, round(length_m * ppm)), max(8, round(height_m * ppm))
    paint = np.array(_random_colour(rng, (0.05, 0.3), (0.75, 0.95)), np.float32)
    shade = 1.0 + 0.04 * _smooth_noise(rng, h, w, max(4, int(0.5 * ppm)))
    grain = rng.normal(0, 1.5, (64, 64, 1)).astype(np.float32)
    wall = paint[None, None, :] * shade[..., None]
    wall += np.tile(grain, (h // 64 + 1, w // 64 + 1, 1))[:h, :w]
    img = wall.clip(0, 255).astype(np.uint8)
    board_h = max(2, int(0.08 * ppm))
    board = _random_colour(rng, (0.2, 0.6), (0.25, 0.5))
    img[h - board_h :, :] = board
    img[h - board_h, :] = (20, 20, 20)
    if posters <= 0:
        return img
    slot = length_m / posters
    for i in range(posters):
        pw_m = slot * rng.uniform(0.75, 0.92)
        ph_m = min(rng.uniform(0.9, 1.2), height_m - 0.25)
        cu = (i + 0.5) * slot + rng.uniform(-0.5, 0.5) * (slot - pw_m)
        cz = rng.uniform(0.6, 0.72)
        cz = min(max(cz, 0.12 + ph_m / 2), height_m - 0.05 - ph_m / 2)
        pw, ph = max(4, round(pw_m * ppm)), max(4, round(ph_m * ppm))
        x0 = round((cu - pw_m / 2) * ppm)
        y0 = round((height_m - cz - ph_m / 2) * ppm)
        x0, y0 = max(0, min(x0, w - pw)), max(0, min(y0, h - ph))
        img[y0 : y0 + ph, x0 : x0 + pw] = make_poster(rng, pw, ph)
        if rng.random() < 0.8:  # a fixture in the gap after this poster, low on the wall
            gap_u = (i + 1) * slot if i + 1 < posters else (x0 + pw) / ppm + 0.1
            fu = int(min(max(gap_u, 0.1), length_m - 0.1) * ppm)
            fz = rng.uniform(0.25, 0.45) if rng.random() < 0.6 else rng.uniform(0.9, 1.2)
            _draw_fixture(rng, img, fu, int((height_m - fz) * ppm), ppm)
    return img


def make_furnished_wall(
    rng: np.random.Generator, length_m: float, height_m: float, ppm: float, art: int, office: bool
) -> np.ndarray:
    """A wall of a ``home`` or ``office`` room, ``(H, W, 3)`` uint8 RGB.

    As the MuJoCo rooms (``naoloc/backends/mujoco/interior.py``), drawn flat: skirting board
    (0.08 m), at most one door (0.9 x 2.05 m) and one window (sill 0.9 m, bright daylight)
    over a ribbed radiator, sockets at 0.3 m, and up to ``art`` pictures and photographs
    with centres at 1.2-1.8 m (bottom edges above 0.95 m) with blank wall between them.
    """
    w, h = max(8, round(length_m * ppm)), max(8, round(height_m * ppm))
    paint = (226, 228, 230) if office else _random_colour(rng, (0.05, 0.2), (0.8, 0.92))
    shade = 1.0 + 0.03 * _smooth_noise(rng, h, w, max(4, int(0.5 * ppm)))
    img = (np.array(paint, np.float32)[None, None, :] * shade[..., None]).clip(0, 255)
    img = np.ascontiguousarray(img.astype(np.uint8))

    def px(u_m: float, z_m: float) -> tuple[int, int]:  # wall metres -> pixel (column, row)
        return round(u_m * ppm), round((height_m - z_m) * ppm)

    def rect(u0: float, z0: float, u1: float, z1: float, colour: tuple[int, ...]) -> None:
        cv2.rectangle(img, px(u0, z1), px(u1, z0), tuple(int(c) for c in colour), -1)

    used: list[tuple[float, float]] = []
    if rng.random() < 0.5 and length_m > 2.0:  # a door with architrave and handle
        a = float(rng.uniform(0.6, length_m - 0.6))
        rect(a - 0.53, 0.0, a + 0.53, 2.12, (238, 238, 232))
        rect(a - 0.45, 0.0, a + 0.45, 2.05, (140, 95, 58))
        rect(a + 0.3, 0.99, a + 0.42, 1.01, (150, 150, 155))
        used.append((a - 0.6, a + 0.6))
    if rng.random() < 0.6 and length_m > 2.0:  # a window over a radiator
        ww = float(rng.uniform(1.0, 1.5))
        a = float(rng.uniform(ww / 2 + 0.3, length_m - ww / 2 - 0.3))
        if all(a + ww / 2 + 0.1 < lo or a - ww / 2 - 0.1 > hi for lo, hi in used):
            z1 = min(height_m - 0.25, 2.15)
            rect(a - ww / 2 - 0.05, 0.85, a + ww / 2 + 0.05, z1 + 0.05, (240, 240, 238))
            rect(a - ww / 2, 0.9, a + ww / 2, z1, (250, 252, 255))  # daylight: near white
            rect(a - 0.025, 0.9, a + 0.025, z1, (240, 240, 238))
            rw = 0.8 * ww
            rect(a - rw / 2, 0.15, a + rw / 2, 0.75, (236, 236, 232))
            for k in range(int(rw / 0.06)):
                u = a - rw / 2 + 0.03 + k * 0.06
                rect(u + 0.022, 0.16, u + 0.03, 0.74, (200, 200, 198))
            used.append((a - ww / 2 - 0.1, a + ww / 2 + 0.1))
    for _ in range(int(rng.integers(1, 3))):  # sockets at 0.3 m
        a = float(rng.uniform(0.2, length_m - 0.2))
        rect(a - 0.04, 0.26, a + 0.04, 0.34, (245, 245, 240))
        cv2.circle(img, px(a - 0.012, 0.3), max(1, int(0.006 * ppm)), (60, 60, 60), -1)
        cv2.circle(img, px(a + 0.012, 0.3), max(1, int(0.006 * ppm)), (60, 60, 60), -1)
    u, count = float(rng.uniform(0.3, 1.0)), 0
    while u < length_m - 0.5 and count < art:
        n = int(rng.integers(2, 4)) if rng.random() < 0.3 else 1
        pw = float(rng.uniform(0.3, 0.4)) if n > 1 else float(rng.uniform(0.35, 0.9))
        ph = pw * float(rng.uniform(0.7, 1.3))
        span = n * pw + (n - 1) * 0.12
        if u + span > length_m - 0.3 or not all(u + span < lo or u > hi for lo, hi in used):
            u += 0.3
            continue
        zc = min(
            max(float(rng.uniform(1.35, 1.65)), 0.97 + ph / 2, 1.2), 1.8, height_m - 0.1 - ph / 2
        )
        pw_px, ph_px = max(4, round(pw * ppm)), max(4, round(ph * ppm))
        picture = make_poster(rng, pw_px, ph_px)
        for k in range(n):
            x0, y0 = px(u + k * (pw + 0.12), zc + ph / 2)
            part = img[y0 : y0 + ph_px, x0 : x0 + pw_px]
            part[:] = picture[: part.shape[0], : part.shape[1]]
        count += n
        u += span + float(rng.uniform(0.4, 1.3))
    board_h = max(2, int(0.08 * ppm))
    img[h - board_h :, :] = (236, 236, 230) if office else (120, 82, 50)
    img[h - board_h, :] = (60, 60, 60)
    return img


def make_floor(rng: np.random.Generator, sx: float, sy: float, ppm: float) -> np.ndarray:
    """Mildly textured floor tiles, ``(H, W, 3)`` uint8 RGB; rows along y, columns along x."""
    w, h = max(8, round(sx * ppm)), max(8, round(sy * ppm))
    base = np.array(_random_colour(rng, (0.1, 0.35), (0.45, 0.65)), np.float32)
    shade = 1.0 + 0.06 * _smooth_noise(rng, h, w, max(4, int(0.3 * ppm)))
    grain = rng.normal(0, 3, (64, 64, 1)).astype(np.float32)
    img = base[None, None, :] * shade[..., None]
    img += np.tile(grain, (h // 64 + 1, w // 64 + 1, 1))[:h, :w]
    img = img.clip(0, 255).astype(np.uint8)
    tile = max(4, int(0.5 * ppm))
    grout = tuple(int(c * 0.8) for c in base)
    for x in range(0, w, tile):
        cv2.line(img, (x, 0), (x, h - 1), grout, 1)
    for y in range(0, h, tile):
        cv2.line(img, (0, y), (w - 1, y), grout, 1)
    return img


def make_ceiling(rng: np.random.Generator, sx: float, sy: float, ppm: float) -> np.ndarray:
    """An almost plain ceiling, ``(H, W, 3)`` uint8 RGB."""
    w, h = max(8, round(sx * ppm)), max(8, round(sy * ppm))
    shade = 235 + 6 * _smooth_noise(rng, h, w, max(4, int(1.0 * ppm)))
    return np.repeat(shade[..., None], 3, axis=2).clip(0, 255).astype(np.uint8)


def make_atlas(room: RoomConfig) -> Atlas:
    """Generate every surface texture of a room and pack them into a mip-mapped atlas.

    Args:
        room: Room size (m), wall height (m), seed and posters per wall.

    Returns:
        The atlas; the same config always gives the same pixels.
    """
    rng = np.random.default_rng(room.seed)
    sx, sy = room.size_m
    wall_h = room.wall_height_m
    wall_ppm = min(256.0, 7000.0 / max(sx, sy), 4500.0 / wall_h)
    floor_ppm = min(128.0, 4096.0 / max(sx, sy))
    ceil_ppm = min(32.0, 2048.0 / max(sx, sy))
    if room.style == "posters":
        walls = [
            make_wall(rng, length, wall_h, wall_ppm, room.posters_per_wall)
            for length in (sx, sy, sx, sy)
        ]
    else:
        rng = np.random.default_rng([room.seed, 0x686F6D65])
        office = room.style == "office"
        walls = [
            make_furnished_wall(rng, length, wall_h, wall_ppm, room.posters_per_wall, office)
            for length in (sx, sy, sx, sy)
        ]
    textures = [
        *walls,
        make_floor(rng, sx, sy, floor_ppm),
        make_ceiling(rng, sx, sy, ceil_ppm),
    ]
    ppms = (wall_ppm, wall_ppm, wall_ppm, wall_ppm, floor_ppm, ceil_ppm)
    width = max(t.shape[1] for t in textures) + 2 * _PAD
    height = sum(t.shape[0] + 2 * _PAD for t in textures)
    height += (-height) % (2**MIP_LEVELS)
    width += (-width) % (2**MIP_LEVELS)
    if max(width, height) > _MAX_ATLAS_SIDE:
        raise BackendError(f"room textures need a {width}x{height} px atlas; use a smaller room")
    atlas = np.zeros((height, width, 3), np.uint8)
    regions = []
    y = 0
    for tex, ppm in zip(textures, ppms, strict=True):
        h, w = tex.shape[:2]
        padded = cv2.copyMakeBorder(tex, _PAD, _PAD, _PAD, _PAD, cv2.BORDER_REPLICATE)
        atlas[y : y + h + 2 * _PAD, : w + 2 * _PAD] = padded
        regions.append(Region(_PAD, y + _PAD, w, h, ppm))
        y += h + 2 * _PAD
    levels = [atlas]
    for _ in range(1, MIP_LEVELS):
        levels.append(cv2.pyrDown(levels[-1]))
    return Atlas(tuple(levels), tuple(regions))
