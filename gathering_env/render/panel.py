"""The information panel right of the arena view: counts, sparkline, morphology table, legend, keys.

``draw_panel`` draws it from a ``Renderer``'s state (options, fonts, recorded history, the
``"human"`` window's keys) and returns the sparkline's box. ``panel_width`` is the panel's
width for a view of ``size_px``. ``KEYS`` lists the ``"human"`` window's keys (also its caption).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..config import BLOCK_TYPE_NAMES
from ..sensors import SENSOR_TYPES
from .drawing import (
    BLOCK_COLOURS,
    FLOOR,
    GATHERED_EDGE,
    GATHERED_SHADE,
    HEADING,
    MUTED,
    RGB,
    ROBOT,
    ROBOT_ATTACHED,
    SENSOR_COLOURS,
    TRAIL,
    ZONE_EDGE,
    _Text,
    cone_colour_on,
    cone_sensors,
)

if TYPE_CHECKING:  # pragma: no cover
    import pygame

    from ..simulation import GatheringSimulation
    from .renderer import Renderer

KEYS = "space pause   right step   +/- speed   c cones   esc close"
"""The ``"human"`` window's keys, as listed in the window."""

_CONE_ORDER = [t for t in SENSOR_TYPES if t != "bottom"]


def panel_width(text: _Text, size_px: int, margin: int) -> int:
    """Width of the panel beside a ``size_px`` view: a third of it, or the morphology table's."""
    gap = max(6, text.width("00"))
    table_w = text.table_columns(gap)[2] if text.font is not None else 0
    return max(size_px // 3, table_w + 2 * margin)


def draw_panel(r: Renderer, sim: GatheringSimulation, surf: pygame.Surface) -> pygame.Rect:
    """The panel right of the arena view; returns the sparkline's box."""
    pg, text, small = r._pg, r._text, r._small
    size, m = r._options.size_px, r._margin
    x0 = size + m
    width = r.panel_px - 2 * m
    pg.draw.line(surf, (210, 210, 205), (size, 0), (size, size - 1))
    y = m
    cfg = r.config
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
    sparkline = pg.Rect(x0, y, width, spark_h)
    draw_sparkline(r, surf, sparkline, sim.total_value)
    y += spark_h + m
    # morphology table
    text.draw(surf, f"sensors ({len(sim.morphology)}, every robot)", x0, y)
    y += text.line
    y += text.draw_table(surf, sim.morphology, x0, y, max(6, text.width("00"))) + m // 2
    # legend
    y = draw_legend(r, sim, surf, x0, y, width) + m // 2
    small.draw(surf, f"view {r._options.view}, cones {cones_label(r, sim)}"
               + (f", trail {r._options.trail}" if r._options.trail else ""), x0, y, MUTED)
    y += small.line
    if r.render_mode == "human" and r._window is not None:
        draw_keys(r, surf, x0, max(y + 2, size - m - 2 * small.line), width)
    return sparkline


def cones_label(r: Renderer, sim: GatheringSimulation) -> str:
    """Whose cones are shown: ``all``, ``none`` or ``robot 0,3``."""
    robots = r.cone_robots(sim)
    if robots.size == len(sim.world.robot_pos):
        return "all"
    if robots.size == 0:
        return "none"
    return "robot " + ",".join(str(i) for i in robots.tolist())


def draw_sparkline(r: Renderer, surf: pygame.Surface, box: pygame.Rect, total: float) -> None:
    """The recorded gathered value (a fraction of ``total``) over the episode's steps, in ``box``."""
    pg = r._pg
    pg.draw.rect(surf, (255, 255, 255), box)
    pg.draw.rect(surf, (200, 200, 195), box, 1)
    if not r._history.values:
        return
    steps = np.asarray(r._history.steps, dtype=float)
    values = np.asarray(r._history.values, dtype=float)
    x_max = max(float(r.config.max_cycles), 1.0)
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


def draw_legend(r: Renderer, sim: GatheringSimulation, surf: pygame.Surface, x0: int, y: int, width: int) -> int:
    """Swatches with names, wrapped to the panel width; returns the y below them."""
    pg, small = r._pg, r._small
    h = max(small.line, 10)
    sw = max(6, h - 4)
    kinds = sorted({c[0] for c in cone_sensors(sim.morphology)}, key=_CONE_ORDER.index)
    items: list[tuple[str, str, RGB, RGB | None]] = [
        ("gathered", "box", tuple(int(v * GATHERED_SHADE) for v in BLOCK_COLOURS[1]), GATHERED_EDGE),
        ("carried", "box", BLOCK_COLOURS[1], ROBOT_ATTACHED),
        ("robot", "disc", ROBOT, None),
        ("attached", "disc", ROBOT_ATTACHED, None),
    ]
    if r._options.trail:
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


def draw_keys(r: Renderer, surf: pygame.Surface, x: int, y: int, width: int | None = None) -> None:
    """The ``"human"`` window's keys and frame rate (two lines if ``width`` is too narrow)."""
    small = r._small
    state = "PAUSED   " if r.paused else ""
    line = f"{state}{KEYS}   ({r.fps:g} fps)"
    if width is not None and small.width(line) > width:      # two lines in a narrow panel
        parts = KEYS.split("   ")
        half = (len(parts) + 1) // 2
        small.draw(surf, state + "   ".join(parts[:half]), x, y, MUTED)
        small.draw(surf, "   ".join(parts[half:]) + f"   ({r.fps:g} fps)", x, y + small.line, MUTED)
    else:
        small.draw(surf, line, x, y, MUTED)
