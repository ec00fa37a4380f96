"""Drawing the world with pygame, and saving episodes as GIF/MP4.

The picture follows the paper's Figure 3: the arena with its walls, the gathering zone along
the south wall, blocks coloured by size (gathered blocks drawn darker with a white outline),
robots with a heading line (robots attached to a block drawn in orange), and every robot's
sensor cones drawn semi-transparently, coloured by sensor type. World y points up; the
screen's y points down, so y is flipped.

``Renderer(config, "rgb_array").render(sim)`` returns an ``(H, W, 3)`` uint8 frame drawn on an
offscreen surface (no window, no display needed); ``"human"`` shows it in a pygame window.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .config import WorldConfig
from .sensors import SENSOR_TYPES

if TYPE_CHECKING:  # pragma: no cover
    from .simulation import GatheringSimulation

BACKGROUND = (245, 245, 240)
WALL = (60, 60, 60)
ZONE = (200, 230, 200)
ZONE_EDGE = (90, 160, 90)
BLOCK_COLOURS = ((70, 130, 220), (240, 170, 40), (200, 60, 60))   # small, medium, large
ROBOT = (40, 40, 40)
ROBOT_ATTACHED = (255, 120, 0)
HEADING = (255, 255, 255)
SENSOR_COLOURS = {
    "infrared": (220, 40, 40),
    "ultrasonic": (40, 90, 220),
    "colour": (160, 60, 200),
    "camera": (30, 160, 90),
    "bottom": (120, 120, 120),
}
CONE_ALPHA = 45
MARGIN_PX = 10


class Renderer:
    """Draws a ``GatheringSimulation`` as an image.

    Args:
        config: the world's config (arena size, zone, robot radius).
        render_mode: ``"rgb_array"`` (return frames) or ``"human"`` (pygame window).
        size_px: width and height of the square picture in pixels.
        fps: frame rate of the human window.
    """

    def __init__(self, config: WorldConfig, render_mode: str, size_px: int = 640, fps: int = 30) -> None:
        if render_mode not in ("rgb_array", "human"):
            raise ValueError(f"render_mode={render_mode!r}; allowed: 'rgb_array', 'human'")
        if size_px < 64:
            raise ValueError(f"size_px={size_px}; allowed: >= 64")
        import pygame

        self._pg = pygame
        self.config = config
        self.render_mode = render_mode
        self.size_px = int(size_px)
        self.fps = fps
        self.scale = (self.size_px - 2 * MARGIN_PX) / max(config.arena_width, config.arena_height)
        if not pygame.font.get_init():
            try:
                pygame.font.init()
            except Exception:  # noqa: BLE001 - fonts are optional
                pass
        try:
            self._font = pygame.font.Font(None, 18)
        except Exception:  # noqa: BLE001
            self._font = None
        self._window = None
        self._clock = None
        self._surface = pygame.Surface((self.size_px, self.size_px))
        self._cones = pygame.Surface((self.size_px, self.size_px), pygame.SRCALPHA)

    # ------------------------------------------------------------------ geometry
    def to_screen(self, xy: np.ndarray) -> np.ndarray:
        """World (..., 2) coordinates -> screen pixels (..., 2), y flipped."""
        xy = np.asarray(xy, dtype=float)
        sx = MARGIN_PX + xy[..., 0] * self.scale
        sy = MARGIN_PX + (self.config.arena_height - xy[..., 1]) * self.scale
        return np.stack([sx, sy], axis=-1)

    # ------------------------------------------------------------------ drawing
    def draw(self, sim: GatheringSimulation):
        """Draw the current state onto the internal surface and return it."""
        pg, cfg, w = self._pg, self.config, sim.world
        surf = self._surface
        surf.fill(BACKGROUND)
        # zone
        x0, y0, x1, y1 = cfg.zone_rect
        (zx0, zy1), (zx1, zy0) = self.to_screen(np.array([[x0, y0], [x1, y1]]))
        zone_rect = pg.Rect(int(zx0), int(zy0), int(round(zx1 - zx0)), int(round(zy1 - zy0)))
        pg.draw.rect(surf, ZONE, zone_rect)
        pg.draw.rect(surf, ZONE_EDGE, zone_rect, 1)
        # sensor cones
        self._cones.fill((0, 0, 0, 0))
        self._cones.set_clip(pg.Rect(MARGIN_PX, MARGIN_PX, int(cfg.arena_width * self.scale),
                                     int(cfg.arena_height * self.scale)))
        self._draw_cones(sim)
        surf.blit(self._cones, (0, 0))
        # blocks
        gathered = getattr(sim, "gathered", np.zeros(len(w.block_half), bool))
        corners = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], dtype=float)
        for j in range(len(w.block_half)):
            c, s = math.cos(w.block_angle[j]), math.sin(w.block_angle[j])
            local = corners * w.block_half[j]
            world_pts = w.block_pos[j] + local @ np.array([[c, s], [-s, c]])
            pts = [tuple(p) for p in self.to_screen(world_pts)]
            colour = BLOCK_COLOURS[int(w.block_type[j])]
            if gathered[j]:
                colour = tuple(int(v * 0.55) for v in colour)
            pg.draw.polygon(surf, colour, pts)
            if gathered[j]:
                pg.draw.polygon(surf, (255, 255, 255), pts, 1)
        # robots
        radius_px = max(2, int(round(cfg.robot_radius * self.scale)))
        centres = self.to_screen(w.robot_pos)
        heading_len = max(radius_px + 2, 4)
        for i, (sx, sy) in enumerate(centres):
            attached = w.robot_attached[i] >= 0
            pg.draw.circle(surf, ROBOT_ATTACHED if attached else ROBOT, (int(sx), int(sy)), radius_px)
            a = w.robot_angle[i]
            tip = (sx + heading_len * math.cos(a), sy - heading_len * math.sin(a))
            pg.draw.line(surf, ROBOT_ATTACHED if attached else (90, 90, 90), (sx, sy), tip, 1)
            pg.draw.circle(surf, HEADING, (int(round(tip[0])), int(round(tip[1]))), 1)
        # walls
        pg.draw.rect(surf, WALL, pg.Rect(MARGIN_PX - 2, MARGIN_PX - 2,
                                         int(cfg.arena_width * self.scale) + 4,
                                         int(cfg.arena_height * self.scale) + 4), 3)
        self._draw_status(sim)
        return surf

    def _draw_cones(self, sim: GatheringSimulation) -> None:
        pg, w = self._pg, sim.world
        r = self.config.robot_radius
        for spec in sim.morphology:
            if not SENSOR_TYPES[spec.type].configurable:
                continue
            colour = SENSOR_COLOURS[spec.type] + (CONE_ALPHA,)
            steps = max(2, int(spec.fov / 0.2) + 1)
            offsets = np.linspace(-spec.fov / 2, spec.fov / 2, steps)
            for i in range(len(w.robot_pos)):
                mount_angle = w.robot_angle[i] + spec.bearing
                mount = w.robot_pos[i] + r * np.array([math.cos(mount_angle), math.sin(mount_angle)])
                axis = mount_angle + spec.orientation
                arc = mount + spec.range * np.stack([np.cos(axis + offsets), np.sin(axis + offsets)], axis=1)
                pts = self.to_screen(np.vstack([mount, arc]))
                pg.draw.polygon(self._cones, colour, [tuple(p) for p in pts])

    def _draw_status(self, sim: GatheringSimulation) -> None:
        if self._font is None:
            return
        text = (f"step {sim.steps}   gathered {sim.gathered_value:.0f}/{sim.total_value:.0f}")
        label = self._font.render(text, True, (20, 20, 20))
        self._surface.blit(label, (MARGIN_PX + 4, MARGIN_PX + 2))

    def render(self, sim: GatheringSimulation) -> np.ndarray | None:
        """``rgb_array``: the frame as (H, W, 3) uint8; ``human``: show it, return None."""
        surf = self.draw(sim)
        if self.render_mode == "rgb_array":
            return np.ascontiguousarray(self._pg.surfarray.array3d(surf).transpose(1, 0, 2))
        pg = self._pg
        if self._window is None:
            pg.display.init()
            self._window = pg.display.set_mode((self.size_px, self.size_px))
            pg.display.set_caption("collective gathering")
            self._clock = pg.time.Clock()
        pg.event.pump()
        self._window.blit(surf, (0, 0))
        pg.display.flip()
        self._clock.tick(self.fps)
        return None

    def close(self) -> None:
        if self._window is not None:
            self._pg.display.quit()
            self._window = None


def save_video(frames: Sequence[np.ndarray], path: str | os.PathLike, fps: int = 20) -> Path:
    """Write frames as ``.gif`` (imageio/pillow) or ``.mp4`` (needs ``imageio-ffmpeg``).

    Raises:
        ValueError: empty frame list, unsupported suffix, or MP4 without imageio-ffmpeg.
    """
    import imageio.v2 as imageio

    path = Path(path)
    if not frames:
        raise ValueError("save_video: no frames to write")
    suffix = path.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ValueError(f"video file {path} has suffix {suffix!r}; allowed: '.gif', '.mp4'")
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".gif":
        imageio.mimsave(path, list(frames), duration=1000.0 / fps, loop=0)
    else:
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise ValueError("writing .mp4 needs imageio-ffmpeg: pip install imageio-ffmpeg "
                             "(or the project's 'video' extra); .gif works without it") from None
        imageio.mimsave(path, list(frames), fps=fps, macro_block_size=1)
    return path
