"""Vectorised sensing: every robot's every sensor against every object, in numpy.

``SensorBank`` is built once per episode from the morphology, the world config and the
static block data; ``SensorBank.read(...)`` then turns the current poses into the
``(num_robots, num_sensors)`` observation matrix with a fixed number of numpy operations
(no Python loop over robots, sensors or objects).

Geometry (SPEC section 3). Sensor *s* of robot *i* sits on the rim at
``p_i + r * (cos(a_i + bearing_s), sin(a_i + bearing_s))`` and looks along
``a_i + bearing_s + orientation_s``. An object (robot disc or square block) is seen when its
nearest point to the mount lies inside the cone (half-angle fov/2 about the axis) and
strictly within ``range``. Walls are infinite lines: the reading uses the nearest wall
point inside the cone (at the cone edge when the wall's normal lies outside the cone).
Occlusion is not modelled: an object behind another one is still seen.

Readings, all in [0, 1] (d = distance to the closest seen object, R = range):

* infrared: ``1 - d/R`` (or ``(1 - d/R) ** gamma``), 0 when nothing is seen.
* ultrasonic: 1 for ``d <= 0.05 R``, then linear down to 0 at ``d = R``.
* colour: closest object a block -> ``0.5 + 0.5 (1 - d/R)`` in (0.5, 1];
  a wall -> ``0.5 (1 - d/R)`` in (0, 0.5]; a robot or nothing -> 0.
* camera: with n robots seen, R' = n + 1 and Q = sum of robots needed by the blocks seen:
  ``R'/Q`` if Q > 0 and R' <= Q, else 0. Walls are not seen by the camera.
* bottom: 1 with the robot's centre over the zone, falling linearly to 0 at
  ``bottom_falloff`` units outside it.
"""

from __future__ import annotations

import numpy as np

from .config import WorldConfig
from .sensors import TYPE_CODES, Morphology

IR, US, COLOUR, CAMERA, BOTTOM = (TYPE_CODES[t] for t in ("infrared", "ultrasonic", "colour", "camera", "bottom"))

# Outward normals of the four arena walls: west, east, south, north.
_WALL_NORMALS = np.array([[-1.0, 0.0], [1.0, 0.0], [0.0, -1.0], [0.0, 1.0]])


class SensorBank:
    """Precomputed sensor geometry of one morphology for a whole team.

    Args:
        morphology: the suite every robot carries (S sensors).
        config: world parameters (robot radius, arena, zone, IR response, ...).
        block_half_sizes: (B,) half side length of each square block (units).
        block_needs: (B,) robots needed to push each block (1, 2 or 3).
    """

    def __init__(self, morphology: Morphology, config: WorldConfig,
                 block_half_sizes: np.ndarray, block_needs: np.ndarray) -> None:
        self.config = config
        self.num_sensors = len(morphology)
        self.types = np.array([TYPE_CODES[s.type] for s in morphology], dtype=np.int64)
        self.bearing = np.array([s.bearing for s in morphology], dtype=float)
        self.axis_offset = self.bearing + np.array([s.orientation for s in morphology], dtype=float)
        self.range = np.array([s.range for s in morphology], dtype=float)
        half_fov = 0.5 * np.array([s.fov for s in morphology], dtype=float)
        self.cos_half = np.cos(half_fov)
        self.sin_half = np.sin(half_fov)
        self.block_half = np.asarray(block_half_sizes, dtype=float)
        self.block_needs = np.asarray(block_needs, dtype=float)

        present = set(self.types.tolist())
        self._cone_idx = np.flatnonzero(self.types != BOTTOM)   # sensors that look into a cone
        self._bottom_idx = np.flatnonzero(self.types == BOTTOM)
        cone_types = self.types[self._cone_idx]
        self._needs_walls = bool(present & {IR, US, COLOUR})
        self._needs_camera = CAMERA in present
        # Per cone-sensor column masks (shape (1, C)).
        self._is = {t: (cone_types == t)[None, :] for t in (IR, US, COLOUR, CAMERA)}
        self._range_c = self.range[self._cone_idx]
        self._inv_range_c = np.where(self._range_c > 0, 1.0 / np.maximum(self._range_c, 1e-12), 0.0)
        self._cos_half_c = self.cos_half[self._cone_idx]
        self._sin_half_c = self.sin_half[self._cone_idx]
        self._offset_c = self.axis_offset[self._cone_idx]
        self._bearing_c = self.bearing[self._cone_idx]
        self._has_cone = self._cone_idx.size > 0

    # ------------------------------------------------------------------------------
    def read(self, robot_pos: np.ndarray, robot_angle: np.ndarray,
             block_pos: np.ndarray, block_angle: np.ndarray) -> np.ndarray:
        """Observation matrix for the team.

        Args:
            robot_pos: (N, 2) robot centres. robot_angle: (N,) headings (rad).
            block_pos: (B, 2) block centres. block_angle: (B,) block rotations (rad).

        Returns:
            (N, S) float32 readings in [0, 1], columns in morphology order.
        """
        n = robot_pos.shape[0]
        out = np.zeros((n, self.num_sensors), dtype=np.float32)
        if self._has_cone:
            out[:, self._cone_idx] = self._read_cones(robot_pos, robot_angle, block_pos, block_angle)
        if self._bottom_idx.size:
            out[:, self._bottom_idx] = self._read_bottom(robot_pos)[:, None]
        return out

    def _read_bottom(self, robot_pos: np.ndarray) -> np.ndarray:
        x0, y0, x1, y1 = self.config.zone_rect
        dx = np.maximum(np.maximum(x0 - robot_pos[:, 0], robot_pos[:, 0] - x1), 0.0)
        dy = np.maximum(np.maximum(y0 - robot_pos[:, 1], robot_pos[:, 1] - y1), 0.0)
        outside = np.hypot(dx, dy)
        return np.clip(1.0 - outside / self.config.bottom_falloff, 0.0, 1.0)

    def _read_cones(self, robot_pos, robot_angle, block_pos, block_angle) -> np.ndarray:
        cfg = self.config
        r = cfg.robot_radius
        rng = self._range_c                                   # (C,)
        cos_half = self._cos_half_c
        mount_angle = robot_angle[:, None] + self._bearing_c  # (N, C)
        mx = robot_pos[:, 0:1] + r * np.cos(mount_angle)       # (N, C)
        my = robot_pos[:, 1:2] + r * np.sin(mount_angle)
        axis = robot_angle[:, None] + self._offset_c
        hx, hy = np.cos(axis), np.sin(axis)                   # (N, C)

        # --- robots: discs; the nearest point lies along the line to the centre -----
        dx = robot_pos[None, None, :, 0] - mx[:, :, None]     # (N, C, N)
        dy = robot_pos[None, None, :, 1] - my[:, :, None]
        centre_dist = np.sqrt(dx * dx + dy * dy)
        dist_r = np.maximum(centre_dist - r, 0.0)
        seen_r = (dx * hx[:, :, None] + dy * hy[:, :, None]) >= centre_dist * cos_half[None, :, None]
        seen_r &= dist_r < rng[None, :, None]
        idx = np.arange(robot_pos.shape[0])
        seen_r[idx, :, idx] = False                           # a robot never sees itself
        d_robot = np.where(seen_r, dist_r, np.inf).min(axis=2)  # (N, C)

        # --- blocks: squares; nearest point by clamping in the block frame ----------
        if block_pos.shape[0]:
            cb, sb = np.cos(block_angle), np.sin(block_angle)     # (B,)
            rx = mx[:, :, None] - block_pos[None, None, :, 0]     # (N, C, B)
            ry = my[:, :, None] - block_pos[None, None, :, 1]
            lx = rx * cb + ry * sb                                # mount in the block frame
            ly = -rx * sb + ry * cb
            half = self.block_half
            vx = np.clip(lx, -half, half) - lx                    # mount -> nearest point
            vy = np.clip(ly, -half, half) - ly
            wx = vx * cb - vy * sb                                # back to the world frame
            wy = vx * sb + vy * cb
            dist_b = np.sqrt(wx * wx + wy * wy)
            seen_b = (wx * hx[:, :, None] + wy * hy[:, :, None]) >= dist_b * cos_half[None, :, None]
            seen_b &= dist_b < rng[None, :, None]
            d_block = np.where(seen_b, dist_b, np.inf).min(axis=2)
        else:
            seen_b = np.zeros(mx.shape + (0,), dtype=bool)
            d_block = np.full(mx.shape, np.inf)

        readings = np.zeros(mx.shape)
        if self._needs_walls:
            d_wall = self._wall_distance(mx, my, hx, hy)
            d_any = np.minimum(np.minimum(d_robot, d_block), d_wall)
            closeness = np.where(d_any < rng, 1.0 - d_any * self._inv_range_c, 0.0)  # (N, C)
            if cfg.ir_response == "gamma":
                ir = closeness ** cfg.ir_gamma
            else:
                ir = closeness
            readings = np.where(self._is[IR], ir, readings)
            us = np.clip(closeness / 0.95, 0.0, 1.0)
            readings = np.where(self._is[US], us, readings)
            colour = np.where(d_block <= d_any, 0.5 + 0.5 * closeness,
                              np.where((d_wall <= d_any) & (d_robot > d_any), 0.5 * closeness, 0.0))
            colour = np.where(d_any < rng, colour, 0.0)
            readings = np.where(self._is[COLOUR], colour, readings)
        if self._needs_camera:
            robots_seen = seen_r.sum(axis=2) + 1.0
            need_seen = seen_b @ self.block_needs if seen_b.shape[2] else np.zeros(mx.shape)
            with np.errstate(divide="ignore", invalid="ignore"):
                camera = np.where((need_seen > 0) & (robots_seen <= need_seen),
                                  robots_seen / np.where(need_seen > 0, need_seen, 1.0), 0.0)
            readings = np.where(self._is[CAMERA], camera, readings)
        return readings

    def _wall_distance(self, mx, my, hx, hy) -> np.ndarray:
        """Distance (N, C) to the nearest wall point inside each cone, inf if none."""
        cfg = self.config
        perp = np.stack([mx, cfg.arena_width - mx, my, cfg.arena_height - my], axis=-1)  # (N, C, 4)
        cos_d = hx[..., None] * _WALL_NORMALS[:, 0] + hy[..., None] * _WALL_NORMALS[:, 1]
        sin_d = np.abs(hx[..., None] * _WALL_NORMALS[:, 1] - hy[..., None] * _WALL_NORMALS[:, 0])
        cos_half = self._cos_half_c[None, :, None]
        sin_half = self._sin_half_c[None, :, None]
        # Angle between the wall normal and the nearest cone direction: 0 when the
        # normal is inside the cone, else (delta - half_fov).
        cos_eff = np.where(cos_d >= cos_half, 1.0, cos_d * cos_half + sin_d * sin_half)
        with np.errstate(divide="ignore"):
            dist = np.where(cos_eff > 1e-9, np.maximum(perp, 0.0) / np.maximum(cos_eff, 1e-9), np.inf)
        return dist.min(axis=-1)


__all__ = ["SensorBank", "IR", "US", "COLOUR", "CAMERA", "BOTTOM"]
