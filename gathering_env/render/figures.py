"""Figures from frames and morphologies: ``film_strip`` (frames side by side) and ``sensor_layout``.

Both draw offscreen with pygame (imported when called) and return ``(H, W, 3)`` uint8 arrays,
ready for ``save_png``.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence

import numpy as np

from ..sensors import Morphology
from .drawing import (
    HEADING,
    MUTED,
    PAGE,
    ROBOT,
    SENSOR_COLOURS,
    TEXT,
    _arc_points,
    _draw_cone_layer,
    _surface_to_array,
    _Text,
)
from .export import _check_frames
from .options import MAX_SIZE_PX, MIN_SIZE_PX


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
    if (isinstance(size_px, bool) or not isinstance(size_px, (int, np.integer))
            or not MIN_SIZE_PX <= size_px <= MAX_SIZE_PX):
        raise ValueError(f"sensor_layout: size_px={size_px!r}; allowed: an integer in {MIN_SIZE_PX}..{MAX_SIZE_PX}")
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
