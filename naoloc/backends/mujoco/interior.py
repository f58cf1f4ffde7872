"""Furnished walls of ``home`` and ``office`` rooms: art at real heights and what lies below.

Real rooms hang pictures with their centres at about 1.5 m (here 1.2-1.8 m, bottom edges
above 0.95 m), while a NAO's top camera, 1 m from a wall with the head level, sees the band
0.07-0.95 m: skirting boards, sockets, radiators, doors, the lower half of a window, blank
wall. So the pictures sit above the camera's band, where the robot must tilt its head to see
them; that is the honest difficulty these rooms pose. Per wall: free stretches are filled
with single pictures, photographs or series of identical frames, with blank stretches left
between them; doors (0.9 x 2.05 m), windows with bright daylight (sill 0.9 m) over
radiators, sockets at 0.3 m, light switches at 1.05 m, skirting boards everywhere, and a
few objects on the floor along the walls. ``office`` adds whiteboards, notice boards and
filing cabinets.

Everything is in the room frame (see ``room.py``); this module never imports mujoco.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from naoloc.backends.mujoco import posters as poster_images
from naoloc.backends.mujoco.nao import ROBOT_RADIUS
from naoloc.backends.simulated import pictures
from naoloc.config import Config

ART_Z = (1.2, 1.8)  # m, range of picture centres
CAMERA_BAND_TOP = 0.95  # m, top of what the camera sees from 1 m with the head level
WALL_ITEM_CLEARANCE = ROBOT_RADIUS + 0.1  # m between the survey circuit and wall-side objects
_WHITE = (0.93, 0.93, 0.9, 1.0)
_METAL = (0.55, 0.57, 0.6, 1.0)


@dataclass(frozen=True)
class WallArt:
    """A picture to hang: wall, centre along the wall (m), centre height (m), size, pixels."""

    wall: str
    along: float
    z: float
    width: float
    height: float
    image: np.ndarray = field(repr=False, compare=False)


@dataclass(frozen=True)
class Part:
    """One visual primitive of a wall fixture or a piece of furniture (room frame, m)."""

    kind: str  # "box", "cylinder" or "sphere"
    pos: tuple[float, float, float]
    size: tuple[float, ...]
    rgba: tuple[float, float, float, float]
    material: str = ""  # a texture of RoomLayout.materials (tinted by rgba), or none


@dataclass(frozen=True)
class WallPlan:
    """What goes on the walls of one room.

    Attributes:
        art: Pictures (become ``poster_<wall>_<k>`` posters).
        fixtures: Visual-only boxes: skirting, doors, windows, radiators, sockets, boards.
        objects: ``(name, kind, rect, height, parts)`` pieces that collide (cabinets, clutter,
            bookcases: their parts are left to ``room.py``); ``room.py`` keeps those clear of
            the survey circuit by ``WALL_ITEM_CLEARANCE``.
    """

    art: tuple[WallArt, ...]
    fixtures: tuple[Part, ...]
    objects: tuple[tuple[str, str, tuple[float, float, float, float], float, tuple[Part, ...]], ...]


def wall_length(wall: str, size: tuple[float, float]) -> float:
    """Length of a wall (m)."""
    return size[0] if wall in ("y0", "y1") else size[1]


def _wall_box(
    wall: str,
    along: float,
    z: float,
    width: float,
    height: float,
    depth: float,
    size: tuple[float, float],
    rgba: tuple[float, float, float, float] = _WHITE,
    material: str = "",
    offset: float = 0.0,
) -> Part:
    """An axis-aligned box against a wall: ``offset`` m from its surface, ``depth`` m deep."""
    sx, sy = size
    d = offset + depth / 2
    if wall == "y0":
        pos, half = (along, d, z), (width / 2, depth / 2, height / 2)
    elif wall == "y1":
        pos, half = (along, sy - d, z), (width / 2, depth / 2, height / 2)
    elif wall == "x0":
        pos, half = (d, along, z), (depth / 2, width / 2, height / 2)
    else:
        pos, half = (sx - d, along, z), (depth / 2, width / 2, height / 2)
    return Part("box", pos, half, rgba, material)


def _free(intervals: list[tuple[float, float]], a: float, b: float) -> bool:
    return all(b <= lo or a >= hi for lo, hi in intervals)


def _picture(
    rng: np.random.Generator, w_px: int, h_px: int, real_p: float, own: list[np.ndarray]
) -> np.ndarray:
    if own:  # world.room.poster_dir: the user's photographs, in turn
        return pictures.framed(own.pop(0) if len(own) > 1 else own[0], rng, w_px, h_px)
    photos = pictures.sample_photographs()
    kind = float(rng.random())
    if photos and kind < real_p:
        image = photos[int(rng.integers(0, len(photos)))]
    elif kind < real_p + 0.45 * (1 - real_p):  # an abstract print or a poster
        image = poster_images.procedural_poster(w_px, h_px, rng)
    elif kind < real_p + 0.75 * (1 - real_p):
        image = pictures.landscape(rng, w_px, h_px)
    else:
        image = pictures.portrait(rng, w_px, h_px)
    return pictures.framed(image, rng, w_px, h_px)


def plan_walls(cfg: Config) -> WallPlan:
    """Plan the walls of a ``home`` or ``office`` room (seeded by ``world.room.seed``).

    Args:
        cfg: The validated config.

    Returns:
        The plan; the same config gives the same plan.
    """
    room = cfg.world.room
    office = room.style == "office"
    rng = np.random.default_rng([room.seed, 0x686F6D65, int(office)])
    size = (float(room.size_m[0]), float(room.size_m[1]))
    top = float(room.wall_height_m)
    walls = ("y0", "x1", "y1", "x0")
    used: dict[str, list[tuple[float, float]]] = {w: [] for w in walls}
    fixtures: list[Part] = []
    objects: list[tuple[str, str, tuple[float, float, float, float], float, tuple[Part, ...]]] = []
    skirting = (0.95, 0.95, 0.93, 1.0) if office or rng.random() < 0.5 else (0.45, 0.3, 0.18, 1.0)
    for w in walls:  # skirting boards
        fixtures.append(
            _wall_box(
                w, wall_length(w, size) / 2, 0.04, wall_length(w, size), 0.08, 0.012, size, skirting
            )
        )

    low: dict[str, list[tuple[float, float]]] = {w: [] for w in walls}
    hung: dict[str, list[tuple[float, float]]] = {w: [] for w in walls}  # pictures

    def place(w: str, width: float, margin: float = 0.25, tall: bool = True) -> float | None:
        """Find a free place along a wall: tall things block pictures, low ones do not."""
        length = wall_length(w, size)
        for _ in range(40):
            a = float(rng.uniform(margin + width / 2, length - margin - width / 2))
            if _free(used[w] + low[w], a - width / 2 - 0.1, a + width / 2 + 0.1):
                (used if tall else low)[w].append((a - width / 2, a + width / 2))
                return a
        return None

    order = [walls[int(i)] for i in rng.permutation(4)]
    # Doors: 0.9 x 2.05 m with an architrave, a handle at 1.0 m, a switch at 1.05 m.
    for w in order[: 2 if office and max(size) >= 5.0 else 1]:
        a = place(w, 1.1, 0.35)
        if a is None:
            continue
        fixtures.append(_wall_box(w, a, 1.06, 1.06, 2.12, 0.02, size, skirting))  # architrave
        fixtures.append(_wall_box(w, a, 1.025, 0.9, 2.05, 0.03, size, material="wood"))
        fixtures.append(_wall_box(w, a + 0.35, 1.0, 0.12, 0.025, 0.04, size, _METAL, offset=0.03))
        fixtures.append(_wall_box(w, a + 0.7, 1.05, 0.08, 0.08, 0.01, size))  # light switch
        used[w].append((a + 0.6, a + 0.8))
    # Windows with daylight (sill 0.9 m) and a ribbed radiator under each.
    for w in order[1 : 3 if max(size) >= 4.5 else 2]:
        width = float(rng.uniform(1.0, 1.6))
        a = place(w, width + 0.2)
        if a is None:
            continue
        z0, z1 = 0.9, min(top - 0.25, 2.15)
        zc, h = (z0 + z1) / 2, z1 - z0
        fixtures.append(_wall_box(w, a, zc, width + 0.1, h + 0.1, 0.02, size))  # frame
        fixtures.append(_wall_box(w, a, zc, width, h, 0.005, size, material="window", offset=0.02))
        fixtures.append(_wall_box(w, a, zc, 0.05, h, 0.02, size, offset=0.025))  # mullion
        fixtures.append(_wall_box(w, a, z0 - 0.02, width + 0.2, 0.04, 0.2, size))  # sill
        rw = 0.8 * width
        fixtures.append(_wall_box(w, a, 0.45, rw, 0.6, 0.03, size, offset=0.04))
        for k in range(int(rw / 0.06)):  # radiator fins
            along = a - rw / 2 + 0.03 + k * 0.06
            fixtures.append(_wall_box(w, along, 0.45, 0.025, 0.58, 0.05, size, offset=0.06))
    # Sockets at 0.3 m.
    for w in walls:
        for _ in range(int(rng.integers(1, 3))):
            a = place(w, 0.1, 0.2, tall=False)
            if a is not None:
                fixtures.append(_wall_box(w, a, 0.3, 0.08, 0.08, 0.012, size))
                fixtures.append(
                    _wall_box(
                        w, a, 0.3, 0.05, 0.05, 0.004, size, (0.75, 0.75, 0.72, 1.0), offset=0.012
                    )
                )
    # Pictures above the camera's band; blank stretches between them.
    art: list[WallArt] = []
    own: list[np.ndarray] = []
    if room.poster_dir is not None:
        count = 4 * room.posters_per_wall
        own = poster_images.photo_posters(room.poster_dir, [(512, 384)] * count, room.seed)
    for w in walls:
        length = wall_length(w, size)
        along, count = 0.3 + float(rng.uniform(0.0, 0.6)), 0
        if rng.random() < 0.15 and length >= 5.0:
            along = length  # a long stretch of blank wall: this wall stays bare
        tries = 0
        while along < length - 0.4 and count < room.posters_per_wall:
            kind = float(rng.random())
            if office and kind < 0.25:  # a whiteboard or a notice board
                n, pw, ph, pick = 1, float(rng.uniform(1.0, 1.6)), float(rng.uniform(0.7, 0.9)), 0
            elif kind < 0.45:  # one large picture
                n, pw, ph, pick = (
                    1,
                    float(rng.uniform(0.55, 1.0)),
                    float(rng.uniform(0.45, 0.75)),
                    1,
                )
            elif kind < 0.7:  # a series of identical frames
                n, pw, pick = int(rng.integers(2, 4)), float(rng.uniform(0.28, 0.4)), 2
                ph = pw * float(rng.uniform(1.1, 1.35))
            else:  # a small photograph
                n, pw, ph, pick = (
                    1,
                    float(rng.uniform(0.3, 0.45)),
                    float(rng.uniform(0.25, 0.45)),
                    3,
                )
            gap = 0.12
            span = n * pw + (n - 1) * gap
            if along + span > length - 0.3 or not _free(used[w] + hung[w], along, along + span):
                tries += 1
                if tries >= 4:  # nothing fits here: move on along the wall
                    along, tries = along + 0.15, 0
                continue
            tries = 0
            if pick == 0:
                image = _board(rng, pw, ph, bool(rng.random() < 0.5))
            else:
                px = (384, 192, 256)[pick - 1]
                image = _picture(rng, px, int(px * ph / pw), (0.3, 0.2, 0.5)[pick - 1], own)
            zc = float(rng.uniform(1.35, 1.65)) if n == 1 else 1.5
            zc = min(
                max(zc, CAMERA_BAND_TOP + 0.02 + ph / 2, ART_Z[0]), ART_Z[1], top - 0.1 - ph / 2
            )
            for k in range(n):
                centre = along + pw / 2 + k * (pw + gap)
                art.append(WallArt(w, centre, zc, pw, ph, image))
            hung[w].append((along, along + span))
            count += n
            along += span + float(rng.uniform(0.25, 1.1))
    # Objects that stand along the walls: filing cabinets (office), clutter on the floor.
    start = cfg.start_pose()
    kinds: list[str] = ["cabinet", "cabinet"] if office else []
    # Against the walls, in the camera's band: bookcases, sideboards at home, desks at work.
    kinds += ["bookcase"] * (1 if office else 2) + (["desk"] * 2 if office else ["sideboard"] * 2)
    kinds += ["bin", "box", "plant"][: int(rng.integers(2, 4))]
    for i, what in enumerate(kinds):
        w = walls[int(rng.integers(0, 4))]
        width, depth, height = {
            "cabinet": (0.45, 0.6, 1.0),
            "bin": (0.28, 0.28, 0.32),
            "box": (0.4, 0.3, 0.28),
            "plant": (0.3, 0.3, 0.35),
            "bookcase": (0.9, 0.32, 1.2),
            "sideboard": (1.2, 0.42, 0.78),
            "desk": (1.2, 0.6, 0.75),
        }[what]
        a = place(w, width, 0.3, tall=what in ("cabinet", "bookcase"))
        if a is None:
            continue
        body = _wall_box(w, a, height / 2, width, height, depth, size, offset=0.03)
        (cx, cy, _), (hx, hy, _) = body.pos, body.size
        rect = (cx - hx, cy - hy, cx + hx, cy + hy)
        if math.hypot(cx - start[0], cy - start[1]) < 0.6:
            continue
        parts = () if what == "bookcase" else _object_parts(what, body, rng)
        objects.append((f"{what}_{i}", what, rect, height, parts))
    return WallPlan(tuple(art), tuple(fixtures), tuple(objects))


def _object_parts(kind: str, body: Part, rng: np.random.Generator) -> tuple[Part, ...]:
    (cx, cy, cz), (hx, hy, hz) = body.pos, body.size
    if kind == "sideboard":
        return _sideboard(body, rng)
    if kind == "desk":
        return _desk(body, rng)
    if kind == "cabinet":
        parts = [Part("box", body.pos, body.size, _METAL)]
        for k in range(3):  # drawers with handles
            z = 0.17 + k * 0.33
            parts.append(
                Part("box", (cx, cy, z), (hx * 1.01, hy * 1.01, 0.005), (0.3, 0.3, 0.32, 1))
            )
        return tuple(parts)
    if kind == "bin":
        r = min(hx, hy)
        return (Part("cylinder", (cx, cy, cz), (r, hz), (0.2, 0.35, 0.6, 1.0)),)
    if kind == "box":
        return (Part("box", body.pos, body.size, (0.65, 0.5, 0.32, 1.0), "cardboard"),)
    r = min(hx, hy)
    pot = Part("cylinder", (cx, cy, 0.12), (r * 0.7, 0.12), (0.6, 0.3, 0.2, 1.0))
    leaves = Part("sphere", (cx, cy, 0.24 + r * 0.6), (r,), (0.15, 0.45, 0.15, 1.0), "fabric")
    return (pot, leaves)


def _along(body: Part) -> tuple[int, int]:
    """Index of the axis along the wall and of the axis into the room for a wall box."""
    return (0, 1) if body.size[0] >= body.size[1] else (1, 0)


def _at(body: Part, along: float, depth: float, z: float) -> tuple[float, float, float]:
    """A point of a wall box: ``along`` and ``depth`` in [-1, 1] of its half sizes, z (m)."""
    a, d = _along(body)
    p = [body.pos[0], body.pos[1], z]
    p[a] += along * body.size[a]
    p[d] += depth * body.size[d]
    return (p[0], p[1], p[2])


def _half(body: Part, along: float, depth: float, up: float) -> tuple[float, float, float]:
    a, _ = _along(body)
    return (along, depth, up) if a == 0 else (depth, along, up)


def _box(
    body: Part,
    at: tuple[float, float, float],
    half: tuple[float, float, float],
    rgba: tuple[float, float, float, float],
    material: str = "",
) -> Part:
    """A box on the wall box ``body``: centre ``at`` (along and depth in [-1, 1] of its half
    sizes, height m, as :func:`_at`), half sizes ``half`` (along, depth, up; m)."""
    return Part("box", _at(body, *at), _half(body, *half), rgba, material)


def _colour(rng: np.random.Generator, lo: float, hi: float) -> tuple[float, float, float, float]:
    r, g, b = (float(c) for c in rng.uniform(lo, hi, 3))
    return (r, g, b, 1.0)


def _sideboard(body: Part, rng: np.random.Generator) -> tuple[Part, ...]:
    """A low wooden sideboard with doors, books, a vase and a lamp on top."""
    hz = body.size[2]
    white = (1.0, 1.0, 1.0, 1.0)
    parts = [Part("box", (body.pos[0], body.pos[1], hz), body.size, white, "wood")]
    for k in (-0.5, 0.5):  # two doors with knobs
        parts.append(
            Part(
                "box",
                _at(body, k, 1.0, hz),
                _half(body, 0.28, 0.006, hz * 0.8),
                (0.75, 0.6, 0.45, 1.0),
                "wood",
            )
        )
        parts.append(
            Part("sphere", _at(body, k * 0.2, 1.05, hz * 1.1), (0.015,), (0.8, 0.7, 0.3, 1))
        )
    top = 2 * hz
    u = -0.9
    while u < -0.2:  # a row of books
        w = float(rng.uniform(0.02, 0.05))
        h = float(rng.uniform(0.15, 0.28))
        colour = _colour(rng, 0.05, 0.9)
        parts.append(
            Part("box", _at(body, u, 0.0, top + h / 2), _half(body, w / 2, 0.1, h / 2), colour)
        )
        u += (w + 0.005) / body.size[_along(body)[0]]
    vase = _colour(rng, 0.1, 0.9)
    parts.append(Part("cylinder", _at(body, 0.2, 0.0, top + 0.12), (0.06, 0.12), vase))
    parts.append(Part("cylinder", _at(body, 0.7, 0.0, top + 0.2), (0.012, 0.2), (0.2, 0.2, 0.2, 1)))
    parts.append(
        Part(
            "cylinder", _at(body, 0.7, 0.0, top + 0.42), (0.12, 0.08), (0.95, 0.9, 0.8, 1), "fabric"
        )
    )
    return tuple(parts)


def _desk(body: Part, rng: np.random.Generator) -> tuple[Part, ...]:
    """A desk with a monitor (showing a screen), keyboard, papers and a mug."""
    hz = body.size[2]
    top = 2 * hz
    a, d = _along(body)
    white = (1.0, 1.0, 1.0, 1.0)
    parts = [_box(body, (0.0, 0.0, top - 0.02), (body.size[a], body.size[d], 0.02), white, "wood")]
    for u in (-0.95, 0.95):
        for v in (-0.85, 0.85):
            leg = (0.02, 0.02, (top - 0.04) / 2)
            parts.append(_box(body, (u, v, (top - 0.04) / 2), leg, (0.3, 0.3, 0.32, 1.0)))
    parts.append(_box(body, (0.0, -0.5, top + 0.28), (0.27, 0.015, 0.17), white, "screen"))
    parts.append(_box(body, (0.0, -0.6, top + 0.06), (0.03, 0.02, 0.06), (0.1, 0.1, 0.1, 1.0)))
    parts.append(_box(body, (0.0, 0.4, top + 0.01), (0.22, 0.07, 0.01), (0.12, 0.12, 0.13, 1.0)))
    for k in range(int(rng.integers(1, 4))):
        u = float(rng.uniform(-0.9, -0.5)) if k % 2 == 0 else float(rng.uniform(0.5, 0.9))
        at = (u, float(rng.uniform(-0.3, 0.5)), top + 0.002 + 0.002 * k)
        parts.append(_box(body, at, (0.105, 0.148, 0.002), (0.97, 0.97, 0.95, 1.0)))
    mug = _colour(rng, 0.1, 0.9)
    parts.append(Part("cylinder", _at(body, 0.75, 0.3, top + 0.05), (0.04, 0.05), mug))
    return tuple(parts)


def _screen(rng: np.random.Generator) -> np.ndarray:
    """What a monitor shows: windows with title bars, text lines, a picture."""
    import cv2

    w, h = 320, 200
    img = np.full((h, w, 3), (40, 70, 110), np.uint8)
    for _ in range(3):
        x0, y0 = int(rng.integers(0, w // 2)), int(rng.integers(0, h // 2))
        x1, y1 = x0 + int(rng.integers(80, 180)), y0 + int(rng.integers(60, 120))
        cv2.rectangle(img, (x0, y0), (x1, y1), (235, 235, 235), -1)
        cv2.rectangle(img, (x0, y0), (x1, y0 + 10), (60, 60, 160), -1)
        for y in range(y0 + 16, y1 - 4, 7):
            cv2.line(
                img, (x0 + 4, y), (x0 + 4 + int(rng.integers(20, x1 - x0 - 8)), y), (50, 50, 50), 1
            )
    return img


def _board(rng: np.random.Generator, width_m: float, height_m: float, white: bool) -> np.ndarray:
    """A whiteboard with marker writing, or a cork notice board with pinned sheets."""
    import cv2

    w, h = 512, max(64, int(512 * height_m / width_m))
    if white:
        img = np.full((h, w, 3), 245, np.uint8)
        for _ in range(int(rng.integers(4, 9))):
            colour = [(20, 40, 160), (20, 20, 20), (170, 30, 30), (30, 120, 40)][
                int(rng.integers(0, 4))
            ]
            x, y = int(rng.integers(10, w - 150)), int(rng.integers(30, h - 10))
            word = " ".join(
                str(rng.choice(["plan", "map", "NAO", "x=2", "test", "todo", "v2"]))
                for _ in range(int(rng.integers(1, 4)))
            )
            cv2.putText(
                img, word, (x, y), cv2.FONT_HERSHEY_SCRIPT_SIMPLEX, 0.9, colour, 2, cv2.LINE_AA
            )
        pts = np.cumsum(rng.normal(0, 12, (12, 2)), axis=0) + np.array([w / 2, h / 2])
        cv2.polylines(img, [pts.astype(np.int32)], False, (20, 40, 160), 2, cv2.LINE_AA)
    else:
        grain = rng.normal(0, 14, (h, w, 1))
        img = np.clip(np.array([170, 125, 80]) + grain, 0, 255).astype(np.uint8)
        for _ in range(int(rng.integers(3, 7))):
            pw, ph = int(rng.integers(60, 130)), int(rng.integers(70, 150))
            x, y = int(rng.integers(0, w - pw)), int(rng.integers(0, max(1, h - ph)))
            sheet = poster_images.procedural_poster(pw, ph, rng) if rng.random() < 0.4 else None
            if sheet is None:
                img[y : y + ph, x : x + pw] = 240
                for k in range(8, ph - 5, 9):
                    cv2.line(img, (x + 6, y + k), (x + pw - 6, y + k), (90, 90, 90), 1)
            else:
                img[y : y + ph, x : x + pw] = sheet
            cv2.circle(img, (x + pw // 2, y + 5), 4, (200, 30, 30), -1)
    border = max(3, w // 80)
    frame = (160, 160, 165) if white else (120, 80, 45)
    cv2.rectangle(img, (0, 0), (w - 1, h - 1), frame, border)
    return img


def material_images(seed: int) -> dict[str, np.ndarray]:
    """Textures of the furnished rooms' materials (wood, fabric, window, cardboard, carpet)."""
    import cv2

    rng = np.random.default_rng([seed, 0x7E47])
    out: dict[str, np.ndarray] = {}
    # Wood: stretched noise for the grain, rings as bands.
    grain = cv2.resize(rng.normal(0, 1, (256, 16)).astype(np.float32), (256, 256))
    grain = cv2.GaussianBlur(grain, (0, 0), 1.5)
    bands = np.sin(np.linspace(0, 18 * np.pi, 256))[None, :] * 0.5
    tone = np.clip(0.8 + 0.08 * (grain + bands), 0.5, 1.0)[..., None]
    out["wood"] = np.clip(np.array([150, 100, 60]) * tone, 0, 255).astype(np.uint8)
    # Fabric: a fine weave with soft colour variation.
    yy, xx = np.mgrid[0:128, 0:128]
    weave = (np.sin(xx * np.pi / 2) * np.sin(yy * np.pi / 2) * 0.06)[..., None]
    base = rng.uniform(60, 170, 3)
    noise = rng.normal(0, 6, (128, 128, 3))
    out["fabric"] = np.clip(base * (1 + weave) + noise, 0, 255).astype(np.uint8)
    # Daylight through a window: bright sky, trees; rendered with emission (overexposed).
    view = pictures.landscape(rng, 256, 256)
    out["window"] = np.clip(view.astype(np.float32) * 0.4 + 160, 0, 255).astype(np.uint8)
    card = np.clip(np.array([180, 140, 95]) + rng.normal(0, 8, (64, 64, 3)), 0, 255)
    out["cardboard"] = card.astype(np.uint8)
    pile = np.clip(np.array([105, 110, 120]) + rng.normal(0, 10, (256, 256, 3)), 0, 255)
    carpet = cv2.GaussianBlur(pile.astype(np.uint8), (0, 0), 0.8)
    for k in range(0, 256, 128):  # carpet tiles, 0.5 m
        carpet[k, :] = carpet[:, k] = (85, 90, 98)
    out["carpet"] = carpet
    out["screen"] = _screen(rng)
    return out
