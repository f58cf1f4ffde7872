"""Rooms generated from the config: walls, floor, posters, furniture and lights as MJCF.

Room frame: origin at a room corner, x and y along the walls, z up, metres. The inner
floor is ``[0, sx] x [0, sy]``. Walls are named by the coordinate they stand at: ``x0``
(x = 0), ``x1`` (x = sx), ``y0`` (y = 0), ``y1`` (y = sy). ``world.room.style: posters``:
posters hang on the inside of the walls around the camera's height (about 0.5 m), as in
earlier versions; ``home`` and ``office``: pictures hang at real heights and the walls get
doors, windows, radiators, sockets, skirting and wall-side furniture (``interior.py``).
Furniture stands in the middle of the
room, clear of the survey circuit (by 0.45 m), of the start pose and of the room's centre
(by 0.5 m) and, whenever the room is large enough, of the band 0.6-1.4 m from the walls
where the ``random`` evaluation protocol draws poses.

This module only computes the layout and writes MJCF text; it never imports mujoco.
Textures are declared as flat placeholders and filled with the generated pixels after
compiling (see ``sim.fill_textures``), so nothing is written to disk.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np

from naoloc.backends.mujoco import interior
from naoloc.backends.mujoco import posters as poster_images
from naoloc.backends.mujoco.interior import Part
from naoloc.config import Config

WALL_THICKNESS = 0.1  # m
POSTER_THICKNESS = 0.004  # m, posters are thin boxes this far in front of the wall
POSTER_GAP = 0.001  # m between the wall surface and the back of a poster
PATH_CLEARANCE = 0.45  # m, furniture keeps this far from the survey circuit
RANDOM_BAND_OUTER = 1.4  # m, outer edge of the random protocol's band from the walls
START_CLEARANCE = 0.6  # m, furniture keeps this far from the start pose
CENTRE_CLEARANCE = 0.5  # m, and this far from the centre of the room

# Walls in order around the room; yaw turns a poster box so that its local -y face (which
# MuJoCo textures unmirrored) looks into the room with local +x to the viewer's right.
_NO_CONTACT = 'contype="0" conaffinity="0"'
# Diffuse colour of the two room lights: white, warm lamps at home, cool tubes in offices.
_LIGHTS = {
    "posters": ("0.5 0.5 0.5", "0.4 0.4 0.4"),
    "home": ("0.55 0.5 0.42", "0.44 0.4 0.34"),
    "office": ("0.48 0.5 0.53", "0.38 0.4 0.43"),
}
_WALL_YAW = {"y0": math.pi, "x1": -math.pi / 2, "y1": 0.0, "x0": math.pi / 2}


@dataclass(frozen=True)
class Poster:
    """One poster on a wall.

    Attributes:
        name: Unique name (``poster_<wall>_<k>``); also the MuJoCo geom, material, texture.
        wall: Wall name (x0, x1, y0, y1).
        center: Centre of the poster's visible face, room frame (m).
        width: Width along the wall (m).
        height: Height (m).
        yaw: Rotation of the poster box about z (rad).
        image: ``(h, w, 3)`` uint8 RGB pixels, row 0 at the top.
    """

    name: str
    wall: str
    center: tuple[float, float, float]
    width: float
    height: float
    yaw: float
    image: np.ndarray = field(repr=False, compare=False)


@dataclass(frozen=True)
class Furniture:
    """A piece of furniture: its axis-aligned footprint and the primitives that draw it.

    Attributes:
        name: Unique name (``table_0``, ``chair_1``, ``shelf_0``...).
        kind: table, chair or shelf.
        rect: Footprint ``(xmin, ymin, xmax, ymax)`` in the room frame (m).
        height: Top of the piece above the floor (m).
        parts: Visual primitives; one invisible box over the footprint collides.
    """

    name: str
    kind: str
    rect: tuple[float, float, float, float]
    height: float
    parts: tuple[Part, ...]


@dataclass(frozen=True)
class RoomLayout:
    """Everything that makes up a generated room.

    Attributes:
        size: Inner size ``(sx, sy)`` in metres.
        wall_height: Wall height in metres.
        posters: The posters on all walls.
        furniture: The furniture in the room.
        wall_image: Wall paint texture (covers 1 m x 1 m), RGB.
        floor_image: Floor texture (covers 1 m x 1 m), RGB.
        style: ``world.room.style``.
        fixtures: Visual-only primitives on the walls (skirting, doors, windows, radiators,
            sockets); none in ``posters`` rooms.
        materials: Extra textures by material name (wood, fabric, window...).
    """

    size: tuple[float, float]
    wall_height: float
    posters: tuple[Poster, ...]
    furniture: tuple[Furniture, ...]
    wall_image: np.ndarray = field(repr=False, compare=False)
    floor_image: np.ndarray = field(repr=False, compare=False)
    style: str = "posters"
    fixtures: tuple[Part, ...] = ()
    materials: dict[str, np.ndarray] = field(default_factory=dict, repr=False, compare=False)

    def is_free(self, x: float, y: float, clearance: float) -> bool:
        """True when a disc of radius ``clearance`` (m) at ``(x, y)`` (room frame) is clear.

        Clear means inside the walls and outside every furniture footprint.
        """
        sx, sy = self.size
        if not (clearance <= x <= sx - clearance and clearance <= y <= sy - clearance):
            return False
        return all(_rect_distance(f.rect, x, y) > clearance for f in self.furniture)


def _rect_distance(rect: tuple[float, float, float, float], x: float, y: float) -> float:
    x0, y0, x1, y1 = rect
    dx = max(x0 - x, 0.0, x - x1)
    dy = max(y0 - y, 0.0, y - y1)
    return math.hypot(dx, dy)


def wall_point(
    wall: str, along: float, offset: float, size: tuple[float, float]
) -> tuple[float, float]:
    """Room-frame (x, y) of a point ``along`` metres along a wall, ``offset`` m into the room."""
    sx, sy = size
    if wall == "y0":
        return (along, offset)
    if wall == "x1":
        return (sx - offset, along)
    if wall == "y1":
        return (along, sy - offset)
    return (offset, along)


def _place_posters(cfg: Config, rng: np.random.Generator) -> tuple[Poster, ...]:
    room = cfg.world.room
    sx, sy = room.size_m
    n = room.posters_per_wall
    total = 4 * n
    tex_w = 512 if total <= 40 else 256
    walls = (("y0", sx), ("x1", sy), ("y1", sx), ("x0", sy))
    specs: list[tuple[str, int, float, float, float, float]] = []
    for wall, length in walls:
        slot = length / max(n, 1)
        for k in range(n):
            width = min(0.9, 0.9 * slot) * float(rng.uniform(0.85, 1.0))
            height = min(1.0, room.wall_height_m - 0.3, width * float(rng.uniform(0.85, 1.3)))
            jitter = float(rng.uniform(-1.0, 1.0)) * (slot - width) * 0.3
            along = (k + 0.5) * slot + jitter
            zc = max(float(rng.uniform(0.45, 0.7)), height / 2 + 0.1)
            specs.append((wall, k, along, width, height, zc))
    if room.poster_dir is not None:
        sizes = [(tex_w, _tex_height(tex_w, w, h)) for _, _, _, w, h, _ in specs]
        images = poster_images.photo_posters(room.poster_dir, sizes, room.seed)
    else:
        images = [
            poster_images.procedural_poster(tex_w, _tex_height(tex_w, w, h), rng)
            for _, _, _, w, h, _ in specs
        ]
    out = []
    depth = POSTER_GAP + POSTER_THICKNESS / 2
    for (wall, k, along, width, height, zc), image in zip(specs, images, strict=True):
        x, y = wall_point(wall, along, depth, (sx, sy))
        out.append(
            Poster(f"poster_{wall}_{k}", wall, (x, y, zc), width, height, _WALL_YAW[wall], image)
        )
    return tuple(out)


def _tex_height(tex_w: int, width: float, height: float) -> int:
    return int(min(1024, max(32, round(tex_w * height / width))))


def _rgba(rgb: np.ndarray) -> tuple[float, float, float, float]:
    r, g, b = (float(v) for v in np.clip(rgb, 0.0, 1.0))
    return (r, g, b, 1.0)


def _wood(rng: np.random.Generator) -> tuple[float, float, float, float]:
    return _rgba(np.array([0.55, 0.38, 0.22]) * rng.uniform(0.7, 1.2))


def _table(
    name: str, cx: float, cy: float, w: float, d: float, rng: np.random.Generator
) -> Furniture:
    h = 0.74
    wood = _wood(rng)
    leg = (0.3, 0.3, 0.32, 1.0)
    parts = [Part("box", (cx, cy, h - 0.02), (w / 2, d / 2, 0.02), wood)]
    for sxn in (-1, 1):
        for syn in (-1, 1):
            pos = (cx + sxn * (w / 2 - 0.05), cy + syn * (d / 2 - 0.05), (h - 0.04) / 2)
            parts.append(Part("box", pos, (0.025, 0.025, (h - 0.04) / 2), leg))
    return Furniture(
        name, "table", (cx - w / 2, cy - d / 2, cx + w / 2, cy + d / 2), h, tuple(parts)
    )


def _chair(name: str, cx: float, cy: float, rng: np.random.Generator) -> Furniture:
    s = 0.22
    seat_h = 0.45
    color = _rgba(rng.uniform(0.1, 0.9, 3))
    parts = [Part("box", (cx, cy, seat_h), (s, s, 0.02), color)]
    for sxn in (-1, 1):
        for syn in (-1, 1):
            pos = (cx + sxn * (s - 0.02), cy + syn * (s - 0.02), seat_h / 2)
            parts.append(Part("cylinder", pos, (0.015, seat_h / 2), (0.2, 0.2, 0.2, 1.0)))
    side = int(rng.integers(0, 4))
    bx, by = [(s - 0.015, 0.0), (0.0, s - 0.015), (-(s - 0.015), 0.0), (0.0, -(s - 0.015))][side]
    half = (0.015, s, 0.22) if side in (0, 2) else (s, 0.015, 0.22)
    parts.append(Part("box", (cx + bx, cy + by, seat_h + 0.24), half, color))
    return Furniture(name, "chair", (cx - s, cy - s, cx + s, cy + s), seat_h + 0.46, tuple(parts))


def _shelf(name: str, cx: float, cy: float, along_x: bool, rng: np.random.Generator) -> Furniture:
    length, depth, h = 0.9, 0.32, 1.2
    hx, hy = (length / 2, depth / 2) if along_x else (depth / 2, length / 2)
    wood = _wood(rng)
    parts = []
    for side in (-1, 1):  # side panels
        if along_x:
            parts.append(Part("box", (cx + side * (hx - 0.01), cy, h / 2), (0.01, hy, h / 2), wood))
        else:
            parts.append(Part("box", (cx, cy + side * (hy - 0.01), h / 2), (hx, 0.01, h / 2), wood))
    for level in range(4):  # boards, then books standing on the three lower ones
        z = 0.02 + level * (h - 0.04) / 3
        parts.append(Part("box", (cx, cy, z), (hx - 0.02, hy - 0.01, 0.012), wood))
        if level == 3:
            continue
        pos_along = -length / 2 + 0.04
        while pos_along < length / 2 - 0.08:
            bw = float(rng.uniform(0.02, 0.05))
            bh = float(rng.uniform(0.15, 0.3))
            color = _rgba(rng.uniform(0.05, 0.95, 3))
            a = pos_along + bw / 2
            bx, by = (cx + a, cy) if along_x else (cx, cy + a)
            half = (
                (bw / 2, depth / 2 - 0.04, bh / 2)
                if along_x
                else (depth / 2 - 0.04, bw / 2, bh / 2)
            )
            parts.append(Part("box", (bx, by, z + 0.012 + bh / 2), half, color))
            pos_along += bw + float(rng.uniform(0.0, 0.02))
    return Furniture(name, "shelf", (cx - hx, cy - hy, cx + hx, cy + hy), h, tuple(parts))


def survey_circuit(cfg: Config) -> list[tuple[float, float]]:
    """Corners of the survey rectangle in the room frame, starting at the start pose.

    The circuit turns away from the nearer side wall (the survey keeps that wall beside
    it): left (counter-clockwise) with the nearer wall on the robot's right, else right.
    """
    x0, y0, th = cfg.start_pose()
    a, b = cfg.survey_sides()
    c, s = math.cos(th), math.sin(th)
    sx, sy = cfg.world.room.size_m

    def reach(dx: float, dy: float) -> float:  # distance to the wall along (dx, dy)
        hits = [(sx - x0) / dx if dx > 1e-9 else -x0 / dx if dx < -1e-9 else math.inf,
                (sy - y0) / dy if dy > 1e-9 else -y0 / dy if dy < -1e-9 else math.inf]  # fmt: skip
        return min(hits)

    if reach(-s, c) < reach(s, -c):  # the nearer wall is on the left: a clockwise circuit
        b = -b
    local = [(0.0, 0.0), (a, 0.0), (a, b), (0.0, b)]
    return [(x0 + c * u - s * v, y0 + s * u + c * v) for u, v in local]


def _segment_distance(
    rect: tuple[float, float, float, float], p: tuple[float, float], q: tuple[float, float]
) -> float:
    steps = max(2, int(math.hypot(q[0] - p[0], q[1] - p[1]) / 0.05) + 1)
    return min(
        _rect_distance(rect, p[0] + (q[0] - p[0]) * t, p[1] + (q[1] - p[1]) * t)
        for t in np.linspace(0.0, 1.0, steps)
    )


def _place_furniture(cfg: Config, rng: np.random.Generator) -> tuple[Furniture, ...]:
    sx, sy = cfg.world.room.size_m
    corners = survey_circuit(cfg)
    loop = list(zip(corners, corners[1:] + corners[:1], strict=True))
    start = cfg.start_pose()
    inner = RANDOM_BAND_OUTER + 0.05
    margin = inner if min(sx, sy) - 2 * inner >= 1.2 else 0.3
    placed: list[Furniture] = []

    def fits(f: Furniture) -> bool:
        x0, y0, x1, y1 = f.rect
        if x0 < margin or y0 < margin or x1 > sx - margin or y1 > sy - margin:
            return False
        if _rect_distance(f.rect, start[0], start[1]) < START_CLEARANCE:
            return False
        if _rect_distance(f.rect, sx / 2, sy / 2) < CENTRE_CLEARANCE:
            return False
        if any(_segment_distance(f.rect, p, q) < PATH_CLEARANCE for p, q in loop):
            return False
        return all(_rect_gap(f.rect, g.rect) >= 0.15 for g in placed)

    def attempt(make: object, tries: int = 60) -> Furniture | None:
        for _ in range(tries):
            cx = float(rng.uniform(margin, sx - margin))
            cy = float(rng.uniform(margin, sy - margin))
            f = make(cx, cy)  # type: ignore[operator]
            if fits(f):
                placed.append(f)
                return f
        return None

    along_x = bool(rng.random() < 0.5)
    tw, td = (1.0, 0.6) if along_x else (0.6, 1.0)
    table = attempt(lambda cx, cy: _table("table_0", cx, cy, tw, td, rng))
    for i in range(2):
        if table is not None:
            tx0, ty0, tx1, ty1 = table.rect
            side = int(rng.integers(0, 4))
            tcx, tcy = (tx0 + tx1) / 2, (ty0 + ty1) / 2
            off = [(tx1 + 0.3, tcy), (tcx, ty1 + 0.3), (tx0 - 0.3, tcy), (tcx, ty0 - 0.3)][side]
            chair = _chair(f"chair_{i}", off[0], off[1], rng)
            if fits(chair):
                placed.append(chair)
                continue
        attempt(lambda cx, cy, i=i: _chair(f"chair_{i}", cx, cy, rng))
    if (sx - 2 * margin) * (sy - 2 * margin) >= 4.0:
        attempt(lambda cx, cy: _shelf("shelf_0", cx, cy, bool(rng.random() < 0.5), rng))
    return tuple(placed)


def _rect_gap(a: tuple[float, float, float, float], b: tuple[float, float, float, float]) -> float:
    dx = max(b[0] - a[2], a[0] - b[2], 0.0)
    dy = max(b[1] - a[3], a[1] - b[3], 0.0)
    return math.hypot(dx, dy)


def build_layout(cfg: Config) -> RoomLayout:
    """Generate the room a config describes; the same config gives the same room.

    ``style: posters`` gives the rooms of earlier versions exactly (same seed, same room);
    ``home`` and ``office`` furnish the walls (see ``interior.py``).

    Args:
        cfg: The validated config (world.room.*, world.start_pose, survey.*).

    Returns:
        The room's posters, furniture and textures.
    """
    room = cfg.world.room
    rng = np.random.default_rng([room.seed, 0x6E616F])
    if room.style != "posters":
        return _changed(_furnished_layout(cfg, rng), cfg)
    posters = _place_posters(cfg, rng)
    furniture = _place_furniture(cfg, rng) if room.furniture else ()
    wall_rgb = tuple(int(v) for v in rng.integers(170, 235, 3))
    return _changed(
        RoomLayout(
            size=(float(room.size_m[0]), float(room.size_m[1])),
            wall_height=float(room.wall_height_m),
            posters=posters,
            furniture=furniture,
            wall_image=poster_images.plaster_texture(256, wall_rgb, room.seed),  # type: ignore[arg-type]
            floor_image=poster_images.floor_texture(512, room.seed),
        ),
        cfg,
    )


def _changed(layout: RoomLayout, cfg: Config) -> RoomLayout:
    """The layout with ``world.room.changes`` applied (itself when there are none).

    A share of the pieces moves by up to ``max_move_m`` in x and y, staying inside the
    walls and clear of the other pieces (a piece that finds no such place in 40 draws
    stays); ``added`` plain boxes stand where nothing stood.
    """
    changes = cfg.world.room.changes
    if changes is None:
        return layout
    rng = np.random.default_rng([cfg.world.room.seed, changes.seed, 0xC4A6])
    sx, sy = layout.size
    pieces = list(layout.furniture)
    count = round(changes.moved * len(pieces))
    chosen: list[int] = rng.choice(len(pieces), size=count, replace=False).tolist() if count else []
    for i in sorted(chosen):
        others = [f for j, f in enumerate(pieces) if j != i]
        for _ in range(40):
            dx, dy = rng.uniform(-changes.max_move_m, changes.max_move_m, 2)
            moved = _shifted(pieces[i], float(dx), float(dy))
            x0, y0, x1, y1 = moved.rect
            inside = x0 > 0.05 and y0 > 0.05 and x1 < sx - 0.05 and y1 < sy - 0.05
            if inside and all(_rect_gap(moved.rect, f.rect) >= 0.05 for f in others):
                pieces[i] = moved
                break
    for k in range(changes.added):
        for _ in range(60):
            w, d = rng.uniform(0.3, 0.6, 2)
            h = float(rng.uniform(0.4, 0.9))
            cx, cy = rng.uniform(0.4, sx - 0.4), rng.uniform(0.4, sy - 0.4)
            rect = (cx - w / 2, cy - d / 2, cx + w / 2, cy + d / 2)
            if all(_rect_gap(rect, f.rect) >= 0.1 for f in pieces):
                color = _rgba(rng.uniform(0.15, 0.85, 3))
                part = Part("box", (float(cx), float(cy), h / 2), (w / 2, d / 2, h / 2), color)
                pieces.append(Furniture(f"added_{k}", "box", rect, h, (part,)))
                break
    return dataclasses.replace(layout, furniture=tuple(pieces))


def _shifted(f: Furniture, dx: float, dy: float) -> Furniture:
    """A piece moved by ``(dx, dy)`` m on the floor."""
    x0, y0, x1, y1 = f.rect
    parts = tuple(
        dataclasses.replace(p, pos=(p.pos[0] + dx, p.pos[1] + dy, p.pos[2])) for p in f.parts
    )
    return dataclasses.replace(f, rect=(x0 + dx, y0 + dy, x1 + dx, y1 + dy), parts=parts)


def _textured(f: Furniture) -> Furniture:
    """Wood on tables and shelves, fabric on chairs (texture tinted by the part's colour)."""
    parts = []
    for k, p in enumerate(f.parts):
        r, g, b = (min(1.0, 0.6 + 0.5 * c) for c in p.rgba[:3])
        tint = (r, g, b, 1.0)
        top = f.kind == "table" and k == 0
        board = f.kind == "shelf" and (k < 2 or p.size[-1] <= 0.012)
        if top or board:
            parts.append(Part(p.kind, p.pos, p.size, tint, "wood"))
        elif f.kind == "chair" and p.kind == "box":
            parts.append(Part(p.kind, p.pos, p.size, (1.0, 1.0, 1.0, 1.0), "fabric"))
        else:
            parts.append(p)
    return Furniture(f.name, f.kind, f.rect, f.height, tuple(parts))


def _furnished_layout(cfg: Config, rng: np.random.Generator) -> RoomLayout:
    room = cfg.world.room
    size = (float(room.size_m[0]), float(room.size_m[1]))
    office = room.style == "office"
    plan = interior.plan_walls(cfg)
    corners = survey_circuit(cfg)
    loop = list(zip(corners, corners[1:] + corners[:1], strict=True))
    books = np.random.default_rng([room.seed, 0xB00C])
    posters = []
    depth = POSTER_GAP + POSTER_THICKNESS / 2
    counts = dict.fromkeys(("x0", "x1", "y0", "y1"), 0)
    for art in plan.art:
        x, y = wall_point(art.wall, art.along, depth, size)
        k = counts[art.wall]
        counts[art.wall] += 1
        posters.append(
            Poster(
                f"poster_{art.wall}_{k}",
                art.wall,
                (x, y, art.z),
                art.width,
                art.height,
                _WALL_YAW[art.wall],
                art.image,
            )
        )
    furniture = list(_place_furniture(cfg, rng) if room.furniture else ())
    furniture = [_textured(f) for f in furniture]
    for name, kind, rect, height, boxes in plan.objects if room.furniture else ():
        clear = min(_segment_distance(rect, p, q) for p, q in loop)
        if clear < interior.WALL_ITEM_CLEARANCE:
            continue  # the robot walks there
        if any(_rect_gap(rect, f.rect) < 0.1 for f in furniture):
            continue
        if kind == "bookcase":
            cx, cy = (rect[0] + rect[2]) / 2, (rect[1] + rect[3]) / 2
            along_x = rect[2] - rect[0] > rect[3] - rect[1]
            furniture.append(_textured(_shelf(name, cx, cy, along_x, books)))
            continue
        furniture.append(Furniture(name, kind, rect, height, boxes))
    fixtures = plan.fixtures
    materials = interior.material_images(room.seed)
    paint_rng = np.random.default_rng([room.seed, 0x7A1])
    if office:
        wall_rgb = tuple(int(v) for v in paint_rng.integers(215, 240, 3))
        floor = cv2.resize(materials["carpet"], (512, 512), interpolation=cv2.INTER_NEAREST)
    else:
        warm = np.array([235, 222, 200]) * paint_rng.uniform(0.85, 1.0)
        wall_rgb = tuple(int(v) for v in np.clip(warm + paint_rng.integers(-12, 12, 3), 0, 255))
        floor = poster_images.floor_texture(512, room.seed)
    return RoomLayout(
        size=size,
        wall_height=float(room.wall_height_m),
        posters=tuple(posters),
        furniture=tuple(furniture),
        wall_image=poster_images.plaster_texture(256, wall_rgb, room.seed),  # type: ignore[arg-type]
        floor_image=floor,
        style=room.style,
        fixtures=fixtures,
        materials=materials,
    )


def _f(values: Sequence[float]) -> str:
    return " ".join(f"{v:.6g}" for v in values)


def _part_geom(name: str, part: Part) -> str:
    material = f'material="{part.material}" ' if part.material else ""
    return (
        f'<geom name="{name}" type="{part.kind}" pos="{_f(part.pos)}" size="{_f(part.size)}" '
        f'{material}rgba="{_f(part.rgba)}" contype="0" conaffinity="0"/>'
    )


def room_mjcf(layout: RoomLayout, timestep: float) -> str:
    """The MJCF text of a room with the NAO (``nao.xml``, resolved as an asset) in it.

    Args:
        layout: The generated room.
        timestep: Physics step in seconds.

    Returns:
        MJCF text; textures are flat placeholders of the right sizes.
    """
    sx, sy = layout.size
    h = layout.wall_height
    t = WALL_THICKNESS
    wh, ww = layout.wall_image.shape[:2]
    fh, fw = layout.floor_image.shape[:2]
    assets = [
        f'<texture name="wall" type="2d" builtin="flat" width="{ww}" height="{wh}"/>',
        f'<texture name="floor" type="2d" builtin="flat" width="{fw}" height="{fh}"/>',
        '<material name="wall" texture="wall" texuniform="true" texrepeat="1 1" specular="0"/>',
        '<material name="floor" texture="floor" texuniform="true" texrepeat="1 1" specular="0"/>',
        '<material name="ceiling" rgba="0.95 0.95 0.95 1" specular="0"/>',
        '<material name="marker" rgba="1 0 0 1" emission="1" specular="0"/>',
    ]
    for name, image in layout.materials.items():
        th, tw = image.shape[:2]
        assets.append(
            f'<texture name="{name}" type="2d" builtin="flat" width="{tw}" height="{th}"/>'
        )
        if name in ("window", "screen"):  # daylight and a monitor glow: brighter than lit
            glow = 1 if name == "window" else 0.6
            assets.append(
                f'<material name="{name}" texture="{name}" emission="{glow}" specular="0"/>'
            )
        else:
            assets.append(
                f'<material name="{name}" texture="{name}" texuniform="true" texrepeat="3 3" '
                'specular="0"/>'
            )
    for p in layout.posters:
        ph, pw = p.image.shape[:2]
        assets.append(
            f'<texture name="{p.name}" type="2d" builtin="flat" width="{pw}" height="{ph}"/>'
        )
        assets.append(f'<material name="{p.name}" texture="{p.name}" specular="0"/>')
    d0, d1 = _LIGHTS.get(layout.style, _LIGHTS["posters"])
    body = [
        f'<light name="light0" directional="true" dir="0.35 0.55 -0.75" diffuse="{d0}" '
        'specular="0 0 0" castshadow="false"/>',
        f'<light name="light1" directional="true" dir="-0.55 -0.35 -0.75" diffuse="{d1}" '
        'specular="0 0 0" castshadow="false"/>',
        f'<geom name="floor" type="plane" pos="{_f((sx / 2, sy / 2, 0))}" '
        f'size="{_f((sx / 2 + t, sy / 2 + t, 1.0))}" material="floor" {_NO_CONTACT}/>',
        f'<geom name="ceiling" type="box" pos="{_f((sx / 2, sy / 2, h + 0.02))}" '
        f'size="{_f((sx / 2 + t, sy / 2 + t, 0.02))}" material="ceiling" {_NO_CONTACT}/>',
    ]
    walls = {
        "y0": ((sx / 2, -t / 2, h / 2), (sx / 2 + t, t / 2, h / 2)),
        "y1": ((sx / 2, sy + t / 2, h / 2), (sx / 2 + t, t / 2, h / 2)),
        "x0": ((-t / 2, sy / 2, h / 2), (t / 2, sy / 2, h / 2)),
        "x1": ((sx + t / 2, sy / 2, h / 2), (t / 2, sy / 2, h / 2)),
    }
    for name, (pos, size) in walls.items():
        body.append(
            f'<geom name="wall_{name}" type="box" pos="{_f(pos)}" size="{_f(size)}" '
            'material="wall" contype="0" conaffinity="2" condim="1"/>'
        )
    for p in layout.posters:
        body.append(
            f'<geom name="{p.name}" type="box" pos="{_f(p.center)}" euler="0 0 {p.yaw:.9g}" '
            f'size="{_f((p.width / 2, POSTER_THICKNESS / 2, p.height / 2))}" material="{p.name}" '
            'contype="0" conaffinity="0"/>'
        )
    for f in layout.furniture:
        x0, y0, x1, y1 = f.rect
        body.append(
            f'<geom name="{f.name}" type="box" group="4" rgba="0 0 1 0.2" '
            f'pos="{_f(((x0 + x1) / 2, (y0 + y1) / 2, f.height / 2))}" '
            f'size="{_f(((x1 - x0) / 2, (y1 - y0) / 2, f.height / 2))}" '
            'contype="0" conaffinity="2" condim="1"/>'
        )
        for k, part in enumerate(f.parts):
            body.append(_part_geom(f"{f.name}_{k}", part))
    for k, part in enumerate(layout.fixtures):
        body.append(_part_geom(f"fixture_{k}", part))
    body.append(
        '<body name="marker" mocap="true" pos="0 0 -1">'
        '<geom name="marker" type="sphere" size="0.01" material="marker" contype="0" '
        'conaffinity="0"/></body>'
    )
    return "\n".join(
        [
            '<mujoco model="naoloc room">',
            '  <include file="nao.xml"/>',
            f'  <option timestep="{timestep:.9g}"/>',
            "  <visual>",
            '    <global offwidth="1280" offheight="960"/>',
            '    <quality shadowsize="0" offsamples="0"/>',
            '    <headlight ambient="0.35 0.35 0.35" diffuse="0.15 0.15 0.15" specular="0 0 0"/>',
            "  </visual>",
            "  <asset>",
            *("    " + a for a in assets),
            "  </asset>",
            "  <worldbody>",
            *("    " + b for b in body),
            "  </worldbody>",
            "</mujoco>",
        ]
    )
