"""Drawing primitives: colours, sensor cones, text and tables, the arena, blocks and robots.

The colours and sizes of every picture live here. ``draw_arena``, ``draw_trails``,
``draw_cones``, ``draw_blocks`` and ``draw_robots`` draw one layer of a ``Renderer`` frame
from the renderer's state (its view: ``to_screen``, ``scale``, ``arena_rect``; its options and
history); ``_Text`` draws text and the morphology table with one font (a no-op without
``pygame.font``); every cone is drawn through ``_draw_cone_layer`` (one transparent layer,
composited once). pygame is passed in (``pg``) or taken from the renderer, never imported here.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ..config import WorldConfig
from ..sensors import Morphology

if TYPE_CHECKING:  # pragma: no cover
    import pygame

    from ..simulation import GatheringSimulation
    from .renderer import Renderer

RGB = tuple[int, int, int]

PAGE: RGB = (250, 250, 247)
"""Background outside the arena and of the panel."""
FLOOR: RGB = (238, 238, 232)
"""Arena floor."""
WALL: RGB = (70, 70, 70)
ZONE: RGB = (196, 232, 196)
"""Gathering zone fill."""
ZONE_EDGE: RGB = (80, 150, 80)
BLOCK_COLOURS: tuple[RGB, RGB, RGB] = ((60, 130, 220), (235, 160, 30), (200, 50, 50))
"""Block fill by type: small, medium, large."""
GATHERED_SHADE = 0.55
"""Gathered blocks are drawn with their colour times this factor, outlined in white."""
GATHERED_EDGE: RGB = (255, 255, 255)
ROBOT: RGB = (30, 30, 30)
"""Robot body."""
ROBOT_ATTACHED: RGB = (230, 0, 170)
"""Body of a robot welded to a block, and the outline of a carried block."""
HEADING: RGB = (255, 255, 255)
"""Heading mark: a line from near the robot's centre to its rim."""
FOCUS: RGB = (255, 120, 0)
"""Ring around the robots whose cones are shown when not all robots' cones are."""
TRAIL: RGB = (70, 70, 220)
"""Colour of the newest trail segment; older segments fade towards the floor colour."""
TEXT: RGB = (20, 20, 20)
MUTED: RGB = (110, 110, 110)
SENSOR_COLOURS: dict[str, RGB] = {
    "infrared": (225, 40, 40),
    "ultrasonic": (40, 90, 225),
    "colour": (160, 50, 200),
    "camera": (0, 150, 150),
    "bottom": (120, 120, 120),
}
"""Cone colour by sensor type."""
CONE_FILL_ALPHA = 24
"""Opacity (0..255) of a cone's fill; never accumulates (one layer for all cones)."""
CONE_EDGE_ALPHA = 150
"""Opacity (0..255) of a cone's outline."""

MIN_BLOCK_PX = 3
"""Blocks are drawn at least this many pixels from centre to side."""

_MAX_ARC_POINTS = 64
_BLOCK_CORNERS = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])


def cone_colour_on(background: RGB, sensor_type: str) -> RGB:
    """The colour a cone's fill of ``sensor_type`` gives on a ``background`` pixel (alpha blend)."""
    a = CONE_FILL_ALPHA / 255.0
    c = SENSOR_COLOURS[sensor_type]
    return tuple(int(round(b * (1.0 - a) + v * a)) for b, v in zip(background, c))  # type: ignore[return-value]


def cone_sensors(morphology: Morphology) -> list[tuple[str, float, float, float, float]]:
    """(type, bearing, axis offset from the heading, range, fov) of every sensor with a cone."""
    return [(s.type, s.bearing, s.bearing + s.orientation, float(s.range), float(s.fov))
            for s in morphology if s.type != "bottom" and (s.range or 0) > 0 and (s.fov or 0) > 0]


def team_cone_cover(morphology: Morphology, config: WorldConfig) -> float:
    """Summed area of every robot's cones over the arena's area (overlaps counted twice)."""
    area = sum(0.5 * rng * rng * fov for _, _, _, rng, fov in cone_sensors(morphology))
    return config.num_robots * area / (config.arena_width * config.arena_height)


def _degrees(angle: float) -> str:
    return f"{math.degrees(angle):+.0f}\u00b0"


def morphology_rows(morphology: Morphology) -> list[tuple[str, str, str, str, str, str]]:
    """The morphology table: (#, type, bearing, orientation, range, FOV) per sensor, as text."""
    rows = []
    for i, s in enumerate(morphology):
        if s.type == "bottom":
            rows.append((str(i), s.type, _degrees(s.bearing), "\u2013", "\u2013", "\u2013"))
        else:
            rows.append((str(i), s.type, _degrees(s.bearing), _degrees(s.orientation),
                         f"{s.range:.1f}" if s.range >= 0.95 else f"{s.range:.2g}", f"{math.degrees(s.fov):.0f}\u00b0"))
    return rows


_TABLE_HEADER = ("#", "type", "bearing", "orient.", "range", "FOV")
_TABLE_WIDEST = ("10", "ultrasonic", "+180\u00b0", "+90\u00b0", "25.0", "180\u00b0")


class _Text:
    """pygame text helpers with one font; every call is a no-op without a font."""

    def __init__(self, pg: Any, size: int) -> None:
        self.pg = pg
        try:
            if not pg.font.get_init():
                pg.font.init()
            self.font = pg.font.Font(None, size)
        except Exception:  # noqa: BLE001 - fonts are optional: no font, no text
            self.font = None

    @property
    def line(self) -> int:
        return self.font.get_linesize() if self.font is not None else 0

    def width(self, text: str) -> int:
        return self.font.size(text)[0] if self.font is not None else 0

    def draw(self, surf: pygame.Surface, text: str, x: int, y: int, colour: RGB = TEXT,
             right: bool = False) -> int:
        """Blit ``text`` with its top-left (top-right if ``right``) at (x, y); returns its width."""
        if self.font is None:
            return 0
        label = self.font.render(text, True, colour)
        surf.blit(label, (x - label.get_width() if right else x, y))
        return label.get_width()

    def table_columns(self, gap: int) -> tuple[list[int], list[int], int]:
        """Left edges and widths of the morphology table's columns, and the table's width."""
        widths = [max(self.width(a), self.width(b)) for a, b in zip(_TABLE_HEADER, _TABLE_WIDEST)]
        lefts = [sum(widths[:i]) + i * gap for i in range(len(widths))]
        return lefts, widths, lefts[-1] + widths[-1]

    def draw_table(self, surf: pygame.Surface, morphology: Morphology, x: int, y: int, gap: int) -> int:
        """Draw the morphology table with a colour swatch per type; returns the height used."""
        if self.font is None:
            return 0
        cols, widths, _ = self.table_columns(gap)
        sw = max(4, self.line // 2)
        rows = [_TABLE_HEADER] + morphology_rows(morphology)
        for r, row in enumerate(rows):
            yy = y + r * self.line
            for c, cell in enumerate(row):
                colour = MUTED if r == 0 else TEXT
                if c == 0:
                    self.draw(surf, cell, x + cols[0] + widths[0], yy, colour, right=True)
                elif c == 1:
                    if r > 0:
                        box = self.pg.Rect(x + cols[1], yy + (self.line - sw) // 2, sw, sw)
                        self.pg.draw.rect(surf, SENSOR_COLOURS[cell], box)
                    self.draw(surf, cell, x + cols[1] + (sw + 3 if r > 0 else 0), yy, colour)
                else:
                    self.draw(surf, cell, x + cols[c] + widths[c], yy, colour, right=True)
        return len(rows) * self.line


def _cone_polygons(pos: np.ndarray, angle: np.ndarray, robot_radius: float, bearing: float,
                   offset: float, rng: float, fov: float, k: int) -> np.ndarray:
    """World polygons (N, k + 1, 2) of one sensor's cone on robots at ``pos``/``angle``."""
    offsets = np.linspace(-0.5 * fov, 0.5 * fov, k)
    mount = angle + bearing
    pts = np.empty((len(pos), k + 1, 2))
    pts[:, 0, 0] = pos[:, 0] + robot_radius * np.cos(mount)
    pts[:, 0, 1] = pos[:, 1] + robot_radius * np.sin(mount)
    arc = (angle + offset)[:, None] + offsets[None, :]
    pts[:, 1:, 0] = pts[:, :1, 0] + rng * np.cos(arc)
    pts[:, 1:, 1] = pts[:, :1, 1] + rng * np.sin(arc)
    return pts


def _arc_points(radius_px: float, fov: float) -> int:
    """Points along a cone's arc so the chord error stays under half a pixel."""
    radius_px = max(radius_px, 1.0)
    step = 2.0 * math.acos(max(-1.0, 1.0 - 0.5 / radius_px))
    return int(min(_MAX_ARC_POINTS, max(2, math.ceil(fov / step) + 1)))


def _draw_cone_layer(pg: Any, layer: pygame.Surface, target: pygame.Surface,
                     polygons: list[tuple[str, list]]) -> None:
    """Fill then outline every (type, screen polygon) in ``layer``, then composite it once."""
    clip = layer.get_clip()
    layer.set_clip(None)
    layer.fill((0, 0, 0, 0))
    layer.set_clip(clip)
    for kind, poly in polygons:
        pg.draw.polygon(layer, SENSOR_COLOURS[kind] + (CONE_FILL_ALPHA,), poly)
    for kind, poly in polygons:
        pg.draw.polygon(layer, SENSOR_COLOURS[kind] + (CONE_EDGE_ALPHA,), poly, 1)
    target.blit(layer, (0, 0))


def _surface_to_array(pg: Any, surf: pygame.Surface) -> np.ndarray:
    view = pg.surfarray.pixels3d(surf)             # (W, H, 3) view, locks the surface
    try:
        return np.ascontiguousarray(view.transpose(1, 0, 2))
    finally:
        del view


# ---------------------------------------------------------------------- the layers of a Renderer frame
def draw_arena(r: Renderer, surf: pygame.Surface) -> None:
    """Wall band, floor and zone."""
    pg, cfg = r._pg, r.config
    left, top, width, height = r.arena_rect
    wp = r.wall_px
    pg.draw.rect(surf, WALL, pg.Rect(left - wp, top - wp, width + 2 * wp, height + 2 * wp))
    pg.draw.rect(surf, FLOOR, pg.Rect(r.arena_rect))
    x0, y0, x1, y1 = cfg.zone_rect
    (sx0, sy1), (sx1, sy0) = r.to_screen(np.array([[x0, y1], [x1, y0]]))
    zl, zt = int(round(sx0)), int(round(sy1))
    zone = pg.Rect(zl, zt, int(round(sx1)) - zl, int(round(sy0)) - zt)
    pg.draw.rect(surf, ZONE, zone)
    pg.draw.rect(surf, ZONE_EDGE, zone, 1)


def draw_trails(r: Renderer, surf: pygame.Surface) -> None:
    """Each robot's recorded path, fading from the floor colour (oldest) to ``TRAIL``."""
    if r._options.trail <= 0 or len(r._history.positions) < 2:
        return
    pg = r._pg
    pts = r.to_screen(np.stack(r._history.positions))             # (T, N, 2), oldest first
    t = len(pts)
    width = 3 if r.scale >= 30 else 2
    for age in range(t - 1):
        f = (age + 1) / (t - 1)                                   # 1 for the newest segment
        colour = tuple(int(round(a + (b - a) * f)) for a, b in zip(FLOOR, TRAIL))
        for a, b in zip(pts[age].tolist(), pts[age + 1].tolist()):
            pg.draw.line(surf, colour, a, b, width)


def draw_cones(r: Renderer, sim: GatheringSimulation, surf: pygame.Surface) -> None:
    """The cones of ``r.cone_robots(sim)`` in one layer, clipped to the arena."""
    pg, w = r._pg, sim.world
    robots = r.cone_robots(sim)
    sensors = cone_sensors(sim.morphology)
    if not sensors or robots.size == 0:
        return
    pos, angle = w.robot_pos[robots], w.robot_angle[robots]
    polygons: list[tuple[str, list]] = []
    for kind, bearing, offset, rng, fov in sensors:
        k = _arc_points(rng * r.scale, fov)
        pts = _cone_polygons(pos, angle, r.config.robot_radius, bearing, offset, rng, fov, k)
        polygons.extend((kind, poly) for poly in r.to_screen(pts).tolist())
    size = r._options.size_px
    clip = pg.Rect(r.arena_rect).clip(pg.Rect(0, 0, size, size))
    r._layer.set_clip(clip)
    _draw_cone_layer(pg, r._layer, surf, polygons)


def draw_blocks(r: Renderer, sim: GatheringSimulation, surf: pygame.Surface) -> None:
    """Blocks as rotated squares; gathered ones shaded and outlined, carried ones outlined."""
    pg, w = r._pg, sim.world
    n = len(w.block_pos)
    if n == 0:
        return
    half = np.asarray(w.block_half, dtype=float)
    half = np.maximum(half, MIN_BLOCK_PX / r.scale)
    c, s = np.cos(w.block_angle), np.sin(w.block_angle)
    local = _BLOCK_CORNERS[None, :, :] * half[:, None, None]               # (B, 4, 2)
    world_pts = np.empty_like(local)
    world_pts[..., 0] = w.block_pos[:, None, 0] + c[:, None] * local[..., 0] - s[:, None] * local[..., 1]
    world_pts[..., 1] = w.block_pos[:, None, 1] + s[:, None] * local[..., 0] + c[:, None] * local[..., 1]
    corners = r.to_screen(world_pts).tolist()
    gathered = np.asarray(sim.gathered, dtype=bool).tolist()
    attached = np.asarray(w.robot_attached)
    carried = set(attached[attached >= 0].tolist())
    types = np.asarray(w.block_type).tolist()
    edge_w = 2 if r.scale * 0.6 >= 12 else 1
    for j in range(n):
        colour = BLOCK_COLOURS[types[j]]
        if gathered[j]:
            colour = tuple(int(v * GATHERED_SHADE) for v in colour)
        pg.draw.polygon(surf, colour, corners[j])
        if gathered[j]:
            pg.draw.polygon(surf, GATHERED_EDGE, corners[j], edge_w)
        elif j in carried:
            pg.draw.polygon(surf, ROBOT_ATTACHED, corners[j], edge_w)


def draw_robots(r: Renderer, sim: GatheringSimulation, surf: pygame.Surface) -> None:
    """Robot discs with heading marks, and a focus ring when only some robots' cones are shown."""
    pg, w = r._pg, sim.world
    n = len(w.robot_pos)
    rad = r.robot_px
    centres = r.to_screen(w.robot_pos)
    heading = np.stack([np.cos(w.robot_angle), -np.sin(w.robot_angle)], axis=1)
    starts = (centres + 0.35 * rad * heading).tolist()
    tips = (centres + (rad - 0.5) * heading).tolist()
    stubs = (centres + (rad + max(3, rad // 2 + 1)) * heading).tolist()
    centres_i = np.rint(centres).astype(int).tolist()
    attached = (np.asarray(w.robot_attached) >= 0).tolist()
    focus = r.cone_robots(sim)
    focus = focus.tolist() if 0 < focus.size < n else []
    mark_w = max(1, rad // 4)
    for i in focus:
        pg.draw.circle(surf, FOCUS, centres_i[i], rad + max(2, rad // 2), max(1, rad // 4))
    for i in range(n):
        colour = ROBOT_ATTACHED if attached[i] else ROBOT
        pg.draw.line(surf, colour, centres_i[i], stubs[i], mark_w + 1)
        pg.draw.circle(surf, colour, centres_i[i], rad)
        pg.draw.line(surf, HEADING, starts[i], tips[i], mark_w)
