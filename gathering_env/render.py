"""Drawing the collective gathering world with pygame, and saving episodes as GIF/MP4.

The picture follows the paper's Figure 3, seen from above:

* the arena floor (``config.arena_width`` x ``config.arena_height`` units) inside a dark wall
  band, and the gathering zone (``config.zone_rect``) along the south wall in green;
* blocks as rotated squares coloured by size (small blue, medium amber, large red); gathered
  blocks (``sim.gathered``) are drawn darker with a white outline;
* robots as dark discs with a heading stub; robots welded to a block
  (``world.robot_attached >= 0``) are magenta;
* every robot's sensor cones (circular sectors of radius ``range`` and full angle ``fov`` from
  the sensor's mount point on the rim, as in ``sensing.py``) drawn semi-transparently,
  coloured by sensor type. Overlapping cones of one type do not darken each other; cones of
  different types blend. Cones are clipped at the walls. Bottom sensors (no cone) are not drawn;
* a header with the step count, the gathered value / total value and a legend, when
  ``pygame.font`` works (otherwise the header is left out).

World y points up (north); screen y points down, so y is flipped. The robots are honest-sized
(0.15 units is ~2.3 px at 640 px for a 40 x 40 arena) but never drawn smaller than 2 px.

Usage::

    renderer = Renderer(config, "rgb_array", size_px=640)
    frame = renderer.render(sim)          # (640, 640, 3) uint8, no window, no display needed
    save_video(frames, "episode.gif")     # or .mp4 with imageio-ffmpeg

pygame is imported lazily by ``Renderer`` so importing ``gathering_env`` does not need it.
``"rgb_array"`` draws on an offscreen ``pygame.Surface`` and never opens a window; only
``"human"`` initialises pygame's display.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .config import WorldConfig
from .sensors import SENSOR_TYPES, TYPE_CODES

if TYPE_CHECKING:  # pragma: no cover
    import pygame

    from .simulation import GatheringSimulation

RGB = tuple[int, int, int]

PAGE: RGB = (250, 250, 247)
"""Background outside the arena and behind the header."""
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
"""Robot body (and heading stub)."""
ROBOT_ATTACHED: RGB = (230, 0, 170)
"""Body of a robot welded to a block."""
TEXT: RGB = (20, 20, 20)
SENSOR_COLOURS: dict[str, RGB] = {
    "infrared": (225, 40, 40),
    "ultrasonic": (40, 90, 225),
    "colour": (160, 50, 200),
    "camera": (0, 160, 160),
    "bottom": (120, 120, 120),
}
"""Cone colour by sensor type (drawn with alpha ``CONE_ALPHA``)."""
CONE_ALPHA = 50
"""Opacity of a sensor cone, 0..255."""

_TYPE_NAMES = list(SENSOR_TYPES)                 # index = integer type code
_BOTTOM = TYPE_CODES["bottom"]
_MAX_ARC_POINTS = 64
_BLOCK_CORNERS = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])


def cone_colour_on(background: RGB, sensor_type: str) -> RGB:
    """The colour a single cone of ``sensor_type`` gives on a ``background`` pixel (alpha blend)."""
    a = CONE_ALPHA / 255.0
    c = SENSOR_COLOURS[sensor_type]
    return tuple(int(round(b * (1.0 - a) + v * a)) for b, v in zip(background, c))  # type: ignore[return-value]


class Renderer:
    """Draws a ``GatheringSimulation`` as a square picture.

    Args:
        config: the world's config (arena size, zone, robot radius).
        render_mode: ``"rgb_array"`` (``render`` returns frames; offscreen, never opens a
            window) or ``"human"`` (``render`` shows the frame in a pygame window).
        size_px: width = height of the picture in pixels (>= 64). The arena is scaled
            uniformly to fit (non-square arenas are centred).
        fps: frame rate the ``"human"`` window is throttled to (frames per second).

    Attributes:
        scale: pixels per world unit.
        arena_rect: (left, top, width, height) of the arena floor in pixels.
    """

    def __init__(self, config: WorldConfig, render_mode: str, size_px: int = 640, fps: int = 30) -> None:
        if render_mode not in ("rgb_array", "human"):
            raise ValueError(f"render_mode={render_mode!r}; allowed: 'rgb_array', 'human'")
        if isinstance(size_px, bool) or not isinstance(size_px, (int, np.integer)) or size_px < 64:
            raise ValueError(f"size_px={size_px!r}; allowed: an integer >= 64")
        if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)) or not fps > 0:
            raise ValueError(f"fps={fps!r}; allowed: a number > 0")
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        import pygame

        self._pg = pygame
        self.config = config
        self.render_mode = render_mode
        self.size_px = int(size_px)
        self.fps = fps
        self._window: pygame.Surface | None = None
        self._clock: pygame.time.Clock | None = None
        self._font = self._load_font()
        self._legend_cache: dict[tuple[int, ...], pygame.Surface] = {}

        # Layout: header (text) on top, then the arena inside its wall band, centred.
        size = self.size_px
        self.wall_px = max(2, int(round(size / 100)))
        pad = self.wall_px + 2
        if self._font is not None and size >= 200:
            self.header_px = 2 * self._font.get_linesize() + 6
        else:
            self.header_px = 0
        avail_w = size - 2 * pad
        avail_h = size - self.header_px - 2 * pad
        self.scale = min(avail_w / config.arena_width, avail_h / config.arena_height)
        self._ox = 0.5 * (size - config.arena_width * self.scale)
        self._oy = self.header_px + pad + 0.5 * (avail_h - config.arena_height * self.scale)
        left, top = int(round(self._ox)), int(round(self._oy))
        self.arena_rect = (left, top,
                           int(round(self._ox + config.arena_width * self.scale)) - left,
                           int(round(self._oy + config.arena_height * self.scale)) - top)
        self.robot_px = max(2, int(round(config.robot_radius * self.scale)))

        self._surface = pygame.Surface((size, size))
        self._background = self._draw_background()
        # One transparent layer per cone type, created when first needed.
        self._layers: dict[int, pygame.Surface] = {}

    # ------------------------------------------------------------------ geometry
    def to_screen(self, xy: np.ndarray) -> np.ndarray:
        """World coordinates (..., 2) in units -> screen pixels (..., 2) as floats, y flipped.

        The pixel containing a world point is ``to_screen(p).astype(int)`` -> (column, row).
        """
        xy = np.asarray(xy, dtype=float)
        out = np.empty(xy.shape, dtype=float)
        out[..., 0] = self._ox + xy[..., 0] * self.scale
        out[..., 1] = self._oy + (self.config.arena_height - xy[..., 1]) * self.scale
        return out

    def _arc_points(self, range_units: float, fov: float) -> int:
        """Points along a cone's arc so the chord error stays under half a pixel."""
        radius_px = max(range_units * self.scale, 1.0)
        step = 2.0 * math.acos(max(-1.0, 1.0 - 0.5 / radius_px))
        return int(min(_MAX_ARC_POINTS, max(2, math.ceil(fov / step) + 1)))

    # ------------------------------------------------------------------ drawing
    def _load_font(self):
        """pygame's default font, or None if ``pygame.font`` is unavailable."""
        pg = self._pg
        try:
            if not pg.font.get_init():
                pg.font.init()
            return pg.font.Font(None, max(14, self.size_px // 36))
        except Exception:  # noqa: BLE001 - fonts are optional: no font, no text
            return None

    def _draw_background(self) -> pygame.Surface:
        """The static part of every frame: page, wall band, floor and zone."""
        pg, cfg = self._pg, self.config
        bg = pg.Surface((self.size_px, self.size_px))
        bg.fill(PAGE)
        left, top, width, height = self.arena_rect
        wp = self.wall_px
        pg.draw.rect(bg, WALL, pg.Rect(left - wp, top - wp, width + 2 * wp, height + 2 * wp))
        pg.draw.rect(bg, FLOOR, pg.Rect(self.arena_rect))
        x0, y0, x1, y1 = cfg.zone_rect
        (sx0, sy1), (sx1, sy0) = self.to_screen(np.array([[x0, y1], [x1, y0]]))
        zl, zt = int(round(sx0)), int(round(sy1))
        zone = pg.Rect(zl, zt, int(round(sx1)) - zl, int(round(sy0)) - zt)
        pg.draw.rect(bg, ZONE, zone)
        pg.draw.rect(bg, ZONE_EDGE, zone, 1)
        return bg

    def draw(self, sim: GatheringSimulation) -> pygame.Surface:
        """Draw the current state of ``sim`` onto the internal surface and return it.

        The surface is reused by the next call; copy it if you keep it.
        """
        if not hasattr(sim, "gathered") or getattr(sim.world, "space", None) is None:
            raise RuntimeError("render() called before the simulation was reset; call reset() first")
        surf = self._surface
        surf.blit(self._background, (0, 0))
        self._draw_cones(sim, surf)
        self._draw_blocks(sim, surf)
        self._draw_robots(sim, surf)
        self._draw_header(sim, surf)
        return surf

    def _draw_blocks(self, sim: GatheringSimulation, surf: pygame.Surface) -> None:
        pg, w = self._pg, sim.world
        n = len(w.block_half)
        if n == 0:
            return
        c, s = np.cos(w.block_angle), np.sin(w.block_angle)
        local = _BLOCK_CORNERS[None, :, :] * w.block_half[:, None, None]            # (B, 4, 2)
        world_pts = np.empty_like(local)
        world_pts[..., 0] = w.block_pos[:, None, 0] + c[:, None] * local[..., 0] - s[:, None] * local[..., 1]
        world_pts[..., 1] = w.block_pos[:, None, 1] + s[:, None] * local[..., 0] + c[:, None] * local[..., 1]
        corners = self.to_screen(world_pts).tolist()
        gathered = np.asarray(sim.gathered, dtype=bool)
        types = w.block_type.tolist()
        for j in range(n):
            colour = BLOCK_COLOURS[types[j]]
            if gathered[j]:
                colour = tuple(int(v * GATHERED_SHADE) for v in colour)
                pg.draw.polygon(surf, colour, corners[j])
                pg.draw.polygon(surf, GATHERED_EDGE, corners[j], 1)
            else:
                pg.draw.polygon(surf, colour, corners[j])

    def _draw_robots(self, sim: GatheringSimulation, surf: pygame.Surface) -> None:
        pg, w = self._pg, sim.world
        rad = self.robot_px
        stub = rad + max(2, rad // 2 + 1)          # heading stub length from the centre (px)
        centres = self.to_screen(w.robot_pos)
        tips = centres + stub * np.stack([np.cos(w.robot_angle), -np.sin(w.robot_angle)], axis=1)
        centres_i = np.rint(centres).astype(int).tolist()
        tips_l = tips.tolist()
        attached = (np.asarray(w.robot_attached) >= 0).tolist()
        width = 1 if rad < 4 else 2
        for i in range(len(centres_i)):
            colour = ROBOT_ATTACHED if attached[i] else ROBOT
            pg.draw.line(surf, colour, centres_i[i], tips_l[i], width)
            pg.draw.circle(surf, colour, centres_i[i], rad)

    def _cone_sensors(self, sim: GatheringSimulation) -> list[tuple[int, float, float, float, float]]:
        """(type code, bearing, axis offset, range, fov) of every sensor with a cone."""
        bank = getattr(sim, "bank", None)
        if bank is not None:
            half = np.arctan2(bank.sin_half, bank.cos_half)
            rows = zip(bank.types.tolist(), bank.bearing.tolist(), bank.axis_offset.tolist(),
                       bank.range.tolist(), (2.0 * half).tolist())
        else:
            rows = ((TYPE_CODES[s.type], s.bearing, s.bearing + s.orientation, s.range, s.fov)
                    for s in sim.morphology)
        return [r for r in rows if r[0] != _BOTTOM and r[3] > 0.0 and r[4] > 0.0]

    def _layer(self, code: int) -> pygame.Surface:
        layer = self._layers.get(code)
        if layer is None:
            pg = self._pg
            layer = pg.Surface((self.size_px, self.size_px), pg.SRCALPHA)
            layer.set_clip(pg.Rect(self.arena_rect))
            self._layers[code] = layer
        return layer

    def _draw_cones(self, sim: GatheringSimulation, surf: pygame.Surface) -> None:
        pg, w = self._pg, sim.world
        sensors = self._cone_sensors(sim)
        if not sensors or len(w.robot_pos) == 0:
            return
        r = self.config.robot_radius
        pos, angle = w.robot_pos, w.robot_angle
        used: list[int] = []
        for code, bearing, offset, rng, fov in sensors:
            layer = self._layer(code)
            if code not in used:
                layer.fill((0, 0, 0, 0))
                used.append(code)
            colour = SENSOR_COLOURS[_TYPE_NAMES[code]] + (CONE_ALPHA,)
            k = self._arc_points(rng, fov)
            offsets = np.linspace(-0.5 * fov, 0.5 * fov, k)                      # (K,)
            mount_angle = angle + bearing                                        # (N,)
            pts = np.empty((len(pos), k + 1, 2))
            pts[:, 0, 0] = pos[:, 0] + r * np.cos(mount_angle)
            pts[:, 0, 1] = pos[:, 1] + r * np.sin(mount_angle)
            arc = (angle + offset)[:, None] + offsets[None, :]                    # (N, K)
            pts[:, 1:, 0] = pts[:, :1, 0] + rng * np.cos(arc)
            pts[:, 1:, 1] = pts[:, :1, 1] + rng * np.sin(arc)
            for poly in self.to_screen(pts).tolist():
                pg.draw.polygon(layer, colour, poly)
        for code in used:
            surf.blit(self._layers[code], (0, 0))

    def _draw_header(self, sim: GatheringSimulation, surf: pygame.Surface) -> None:
        font = self._font
        if font is None or self.header_px == 0:
            return
        try:
            n_blocks = len(sim.gathered)
            text = (f"step {sim.steps}/{self.config.max_cycles}    gathered value "
                    f"{sim.gathered_value:g}/{sim.total_value:g}    blocks {int(np.sum(sim.gathered))}/{n_blocks}")
            surf.blit(font.render(text, True, TEXT), (6, 3))
            codes = tuple(sorted({s[0] for s in self._cone_sensors(sim)}))
            legend = self._legend_cache.get(codes)
            if legend is None:
                legend = self._legend_cache[codes] = self._make_legend(codes)
            surf.blit(legend, (6, 3 + font.get_linesize()))
        except Exception:  # noqa: BLE001 - text is decoration; never fail a frame over it
            self._font = None

    def _make_legend(self, cone_codes: tuple[int, ...]) -> pygame.Surface:
        """One line of colour swatches and names: block sizes, gathered, attached, cone types."""
        pg, font = self._pg, self._font
        h = font.get_linesize()
        legend = pg.Surface((self.size_px - 12, h))
        legend.fill(PAGE)
        sw = max(6, h - 5)
        x = 0
        items: list[tuple[str, RGB, RGB | None, bool]] = [
            ("small", BLOCK_COLOURS[0], None, False),
            ("medium", BLOCK_COLOURS[1], None, False),
            ("large", BLOCK_COLOURS[2], None, False),
            ("gathered", tuple(int(v * GATHERED_SHADE) for v in BLOCK_COLOURS[1]), GATHERED_EDGE, False),
            ("robot", ROBOT, None, True),
            ("attached", ROBOT_ATTACHED, None, True),
        ]
        for code in cone_codes:
            name = _TYPE_NAMES[code]
            items.append((name, cone_colour_on(FLOOR, name), SENSOR_COLOURS[name], False))
        top = (h - sw) // 2
        for name, fill, edge, disc in items:
            if disc:
                pg.draw.circle(legend, fill, (x + sw // 2, top + sw // 2), max(2, sw // 3))
            else:
                box = pg.Rect(x, top, sw, sw)
                pg.draw.rect(legend, fill, box)
                if edge is not None:
                    pg.draw.rect(legend, edge, box, 1)
            x += sw + 3
            label = font.render(name, True, TEXT)
            legend.blit(label, (x, (h - label.get_height()) // 2))
            x += label.get_width() + 10
        return legend

    # ------------------------------------------------------------------ output
    def render(self, sim: GatheringSimulation) -> np.ndarray | None:
        """Draw ``sim``'s current state.

        Returns:
            ``"rgb_array"``: the frame, a new ``(size_px, size_px, 3)`` uint8 array (rows =
            screen y, top = north). ``"human"``: None (the frame is shown in a window).
        """
        surf = self.draw(sim)
        pg = self._pg
        if self.render_mode == "rgb_array":
            view = pg.surfarray.pixels3d(surf)             # (W, H, 3) view, locks the surface
            try:
                frame = np.ascontiguousarray(view.transpose(1, 0, 2))
            finally:
                del view
            return frame
        if self._window is None:
            try:
                pg.display.init()
                self._window = pg.display.set_mode((self.size_px, self.size_px))
            except pg.error as err:
                raise RuntimeError(
                    f"render_mode='human' could not open a window ({err}); "
                    "use render_mode='rgb_array' without a display"
                ) from None
            pg.display.set_caption("collective gathering")
            self._clock = pg.time.Clock()
        for event in pg.event.get():
            if event.type == pg.QUIT:
                self.close()
                return None
        self._window.blit(surf, (0, 0))
        pg.display.flip()
        self._clock.tick(self.fps)
        return None

    def close(self) -> None:
        """Close the ``"human"`` window if one is open (safe to call more than once)."""
        if self._window is not None:
            self._window = None
            self._clock = None
            self._pg.display.quit()


def save_video(frames: Sequence[np.ndarray], path: str | os.PathLike, fps: int = 20) -> Path:
    """Write frames to a ``.gif`` (imageio + pillow) or ``.mp4`` (needs ``imageio-ffmpeg``).

    Args:
        frames: equally shaped ``(H, W, 3)`` uint8 arrays, e.g. from ``Renderer.render``.
        path: output file; the suffix picks the format. Parent folders are created.
        fps: playback rate (frames per second, > 0).

    Returns:
        The path written.

    Raises:
        ValueError: no frames, frames of different or wrong shapes, a bad ``fps``, an
            unsupported suffix, or ``.mp4`` without ``imageio-ffmpeg`` (``pip install imageio-ffmpeg``).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ValueError(f"video file {str(path)!r} has suffix {suffix!r}; allowed: '.gif', '.mp4'")
    frames = list(frames)
    if not frames:
        raise ValueError("save_video: no frames to write")
    if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)) or not fps > 0:
        raise ValueError(f"save_video: fps={fps!r}; allowed: a number > 0")
    arrays = [np.asarray(f) for f in frames]
    shape = arrays[0].shape
    if len(shape) != 3 or shape[2] != 3:
        raise ValueError(f"save_video: frames must have shape (H, W, 3); frame 0 has {shape}")
    for i, a in enumerate(arrays):
        if a.shape != shape:
            raise ValueError(f"save_video: frame {i} has shape {a.shape}; frame 0 has {shape}")
    arrays = [a if a.dtype == np.uint8 else np.clip(a, 0, 255).astype(np.uint8) for a in arrays]

    import imageio.v2 as imageio

    if suffix == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise ValueError(
                "writing .mp4 needs ffmpeg through imageio-ffmpeg: pip install imageio-ffmpeg "
                "(or the project's 'video' extra); .gif works without it"
            ) from None
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".gif":
        imageio.mimsave(path, arrays, duration=1000.0 / fps, loop=0)
    else:
        h, w = shape[:2]
        if h % 2 or w % 2:     # H.264 in yuv420p needs even sizes: pad by repeating the edge
            arrays = [np.pad(a, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge") for a in arrays]
        imageio.mimsave(path, arrays, fps=fps, macro_block_size=1)
    return path
