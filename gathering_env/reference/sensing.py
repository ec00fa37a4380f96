"""Vectorised sensing: every robot's every sensor against every object, in numpy.

``SensorBank`` is built once per episode from the morphology, the world config and the
static block data; ``SensorBank.read(...)`` then turns the current poses into the
``(num_robots, num_sensors)`` observation matrix with a fixed number of numpy operations
(no Python loop over robots, sensors or objects).

Geometry (docs/model.md §3). Sensor *s* of robot *i* sits on the rim at
``p_i + r * (cos(a_i + bearing_s), sin(a_i + bearing_s))`` and looks along
``a_i + bearing_s + orientation_s``. An object (robot disc or square block) is seen when its
nearest point to the mount lies inside the cone (half-angle fov/2 about the axis) and
strictly within ``range``. Walls are infinite lines: the reading uses the nearest wall
point inside the cone (at the cone edge when the wall's normal lies outside the cone).
Occlusion is not modelled: an object behind another one is still seen. With ``block_sighting =
"rays"`` (the original's) a block is seen only where one of three rays from the mount enters it:
the axis (length R), else the cone's left edge, else its right edge (each to x = R in the
sensor's frame), at the distance of the entry point projected on the axis; or at distance 0 if
the mount lies inside it (``ray_sighting``).

Readings, all in [0, 1] (d = distance to the closest seen object, R = range):

* infrared: ``1 - d/R`` (or ``(1 - d/R) ** gamma``, or the original's Khepera curve of
  ``200 d/R``, ``gathering_env.khepera``), 0 when nothing is seen.
* ultrasonic: 1 for ``d <= 0.05 R``, then linear down to 0 at ``d = R``.
* colour: closest object a block -> ``0.5 + 0.5 (1 - d/R)`` in (0.5, 1];
  a wall -> ``0.5 (1 - d/R)`` in (0, 0.5]; a robot or nothing -> 0. With
  ``colour_response = "farther"`` (the original's) ``d/R`` takes the place of ``1 - d/R``:
  a block in [0.5, 1), a wall in [0, 0.5), rising with distance.
* camera: with n robots seen, R' = n + 1 and Q = sum of robots needed by the blocks seen:
  ``R'/Q`` if Q > 0 and R' <= Q, else 0. Walls are not seen by the camera.
* bottom: 1 with the robot's centre over the zone, falling linearly to 0 at
  ``bottom_falloff`` units outside it (or, ``bottom_response = "khepera"``, the original's disc
  ahead of the centre through the Khepera curve, ``gathering_env.khepera``).
"""

from __future__ import annotations

import numpy as np

from .. import khepera as khepera_curves
from ..config import WorldConfig
from ..sensors import TYPE_CODES, Morphology

IR, US, COLOUR, CAMERA, BOTTOM = (TYPE_CODES[t] for t in ("infrared", "ultrasonic", "colour", "camera", "bottom"))

# Outward normals of the four arena walls: west, east, south, north.
_WALL_NORMALS = np.array([[-1.0, 0.0], [1.0, 0.0], [0.0, -1.0], [0.0, 1.0]])
_WALL_TANGENTS = _WALL_NORMALS[:, ::-1].copy()


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
        self._present = frozenset(present)
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
        # Inward distance of a point p to wall w is offset_w - normal_w . p (>= 0 inside).
        self._wall_offset = np.array([0.0, config.arena_width, 0.0, config.arena_height])
        self._cos_half_w = self._cos_half_c[None, :, None]
        self._sin_half_w = self._sin_half_c[None, :, None]

        # Object list for the cone kernel: N robots (discs) then B blocks (squares).
        n = config.num_robots
        r = config.robot_radius
        self._ones_n, self._zeros_n = np.ones(n), np.zeros(n)
        self._obj_half = np.concatenate([np.zeros(n), self.block_half])
        self._obj_radius = np.concatenate([np.full(n, r), np.zeros(self.block_half.size)])
        self._obj_is_robot = np.concatenate([np.ones(n, bool), np.zeros(self.block_half.size, bool)])
        self._obj_need = np.concatenate([np.zeros(n), self.block_needs])
        # Squared centre distance below which some sensor of a robot may see an object:
        # mount offset r + longest range + the object's circumradius. Self pairs: -1.
        max_range = float(self._range_c.max(initial=0.0))
        bound = self._obj_radius + self._obj_half * np.sqrt(2.0)
        reach = (r + max_range + bound + 1e-9) ** 2
        self._reach_sq = np.broadcast_to(reach, (n, reach.size)).copy()
        self._reach_sq[np.arange(n), np.arange(n)] = -1.0

    # ------------------------------------------------------------------------------
    def read(self, robot_pos: np.ndarray, robot_angle: np.ndarray,
             block_pos: np.ndarray, block_angle: np.ndarray, dtype=np.float32) -> np.ndarray:
        """Observation matrix for the team.

        Args:
            robot_pos: (N, 2) robot centres. robot_angle: (N,) headings (rad).
            block_pos: (B, 2) block centres. block_angle: (B,) block rotations (rad).
            dtype: of the result: float32 (the env's observations) or float64.

        Returns:
            (N, S) readings in [0, 1], columns in morphology order.
        """
        n = robot_pos.shape[0]
        out = np.zeros((n, self.num_sensors), dtype=dtype)
        if self._has_cone:
            out[:, self._cone_idx] = self._read_cones(robot_pos, robot_angle, block_pos, block_angle)
        if self._bottom_idx.size:
            out[:, self._bottom_idx] = self._read_bottom(robot_pos, robot_angle)[:, None]
        return out

    def _read_bottom(self, robot_pos: np.ndarray, robot_angle: np.ndarray) -> np.ndarray:
        cfg = self.config
        x0, y0, x1, y1 = cfg.zone_rect
        khepera = cfg.bottom_response == "khepera"
        px, py = robot_pos[:, 0], robot_pos[:, 1]
        if khepera:
            ahead = khepera_curves.BOTTOM_AHEAD * cfg.robot_radius
            px, py = px + ahead * np.cos(robot_angle), py + ahead * np.sin(robot_angle)
        dx = np.maximum(np.maximum(x0 - px, px - x1), 0.0)
        dy = np.maximum(np.maximum(y0 - py, py - y1), 0.0)
        outside = np.hypot(dx, dy)
        if khepera:
            d = np.where(dx > 0.0, dx, dy)   # along x first, as the original
            reading = khepera_curves.curve(khepera_curves.MM * (d + khepera_curves.BOTTOM_HEIGHT))
            return np.where(outside < khepera_curves.BOTTOM_RADIUS, reading, 0.0)
        return np.clip(1.0 - outside / cfg.bottom_falloff, 0.0, 1.0)

    def _read_cones(self, robot_pos, robot_angle, block_pos, block_angle) -> np.ndarray:
        """(N, C) readings of the cone sensors.

        Robots and blocks form one object list (robots = discs of radius r, blocks =
        squares). A cheap (N, K) centre-distance test keeps only the (robot, object)
        pairs some sensor could reach; the exact nearest-point and cone geometry is then
        evaluated on those P pairs x C sensors and reduced per robot with ``reduceat``.
        """
        cfg = self.config
        n = robot_pos.shape[0]
        r = cfg.robot_radius
        rng = self._range_c                                    # (C,)
        mount_angle = robot_angle[:, None] + self._bearing_c   # (N, C)
        mx = robot_pos[:, 0:1] + r * np.cos(mount_angle)
        my = robot_pos[:, 1:2] + r * np.sin(mount_angle)
        axis = robot_angle[:, None] + self._offset_c
        hx, hy = np.cos(axis), np.sin(axis)

        obj_pos = np.concatenate([robot_pos, block_pos])       # (K, 2)
        obj_cos = np.concatenate([self._ones_n, np.cos(block_angle)])
        obj_sin = np.concatenate([self._zeros_n, np.sin(block_angle)])

        # --- candidate pairs: centre distance within reach of the longest sensor -----
        cdx = obj_pos[None, :, 0] - robot_pos[:, 0:1]          # (N, K)
        cdy = obj_pos[None, :, 1] - robot_pos[:, 1:2]
        near = cdx * cdx + cdy * cdy < self._reach_sq          # self excluded via reach_sq
        ii, kk = np.nonzero(near)

        d_robot = np.full((n, rng.size), np.inf)
        d_block = np.full((n, rng.size), np.inf)
        robots_seen = np.zeros((n, rng.size))
        need_seen = np.zeros((n, rng.size))
        if ii.size:
            # mount relative to the object centre, in the object's frame
            c, s = obj_cos[kk, None], obj_sin[kk, None]         # (P, 1)
            rx = mx[ii] - obj_pos[kk, 0:1]                     # (P, C)
            ry = my[ii] - obj_pos[kk, 1:2]
            lx = rx * c + ry * s
            ly = ry * c - rx * s
            half = self._obj_half[kk, None]
            vx = np.minimum(np.maximum(lx, -half), half) - lx  # mount -> nearest point
            vy = np.minimum(np.maximum(ly, -half), half) - ly
            hxi, hyi = hx[ii], hy[ii]
            dot = vx * (hxi * c + hyi * s) + vy * (hyi * c - hxi * s)
            centre = np.sqrt(vx * vx + vy * vy)
            dist = np.maximum(centre - self._obj_radius[kk, None], 0.0)
            seen = (dot >= centre * self._cos_half_c) & (dist < rng)
            is_robot = self._obj_is_robot[kk, None]
            if cfg.block_sighting == "rays":
                ray = ray_sighting(lx, ly, hxi * c + hyi * s, hyi * c - hxi * s, half,
                                   self._cos_half_c, self._sin_half_c, rng)
                seen = np.where(is_robot, seen, np.isfinite(ray) & (dist < rng))
                dist = np.where(is_robot, dist, ray)
            starts = np.flatnonzero(np.concatenate(([True], ii[1:] != ii[:-1])))
            rows = ii[starts]
            d_robot[rows] = np.minimum.reduceat(np.where(seen & is_robot, dist, np.inf), starts)
            d_block[rows] = np.minimum.reduceat(np.where(seen & ~is_robot, dist, np.inf), starts)
            if self._needs_camera:
                robots_seen[rows] = np.add.reduceat(seen & is_robot, starts)
                need_seen[rows] = np.add.reduceat(np.where(seen, self._obj_need[kk, None], 0.0), starts)

        readings = np.zeros((n, rng.size))
        present = self._present
        if self._needs_walls:
            d_wall = self._wall_distance(mx, my, hx, hy)
            d_any = np.minimum(np.minimum(d_robot, d_block), d_wall)
            closeness = np.maximum(1.0 - d_any * self._inv_range_c, 0.0)   # 0 when nothing seen
            if IR in present:
                if cfg.ir_response == "khepera":
                    scaled = khepera_curves.MM * khepera_curves.REFERENCE_RANGE * self._inv_range_c
                    ir = np.where(d_any < rng, khepera_curves.curve(np.where(d_any < rng, d_any, 0.0) * scaled), 0.0)
                else:
                    ir = closeness ** cfg.ir_gamma if cfg.ir_response == "gamma" else closeness
                readings = np.where(self._is[IR], ir, readings)
            if US in present:
                readings = np.where(self._is[US], np.minimum(closeness / 0.95, 1.0), readings)
            if COLOUR in present:
                level = 1.0 - closeness if cfg.colour_response == "farther" else closeness
                colour = np.where(d_block <= d_any, 0.5 + 0.5 * level,
                                  np.where((d_wall <= d_any) & (d_robot > d_any), 0.5 * level, 0.0))
                # a wall read at the original's distance may lie beyond the range: still seen
                seen_any = np.isfinite(d_any) if cfg.wall_distance == "original" else d_any < rng
                readings = np.where(self._is[COLOUR] & seen_any, colour, readings)
        if self._needs_camera:
            team = robots_seen + 1.0
            ok = (need_seen > 0) & (team <= need_seen)
            camera = np.where(ok, team / np.where(ok, need_seen, 1.0), 0.0)
            readings = np.where(self._is[CAMERA], camera, readings)
        return readings

    def _wall_distance(self, mx, my, hx, hy) -> np.ndarray:
        """Distance (N, C) to the nearest wall point inside each cone, inf if none.

        For a wall with inward distance ``perp`` whose outward normal makes the angle
        ``delta`` with the sensor axis, the nearest wall point inside a cone of half-angle
        ``a`` lies at ``perp / cos(max(delta - a, 0))`` (visible while that angle < 90 deg).
        """
        heading = np.stack((hx, hy), axis=-1)                            # (N, C, 2)
        cos_d = heading @ _WALL_NORMALS.T                                 # (N, C, 4)
        sin_d = np.abs(heading @ _WALL_TANGENTS.T)
        # A robot may overlap a wall for a step (contacts are discrete): its mount then lies
        # outside the arena, which reads as touching the wall (distance 0), never closer.
        perp = np.maximum(self._wall_offset - np.stack((mx, my), axis=-1) @ _WALL_NORMALS.T, 0.0)
        cos_eff = np.where(cos_d >= self._cos_half_w, 1.0, cos_d * self._cos_half_w + sin_d * self._sin_half_w)
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = np.where(cos_eff > 1e-9, perp / cos_eff, np.inf)
        if self.config.wall_distance == "original":
            seen = dist < self._range_c[None, :, None]
            cfg = self.config
            buggy = original_wall_distance(mx[..., None], my[..., None], hx[..., None], hy[..., None],
                                           self._cos_half_w, self._sin_half_w, _wall_ends(cfg.arena_width, cfg.arena_height))
            return np.where(seen, buggy, np.inf).min(axis=-1)
        return dist.min(axis=-1)


def _wall_ends(width, height):
    """(4, 2, 2) end points of the walls west, east, south, north (their order in the kernels)."""
    return np.array([[[0.0, 0.0], [0.0, height]], [[width, 0.0], [width, height]],
                     [[0.0, 0.0], [width, 0.0]], [[0.0, height], [width, height]]])


def original_wall_distance(mx, my, hx, hy, cos_half, sin_half, ends):
    """The distance at which the 2018 simulator's cone sensors read each wall (arrays broadcast
    against the walls' last axis, ``ends`` (4, 2, 2)).

    In the sensor's frame (mount at the origin, axis +x, g = tan of the half-angle) it takes the
    wall's line y = m x + c through its end points v1, v2 (v1 the lower in y) and, as its
    ``senseEdgeFixture`` does: the points where the line reaches y = -g and y = +g (not the
    cone's edges y = -g x and y = g x), each replaced by v1 / v2 when the wall ends before; the
    foot x = (m + 1/m) / (c' - c) with c' = s_y + s_x / m built from the mount's *world*
    position s; and the distance of the point at x, or of the nearer end point when x falls
    outside them. A wall level or upright in the sensor's frame (|dy| or |dx| < 1e-6) has its
    own rules, also the original's. The result is not the wall's distance; it may exceed the
    range, or fall short of it."""
    ax_w, ay_w, bx_w, by_w = ends[:, 0, 0], ends[:, 0, 1], ends[:, 1, 0], ends[:, 1, 1]
    g = sin_half / cos_half
    # end points in the sensor's frame
    ax = (ax_w - mx) * hx + (ay_w - my) * hy
    ay = (ay_w - my) * hx - (ax_w - mx) * hy
    bx = (bx_w - mx) * hx + (by_w - my) * hy
    by = (by_w - my) * hx - (bx_w - mx) * hy
    dx, dy = bx - ax, by - ay
    low = ay <= by                                   # v1: the lower end in y
    v1x, v1y = np.where(low, ax, bx), np.where(low, ay, by)
    v2x, v2y = np.where(low, bx, ax), np.where(low, by, ay)
    level = np.abs(dy) < 1e-6
    upright = ~level & (np.abs(dx) < 1e-6)
    general = ~level & ~upright
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        m = np.where(general, dy / np.where(general, dx, 1.0), 1.0)
        c = v1y - m * v1x
        x1, y1 = (-g - c) / m, -g
        x2, y2 = (g - c) / m, g
        x1, y1 = np.where(v1y > y1, v1x, x1), np.where(v1y > y1, v1y, y1)
        x2, y2 = np.where(v2y < y2, v2x, x2), np.where(v2y < y2, v2y, y2)
        foot = (m + 1.0 / m) / (my + mx / m - c)
        d_general = np.where(foot > x2, np.hypot(x2, y2),
                             np.where(foot < x1, np.hypot(x1, y1), np.hypot(foot, m * foot + c)))
        # level in the sensor's frame: the left end (in x), pushed to the cone's edge
        lx, ly = np.where(ax <= bx, ax, bx), np.where(ax <= bx, ay, by)
        d_level = np.hypot(np.maximum(ly / g, lx), ly)
        # upright: straight ahead, or the end of the part inside the cone's edges
        u1 = np.maximum(-g * v1x, v1y)
        u2 = np.minimum(g * v2x, v2y)
        d_upright = np.where(u1 > 0, np.hypot(v1x, u1), np.where(u2 < 0, np.hypot(v2x, u2), v1x))
    return np.where(level, d_level, np.where(upright, d_upright, d_general))


def ray_entry(ox, oy, dx, dy, half, length):
    """Parameter t at which the ray ``o + t d`` (d a unit vector) enters the square
    [-half, half]^2, for 0 <= t <= length; inf if it misses there or starts inside (as Box2D's
    ray cast, which reports no hit from inside a polygon). Arrays broadcast."""
    with np.errstate(divide="ignore", invalid="ignore"):
        bounds = []
        for o, d in ((ox, dx), (oy, dy)):
            t1, t2 = (-half - o) / d, (half - o) / d
            within = np.abs(o) <= half
            lo = np.where(d == 0, np.where(within, -np.inf, np.inf), np.minimum(t1, t2))
            hi = np.where(d == 0, np.where(within, np.inf, -np.inf), np.maximum(t1, t2))
            bounds.append((lo, hi))
    t0 = np.maximum(bounds[0][0], bounds[1][0])
    t1 = np.minimum(bounds[0][1], bounds[1][1])
    return np.where((t0 <= t1) & (t0 >= 0.0) & (t0 <= length), t0, np.inf)


def ray_sighting(lx, ly, ax, ay, half, cos_half, sin_half, rng):
    """Distance at which the original's three rays see a square block (inf: unseen).

    In the block's frame: the mount at (lx, ly), the sensor axis (ax, ay) (unit), a cone of
    half-angle with cosine/sine ``cos_half``/``sin_half`` and range ``rng``. The axis ray (length
    rng) is tried first, then the edge at +half, then at -half (each to x = rng in the sensor's
    frame, length rng / cos_half); the first entry's distance projected on the axis is returned,
    else 0 if the mount lies inside the block."""
    up_x, up_y = ax * cos_half - ay * sin_half, ax * sin_half + ay * cos_half
    dn_x, dn_y = ax * cos_half + ay * sin_half, ay * cos_half - ax * sin_half
    edge = rng / np.maximum(cos_half, 1e-12)
    t_axis = ray_entry(lx, ly, ax, ay, half, rng)
    t_up = ray_entry(lx, ly, up_x, up_y, half, edge)
    t_dn = ray_entry(lx, ly, dn_x, dn_y, half, edge)
    inside = (np.abs(lx) <= half) & (np.abs(ly) <= half)
    return np.where(np.isfinite(t_axis), t_axis,
                    np.where(np.isfinite(t_up), t_up * cos_half,
                             np.where(np.isfinite(t_dn), t_dn * cos_half, np.where(inside, 0.0, np.inf))))


def sensor_bank(morphology: Morphology, config: WorldConfig, block_half_sizes: np.ndarray,
                block_needs: np.ndarray):
    """The sensing of ``config.kernel``: this module's ``SensorBank`` ('numpy') or
    ``kernels.CompiledSensorBank`` ('compiled'); both have ``read(...)`` as above."""
    if config.kernel == "compiled":
        from ..compiled.kernels import CompiledSensorBank

        return CompiledSensorBank(morphology, config, block_half_sizes, block_needs)
    return SensorBank(morphology, config, block_half_sizes, block_needs)


__all__ = ["SensorBank", "sensor_bank", "ray_entry", "ray_sighting", "IR", "US", "COLOUR", "CAMERA", "BOTTOM"]
