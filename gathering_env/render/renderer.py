"""The Renderer: pygame drawing of the gathering world (see the package docstring, ``gathering_env.render``)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..config import BLOCK_TYPE_NAMES, WorldConfig
from ..sensors import SENSOR_TYPES
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
    TRAIL,
    ZONE_EDGE,
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

