"""The ``"human"`` window of a ``Renderer``: opening it, showing frames, the keys.

``show`` opens the window on first use, blits the renderer's frame and throttles to its
``fps``; while paused it waits here for keys. ``handle_events`` applies the keys (``KEYS``):
space pause, right arrow step, +/- faster/slower, c cones (options -> all -> none), esc or q
close. The window's state (``_window``, ``_clock``, ``paused``, ``fps``, the cone toggle)
is the renderer's; ``Renderer.close`` closes the window.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from .panel import KEYS

if TYPE_CHECKING:  # pragma: no cover
    from ..simulation import GatheringSimulation
    from .renderer import Renderer


def show(r: Renderer, sim: GatheringSimulation) -> None:
    """``"human"``: show the frame, handle keys; while paused, wait for keys here."""
    pg = r._pg
    if r._window is None:
        try:
            pg.display.init()
            r._window = pg.display.set_mode(r._surface.get_size())
        except pg.error as err:
            raise RuntimeError(
                f"render_mode='human' could not open a window ({err}); "
                "use render_mode='rgb_array' without a display"
            ) from None
        pg.display.set_caption("collective gathering   " + KEYS)
        r._clock = pg.time.Clock()
    step = handle_events(r, pg.event.get())
    while r._window is not None:
        if r._window.get_size() != r._surface.get_size():
            r._window = pg.display.set_mode(r._surface.get_size())
        r._window.blit(r.draw(sim), (0, 0))
        pg.display.flip()
        if not r.paused:
            r._clock.tick(r.fps)
            return
        if step:
            return
        step = handle_events(r, [pg.event.wait(200)])


def handle_events(r: Renderer, events: Sequence[Any]) -> bool:
    """Apply window events; True if a single step was asked for (or the window closed)."""
    pg = r._pg
    step = False
    for event in events:
        if event.type == pg.QUIT or (event.type == pg.KEYDOWN and event.key in (pg.K_ESCAPE, pg.K_q)):
            r.close()
            return True
        if event.type != pg.KEYDOWN:
            continue
        if event.key == pg.K_SPACE:
            r.paused = not r.paused
        elif event.key in (pg.K_RIGHT, pg.K_PERIOD):
            step = True
        elif event.key in (pg.K_PLUS, pg.K_EQUALS, pg.K_KP_PLUS, pg.K_UP):
            r.fps = min(r.fps * 2.0, 960.0)
        elif event.key in (pg.K_MINUS, pg.K_KP_MINUS, pg.K_DOWN):
            r.fps = max(r.fps / 2.0, 0.5)
        elif event.key == pg.K_c:
            r._cone_toggle = (r._cone_toggle + 1) % 3
    return step
