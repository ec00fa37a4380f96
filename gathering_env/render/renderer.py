"""The Renderer: pygame drawing of the gathering world (see the package docstring, ``gathering_env.render``)."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..config import BLOCK_TYPE_NAMES, WorldConfig
from ..sensors import SENSOR_TYPES, Morphology
from .drawing import (
    BLOCK_COLOURS,
    FLOOR,
    GATHERED_EDGE,
    GATHERED_SHADE,
    HEADING,
    MUTED,
    PAGE,
    RGB,
    ROBOT,
    ROBOT_ATTACHED,
    SENSOR_COLOURS,
    TEXT,
    TRAIL,
    ZONE_EDGE,
    _arc_points,
    _draw_cone_layer,
    _surface_to_array,
    _Text,
    cone_colour_on,
    cone_sensors,
    draw_arena,
    draw_blocks,
    draw_cones,
    draw_robots,
    draw_trails,
    team_cone_cover,
)
from .options import AUTO_CONES_COVER, DEFAULT_SIZE_PX, FOLLOW_SPAN, ZONE_MARGIN, RenderOptions

if TYPE_CHECKING:  # pragma: no cover
    import pygame

    from ..simulation import GatheringSimulation

KEYS = "space pause   right step   +/- speed   c cones   esc close"
"""The ``"human"`` window's keys, as listed in the window."""

_CONE_ORDER = [t for t in SENSOR_TYPES if t != "bottom"]


class Renderer:
    """Draws a ``GatheringSimulation``: a square arena view plus the information panel.

    Args:
        config: the world's config (arena size, zone, robot radius, team size).
        render_mode: ``"rgb_array"`` (``render`` returns frames; offscreen, never opens a
            window) or ``"human"`` (``render`` shows the frame in a pygame window).
        size_px: side of the square arena view in pixels (>= 64).
        fps: frame rate the ``"human"`` window is throttled to (frames per second).
        **options: the other render options (``cones``, ``view``, ``trail``, ``panel``,
            ``min_robot_px``; see the module docstring).

    A frame is ``(size_px, size_px + panel_px, 3)``: the arena view on the left, the panel (if
    any) on the right.

    Attributes:
        scale: pixels per world unit (of the last frame drawn, for the follow view).
        arena_rect: (left, top, width, height) of the arena floor in pixels (idem).
        panel_px: width of the panel in pixels (0 without it).
        sparkline_rect: the panel's sparkline box (a ``pygame.Rect``) once a panel was drawn.
    """

    def __init__(self, config: WorldConfig, render_mode: str, size_px: int = DEFAULT_SIZE_PX,
                 fps: float = 30, **options: Any) -> None:
        if render_mode not in ("rgb_array", "human"):
            raise ValueError(f"render_mode={render_mode!r}; allowed: 'rgb_array', 'human'")
        if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)) or not fps > 0:
            raise ValueError(f"fps={fps!r}; allowed: a number > 0")
        opts = RenderOptions.checked(config.num_robots, size_px=size_px, **options)
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        import pygame

        self._pg = pygame
        self.config = config
        self.render_mode = render_mode
        self.fps = float(fps)
        self._window: pygame.Surface | None = None
        self._clock: pygame.time.Clock | None = None
        self.paused = False
        self._cone_toggle = 0            # "human" key c: 0 = options.cones, 1 = "all", 2 = "none"
        # History of the episode, recorded by ``record`` (every step when driven by the env).
        self._last_step = -1
        self._value_steps: list[int] = []
        self._values: list[float] = []
        self._positions: list[np.ndarray] = []
        self._configure(opts)

    # ------------------------------------------------------------------ options and layout
    @property
    def options(self) -> RenderOptions:
        return self._options

    @property
    def size_px(self) -> int:
        return self._options.size_px

    def set_options(self, **options: Any) -> None:
        """Change render options from now on (validated like the constructor's)."""
        self._configure(RenderOptions.checked(self.config.num_robots, self._options, **options))

    def _configure(self, opts: RenderOptions) -> None:
        pg = self._pg
        self._options = opts
        size = opts.size_px
        self._text = _Text(pg, max(13, size // 32))
        self._small = _Text(pg, max(12, size // 40))
        self.wall_px = max(2, int(round(size / 100)))
        if opts.panel:
            gap = max(6, self._text.width("00"))
            table_w = self._text.table_columns(gap)[2] if self._text.font is not None else 0
            self.panel_px = max(size // 3, table_w + 2 * self._margin)
        else:
            self.panel_px = 0
        shape = (size + self.panel_px, size)
        if getattr(self, "_surface", None) is None or self._surface.get_size() != shape:
            self._surface = pg.Surface(shape)
            self._layer = pg.Surface((size, size), pg.SRCALPHA)
        self._set_view(0.5 * self.config.arena_width, 0.5 * self.config.arena_height, None)

    @property
    def _margin(self) -> int:
        return max(6, self._options.size_px // 64)

    def _set_view(self, cx: float, cy: float, span: float | None) -> None:
        """Map world point (cx, cy) to the view's centre; ``span`` units across (None: arena)."""
        cfg, size = self.config, self._options.size_px
        if span is None:
            avail = size - 2 * (self.wall_px + 2)
            self.scale = min(avail / cfg.arena_width, avail / cfg.arena_height)
        else:
            self.scale = size / span
        self._ox = 0.5 * size - cx * self.scale
        self._oy = 0.5 * size + cy * self.scale
        (left, top), (right, bottom) = self.to_screen(np.array([[0.0, cfg.arena_height], [cfg.arena_width, 0.0]]))
        left, top = int(round(left)), int(round(top))
        self.arena_rect = (left, top, int(round(right)) - left, int(round(bottom)) - top)

    def _view_for(self, sim: GatheringSimulation) -> None:
        cfg, opts = self.config, self._options
        follow = opts.follow
        if follow is not None:
            x, y = sim.world.robot_pos[follow]
            self._set_view(float(x), float(y), FOLLOW_SPAN)
        elif opts.view == "zone":
            x0, y0, x1, y1 = cfg.zone_rect
            span = max(x1 - x0, y1 - y0) + 2 * ZONE_MARGIN
            edge = 0.5                                           # show a little of the wall
            centre = []
            for c, extent in ((0.5 * (x0 + x1), cfg.arena_width), (0.5 * (y0 + y1), cfg.arena_height)):
                lo, hi = 0.5 * span - edge, extent + edge - 0.5 * span
                centre.append(0.5 * extent if lo > hi else min(max(c, lo), hi))
            self._set_view(centre[0], centre[1], span)
        else:
            self._set_view(0.5 * cfg.arena_width, 0.5 * cfg.arena_height, None)

    # ------------------------------------------------------------------ geometry
    def to_screen(self, xy: np.ndarray) -> np.ndarray:
        """World coordinates (..., 2) in units -> frame pixels (..., 2) as floats, y flipped.

        The pixel containing a world point is ``to_screen(p).astype(int)`` -> (column, row).
        """
        xy = np.asarray(xy, dtype=float)
        out = np.empty(xy.shape, dtype=float)
        out[..., 0] = self._ox + xy[..., 0] * self.scale
        out[..., 1] = self._oy - xy[..., 1] * self.scale
        return out

    @property
    def robot_px(self) -> int:
        """Drawn robot radius in pixels: true size, at least ``min_robot_px``."""
        return max(self._options.min_robot_px, int(round(self.config.robot_radius * self.scale)))

    def cone_robots(self, sim: GatheringSimulation) -> np.ndarray:
        """Indices of the robots whose cones are drawn (after the ``"human"`` key c)."""
        n = len(sim.world.robot_pos)
        cones = (self._options.cones, "all", "none")[self._cone_toggle]
        if cones == "none":
            return np.arange(0)
        if cones == "all":
            return np.arange(n)
        if cones == "auto":
            if team_cone_cover(sim.morphology, self.config) <= AUTO_CONES_COVER:
                return np.arange(n)
            return np.array([self._options.follow or 0])
        return np.array(cones, dtype=int)

    # ------------------------------------------------------------------ history
    def record(self, sim: GatheringSimulation) -> None:
        """Note the current step (gathered value, robot positions) for the sparkline and trails.

        The env calls this after every reset and step; ``render`` calls it too. A step count
        lower than the last one (or 0) starts a new history.
        """
        steps = int(sim.steps)
        if steps == self._last_step and steps != 0:
            return
        if steps == 0 or steps < self._last_step:
            self._value_steps, self._values, self._positions = [], [], []
        self._last_step = steps
        self._value_steps.append(steps)
        self._values.append(float(sim.gathered_value))
        keep = self._options.trail
        if keep > 0:
            self._positions.append(np.array(sim.world.robot_pos, dtype=float))
            del self._positions[:-(keep + 1)]

    # ------------------------------------------------------------------ drawing
    def draw(self, sim: GatheringSimulation) -> pygame.Surface:
        """Draw the current state of ``sim`` onto the internal surface and return it.

        The surface is reused by the next call; copy it if you keep it.
        """
        if not hasattr(sim, "gathered") or getattr(sim.world, "robot_pos", None) is None:
            raise RuntimeError("render() called before the simulation was reset; call reset() first")
        self.record(sim)
        pg, surf = self._pg, self._surface
        size = self._options.size_px
        self._view_for(sim)
        surf.fill(PAGE)
        surf.set_clip(pg.Rect(0, 0, size, size))
        draw_arena(self, surf)
        draw_trails(self, surf)
        draw_cones(self, sim, surf)
        draw_blocks(self, sim, surf)
        draw_robots(self, sim, surf)
        if self.render_mode == "human" and self._window is not None and not self.panel_px:
            self._draw_keys(surf, 4, size - self._small.line - 4)
        surf.set_clip(None)
        if self.panel_px:
            self._draw_panel(sim, surf)
        return surf

    # ------------------------------------------------------------------ panel
    def _draw_panel(self, sim: GatheringSimulation, surf: pygame.Surface) -> None:
        pg, text, small = self._pg, self._text, self._small
        size, m = self._options.size_px, self._margin
        x0 = size + m
        width = self.panel_px - 2 * m
        pg.draw.line(surf, (210, 210, 205), (size, 0), (size, size - 1))
        y = m
        cfg = self.config
        text.draw(surf, f"step {sim.steps} / {cfg.max_cycles}", x0, y)
        y += text.line
        text.draw(surf, f"gathered value {sim.gathered_value:g} / {sim.total_value:g}", x0, y)
        y += text.line
        types = np.asarray(sim.world.block_type)
        gathered = np.asarray(sim.gathered, dtype=bool)
        sw = max(6, text.line - 6)
        for t, name in enumerate(BLOCK_TYPE_NAMES):
            total = int(np.sum(types == t))
            if total == 0:
                continue
            done = int(np.sum(gathered & (types == t)))
            pg.draw.rect(surf, BLOCK_COLOURS[t], pg.Rect(x0, y + (text.line - sw) // 2, sw, sw))
            text.draw(surf, f"{name} {done} / {total}", x0 + sw + 4, y)
            y += text.line
        y += m // 2
        # sparkline of the gathered value over the episode
        spark_h = max(24, size // 10)
        small.draw(surf, "gathered value over the episode", x0, y, MUTED)
        y += small.line + 2
        self.sparkline_rect = pg.Rect(x0, y, width, spark_h)
        self._draw_sparkline(surf, self.sparkline_rect, sim.total_value)
        y += spark_h + m
        # morphology table
        text.draw(surf, f"sensors ({len(sim.morphology)}, every robot)", x0, y)
        y += text.line
        y += text.draw_table(surf, sim.morphology, x0, y, max(6, text.width("00"))) + m // 2
        # legend
        y = self._draw_legend(surf, sim, x0, y, width) + m // 2
        small.draw(surf, f"view {self._options.view}, cones {self._cones_label(sim)}"
                   + (f", trail {self._options.trail}" if self._options.trail else ""), x0, y, MUTED)
        y += small.line
        if self.render_mode == "human" and self._window is not None:
            self._draw_keys(surf, x0, max(y + 2, size - m - 2 * small.line), width)

    def _cones_label(self, sim: GatheringSimulation) -> str:
        robots = self.cone_robots(sim)
        if robots.size == len(sim.world.robot_pos):
            return "all"
        if robots.size == 0:
            return "none"
        return "robot " + ",".join(str(i) for i in robots.tolist())

    def _draw_sparkline(self, surf: pygame.Surface, box: pygame.Rect, total: float) -> None:
        pg = self._pg
        pg.draw.rect(surf, (255, 255, 255), box)
        pg.draw.rect(surf, (200, 200, 195), box, 1)
        if not self._values:
            return
        steps = np.asarray(self._value_steps, dtype=float)
        values = np.asarray(self._values, dtype=float)
        x_max = max(float(self.config.max_cycles), 1.0)
        cols = np.arange(box.width - 2)
        at = cols / max(box.width - 3, 1) * x_max
        at = at[at <= steps[-1]]
        idx = np.searchsorted(steps, at, side="right") - 1
        v = values[np.maximum(idx, 0)] / max(total, 1e-12)
        xs = box.left + 1 + np.arange(len(at))
        ys = box.bottom - 2 - v * (box.height - 4)
        pts = np.stack([xs, ys], axis=1).tolist()
        if len(pts) >= 2:
            pg.draw.lines(surf, ZONE_EDGE, False, pts, 2)
        elif pts:
            pg.draw.circle(surf, ZONE_EDGE, pts[0], 2)

    def _draw_legend(self, surf: pygame.Surface, sim: GatheringSimulation, x0: int, y: int, width: int) -> int:
        """Swatches with names, wrapped to the panel width; returns the y below them."""
        pg, small = self._pg, self._small
        h = max(small.line, 10)
        sw = max(6, h - 4)
        kinds = sorted({c[0] for c in cone_sensors(sim.morphology)}, key=_CONE_ORDER.index)
        items: list[tuple[str, str, RGB, RGB | None]] = [
            ("gathered", "box", tuple(int(v * GATHERED_SHADE) for v in BLOCK_COLOURS[1]), GATHERED_EDGE),
            ("carried", "box", BLOCK_COLOURS[1], ROBOT_ATTACHED),
            ("robot", "disc", ROBOT, None),
            ("attached", "disc", ROBOT_ATTACHED, None),
        ]
        if self._options.trail:
            items.append(("trail", "line", TRAIL, None))
        items += [(kind, "box", cone_colour_on(FLOOR, kind), SENSOR_COLOURS[kind]) for kind in kinds]
        x = x0
        for name, shape, fill, edge in items:
            need = sw + 3 + small.width(name) + 10
            if x > x0 and x + need > x0 + width:
                x, y = x0, y + h
            top = y + (h - sw) // 2
            if shape == "disc":
                pg.draw.circle(surf, fill, (x + sw // 2, top + sw // 2), sw // 2)
                pg.draw.line(surf, HEADING, (x + sw // 2 + 1, top + sw // 2), (x + sw - 1, top + sw // 2))
            elif shape == "line":
                pg.draw.line(surf, fill, (x, top + sw // 2), (x + sw, top + sw // 2), 2)
            else:
                box = pg.Rect(x, top, sw, sw)
                pg.draw.rect(surf, fill, box)
                pg.draw.rect(surf, edge, box, 2 if name == "carried" else 1)
            small.draw(surf, name, x + sw + 3, y)
            x += need
        return y + h

    def _draw_keys(self, surf: pygame.Surface, x: int, y: int, width: int | None = None) -> None:
        small = self._small
        state = "PAUSED   " if self.paused else ""
        line = f"{state}{KEYS}   ({self.fps:g} fps)"
        if width is not None and small.width(line) > width:      # two lines in a narrow panel
            parts = KEYS.split("   ")
            half = (len(parts) + 1) // 2
            small.draw(surf, state + "   ".join(parts[:half]), x, y, MUTED)
            small.draw(surf, "   ".join(parts[half:]) + f"   ({self.fps:g} fps)", x, y + small.line, MUTED)
        else:
            small.draw(surf, line, x, y, MUTED)

    # ------------------------------------------------------------------ output
    def render(self, sim: GatheringSimulation, **options: Any) -> np.ndarray | None:
        """Draw ``sim``'s current state; ``options`` override render options for this call only.

        Returns:
            ``"rgb_array"``: the frame, a new ``(size_px, size_px + panel_px, 3)`` uint8 array
            (rows = screen y, top = north). ``"human"``: None (the frame is shown in a window).
        """
        if options:
            saved = self._options
            self.set_options(**options)
            try:
                return self.render(sim)
            finally:
                self._configure(saved)
        if self.render_mode == "rgb_array":
            return _surface_to_array(self._pg, self.draw(sim))
        self._show(sim)
        return None

    def _show(self, sim: GatheringSimulation) -> None:
        """``"human"``: show the frame, handle keys; while paused, wait for keys here."""
        pg = self._pg
        if self._window is None:
            try:
                pg.display.init()
                self._window = pg.display.set_mode(self._surface.get_size())
            except pg.error as err:
                raise RuntimeError(
                    f"render_mode='human' could not open a window ({err}); "
                    "use render_mode='rgb_array' without a display"
                ) from None
            pg.display.set_caption("collective gathering   " + KEYS)
            self._clock = pg.time.Clock()
        step = self._handle_events(pg.event.get())
        while self._window is not None:
            if self._window.get_size() != self._surface.get_size():
                self._window = pg.display.set_mode(self._surface.get_size())
            self._window.blit(self.draw(sim), (0, 0))
            pg.display.flip()
            if not self.paused:
                self._clock.tick(self.fps)
                return
            if step:
                return
            step = self._handle_events([pg.event.wait(200)])

    def _handle_events(self, events: Sequence[Any]) -> bool:
        """Apply window events; True if a single step was asked for (or the window closed)."""
        pg = self._pg
        step = False
        for event in events:
            if event.type == pg.QUIT or (event.type == pg.KEYDOWN and event.key in (pg.K_ESCAPE, pg.K_q)):
                self.close()
                return True
            if event.type != pg.KEYDOWN:
                continue
            if event.key == pg.K_SPACE:
                self.paused = not self.paused
            elif event.key in (pg.K_RIGHT, pg.K_PERIOD):
                step = True
            elif event.key in (pg.K_PLUS, pg.K_EQUALS, pg.K_KP_PLUS, pg.K_UP):
                self.fps = min(self.fps * 2.0, 960.0)
            elif event.key in (pg.K_MINUS, pg.K_KP_MINUS, pg.K_DOWN):
                self.fps = max(self.fps / 2.0, 0.5)
            elif event.key == pg.K_c:
                self._cone_toggle = (self._cone_toggle + 1) % 3
        return step

    def close(self) -> None:
        """Close the ``"human"`` window if one is open (safe to call more than once)."""
        if self._window is not None:
            self._window = None
            self._clock = None
            self.paused = False
            self._pg.display.quit()


# ---------------------------------------------------------------------- figures
def _check_frames(who: str, frames) -> list[np.ndarray]:
    """The frames as arrays, all of one ``(H, W, 3)`` shape, or a ValueError naming ``who``."""
    arrays = [np.asarray(f) for f in frames]
    if not arrays:
        raise ValueError(f"{who}: no frames; allowed: one or more frames")
    shape = arrays[0].shape
    if len(shape) != 3 or shape[2] != 3:
        raise ValueError(f"{who}: frames must have shape (H, W, 3); frame 0 has {shape}")
    for i, a in enumerate(arrays):
        if a.shape != shape:
            raise ValueError(f"{who}: frame {i} has shape {a.shape}; frame 0 has {shape}")
    return arrays


def film_strip(frames: Sequence[np.ndarray], captions: Sequence[str] | None = None,
               gap_px: int = 8) -> np.ndarray:
    """Frames side by side (``gap_px`` of page colour between them), a caption under each.

    Args:
        frames: equally shaped ``(H, W, 3)`` uint8 arrays.
        captions: one text per frame (e.g. ``"step 300"``), or None for none.

    Returns:
        ``(H + caption band, n * W + (n - 1) * gap_px, 3)`` uint8.
    """
    frames = _check_frames("film_strip", frames)
    shape = frames[0].shape
    if captions is not None and len(captions) != len(frames):
        raise ValueError(f"film_strip: {len(captions)} captions for {len(frames)} frames; allowed: one per frame")
    if isinstance(gap_px, bool) or not isinstance(gap_px, (int, np.integer)) or gap_px < 0:
        raise ValueError(f"film_strip: gap_px={gap_px!r}; allowed: an integer >= 0")
    h, w = shape[:2]
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    import pygame as pg

    text = _Text(pg, max(13, h // 32))
    band = text.line + 8 if captions is not None and text.font is not None else 0
    n = len(frames)
    strip = pg.Surface((n * w + (n - 1) * gap_px, h + band))
    strip.fill(PAGE)
    for i, f in enumerate(frames):
        x = i * (w + gap_px)
        strip.blit(pg.surfarray.make_surface(np.ascontiguousarray(f.transpose(1, 0, 2)).astype(np.uint8)), (x, 0))
        if band:
            text.draw(strip, captions[i], x + (w - text.width(captions[i])) // 2, h + 4)
    return _surface_to_array(pg, strip)


def sensor_layout(morphology: Morphology | Sequence, size_px: int = 480, title: str = "") -> np.ndarray:
    """One robot's sensors from above, like the paper's Figure 3 (middle), plus the table.

    The robot (heading up) is drawn large; each sensor's cone starts at its mount point on the
    rim (``bearing``), points along ``bearing + orientation`` and opens ``fov``. Cone length is
    proportional to ``range`` (the longest fills the picture; none shorter than a fifth of it),
    so cones are not to scale with the body. Numbers match the table's rows; a square at the
    centre marks a bottom sensor.

    Returns:
        ``(size_px, size_px + table width, 3)`` uint8.
    """
    morphology = Morphology.coerce(morphology)
    if isinstance(size_px, bool) or not isinstance(size_px, (int, np.integer)) or size_px < 64:
        raise ValueError(f"sensor_layout: size_px={size_px!r}; allowed: an integer >= 64")
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    import pygame as pg

    text = _Text(pg, max(13, size_px // 30))
    gap = max(6, text.width("00"))
    margin = max(8, size_px // 40)
    table_w = text.table_columns(gap)[2] + 2 * margin if text.font is not None else 0
    surf = pg.Surface((size_px + table_w, size_px))
    surf.fill(PAGE)
    top = margin + (text.line + 4 if title else 0)
    if title:
        text.draw(surf, title, margin, margin)
    c = np.array([0.5 * size_px, 0.5 * (size_px + top)])
    reach = 0.5 * size_px - top * 0.5 - margin                     # centre to the picture's edge
    body = 0.2 * reach
    longest = max((s.range for s in morphology if s.type != "bottom"), default=1.0)

    def screen(angle: float, dist: float, origin: np.ndarray = c) -> list[float]:
        # heading = up: world angle a (CCW from heading) -> screen direction (-sin a, -cos a)
        return [origin[0] - dist * math.sin(angle), origin[1] - dist * math.cos(angle)]

    polygons, labels = [], []
    for i, s in enumerate(morphology):
        if s.type == "bottom":
            continue
        length = (reach - body) * max(0.2, s.range / longest)
        mount = np.array(screen(s.bearing, body))
        axis = s.bearing + s.orientation
        k = _arc_points(length, s.fov)
        arc = [screen(axis + a, length, mount) for a in np.linspace(-0.5 * s.fov, 0.5 * s.fov, k)]
        polygons.append((s.type, [mount.tolist()] + arc))
        labels.append((i, s.type, mount, screen(axis, 0.55 * length + 0.5 * text.line, mount)))
    layer = pg.Surface(surf.get_size(), pg.SRCALPHA)
    layer.set_clip(pg.Rect(0, top, size_px, size_px - top))
    _draw_cone_layer(pg, layer, surf, polygons)
    pg.draw.circle(surf, (90, 90, 90), c.tolist(), body)
    pg.draw.circle(surf, ROBOT, c.tolist(), body, 2)
    pg.draw.line(surf, HEADING, c.tolist(), screen(0.0, body * 0.9), 3)
    if any(s.type == "bottom" for s in morphology):
        sq = max(4, int(body * 0.25))
        pg.draw.rect(surf, SENSOR_COLOURS["bottom"], pg.Rect(int(c[0]) - sq, int(c[1]) - sq, 2 * sq, 2 * sq))
        idx = next(i for i, s in enumerate(morphology) if s.type == "bottom")
        text.draw(surf, str(idx), int(c[0]) - text.width(str(idx)) // 2, int(c[1]) - text.line // 2, HEADING)
    for i, kind, mount, at in labels:
        pg.draw.circle(surf, SENSOR_COLOURS[kind], mount.tolist(), max(3, int(body * 0.12)))
        text.draw(surf, str(i), int(at[0]) - text.width(str(i)) // 2, int(at[1]) - text.line // 2, TEXT)
    if text.font is not None:
        x = size_px + margin
        text.draw(surf, f"{len(morphology)} sensors", x, top)
        text.draw_table(surf, morphology, x, top + text.line + 4, gap)
        text.draw(surf, "one robot from above, heading up (white line);", x, size_px - margin - 2 * text.line, MUTED)
        text.draw(surf, "cone length proportional to range", x, size_px - margin - text.line, MUTED)
    return _surface_to_array(pg, surf)


def save_png(image: np.ndarray, path: str | os.PathLike) -> Path:
    """Write an ``(H, W, 3)`` uint8 image as PNG (parent folders are created)."""
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise ValueError(f"picture file {str(path)!r} has suffix {path.suffix!r}; allowed: '.png'")
    import imageio.v2 as imageio

    path.parent.mkdir(parents=True, exist_ok=True)
    imageio.imwrite(path, np.asarray(image, dtype=np.uint8))
    return path


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
    if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)) or not fps > 0:
        raise ValueError(f"save_video: fps={fps!r}; allowed: a number > 0")
    arrays = _check_frames("save_video", frames)
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
        h, w = arrays[0].shape[:2]
        if h % 2 or w % 2:     # H.264 in yuv420p needs even sizes: pad by repeating the edge
            arrays = [np.pad(a, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge") for a in arrays]
        imageio.mimsave(path, arrays, fps=fps, macro_block_size=1)
    return path
