"""The ``Renderer``: options, the view (world units -> pixels), the recorded history, render/show/close.

A frame is drawn by ``Renderer.draw``: the layers of ``drawing`` (arena, trails, cones, blocks,
robots) in the arena view, then the ``panel``; ``render`` returns it (``"rgb_array"``) or shows
it in the ``window`` (``"human"``). Those modules are functions of the renderer's state. What
a frame shows is described in the package docstring (``gathering_env.render``).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import numpy as np

from ..config import WorldConfig
from .drawing import (
    PAGE,
    _surface_to_array,
    _Text,
    draw_arena,
    draw_blocks,
    draw_cones,
    draw_robots,
    draw_trails,
    team_cone_cover,
)
from .options import AUTO_CONES_COVER, DEFAULT_SIZE_PX, FOLLOW_SPAN, ZONE_MARGIN, RenderOptions
from .panel import draw_keys, draw_panel, panel_width
from .window import show

if TYPE_CHECKING:  # pragma: no cover
    import pygame

    from ..simulation import GatheringSimulation


class _History:
    """The episode so far, for the sparkline and trails: gathered value per step, recent positions."""

    def __init__(self) -> None:
        self.last_step = -1
        self.steps: list[int] = []
        self.values: list[float] = []
        self.positions: list[np.ndarray] = []

    def record(self, sim: GatheringSimulation, keep: int) -> None:
        """Note ``sim``'s step (see ``Renderer.record``); keep ``keep`` + 1 positions (none if 0)."""
        steps = int(sim.steps)
        if steps == self.last_step and steps != 0:
            return
        if steps == 0 or steps < self.last_step:
            self.steps, self.values, self.positions = [], [], []
        self.last_step = steps
        self.steps.append(steps)
        self.values.append(float(sim.gathered_value))
        if keep > 0:
            self.positions.append(np.array(sim.world.robot_pos, dtype=float))
            del self.positions[:-(keep + 1)]


def _view_window(config: WorldConfig, opts: RenderOptions,
                 sim: GatheringSimulation) -> tuple[float, float, float | None]:
    """The view's centre (world units) and span (None: the whole arena) for ``opts.view``."""
    follow = opts.follow
    if follow is not None:
        x, y = sim.world.robot_pos[follow]
        return float(x), float(y), FOLLOW_SPAN
    if opts.view == "zone":
        x0, y0, x1, y1 = config.zone_rect
        span = max(x1 - x0, y1 - y0) + 2 * ZONE_MARGIN
        edge = 0.5                                               # show a little of the wall
        centre = []
        for c, extent in ((0.5 * (x0 + x1), config.arena_width), (0.5 * (y0 + y1), config.arena_height)):
            lo, hi = 0.5 * span - edge, extent + edge - 0.5 * span
            centre.append(0.5 * extent if lo > hi else min(max(c, lo), hi))
        return centre[0], centre[1], span
    return 0.5 * config.arena_width, 0.5 * config.arena_height, None


class Renderer:
    """Draws a ``GatheringSimulation``: a square arena view plus the information panel.

    Args:
        config: the world's config (arena size, zone, robot radius, team size).
        render_mode: ``"rgb_array"`` (``render`` returns frames; offscreen, never opens a
            window) or ``"human"`` (``render`` shows the frame in a pygame window).
        size_px: side of the square arena view in pixels (>= 64).
        fps: frame rate the ``"human"`` window is throttled to (frames per second).
        **options: the other render options (``cones``, ``view``, ``trail``, ``panel``,
            ``min_robot_px``; see ``gathering_env.render``).

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
        self._history = _History()      # recorded by ``record`` (every step when driven by the env)
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
        self.panel_px = panel_width(self._text, size, self._margin) if opts.panel else 0
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
        self._history.record(sim, self._options.trail)

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
        self._set_view(*_view_window(self.config, self._options, sim))
        surf.fill(PAGE)
        surf.set_clip(pg.Rect(0, 0, size, size))
        draw_arena(self, surf)
        draw_trails(self, surf)
        draw_cones(self, sim, surf)
        draw_blocks(self, sim, surf)
        draw_robots(self, sim, surf)
        if self.render_mode == "human" and self._window is not None and not self.panel_px:
            draw_keys(self, surf, 4, size - self._small.line - 4)
        surf.set_clip(None)
        if self.panel_px:
            self.sparkline_rect = draw_panel(self, sim, surf)
        return surf

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
        show(self, sim)
        return None

    def close(self) -> None:
        """Close the ``"human"`` window if one is open (safe to call more than once)."""
        if self._window is not None:
            self._window = None
            self._clock = None
            self.paused = False
            self._pg.display.quit()

