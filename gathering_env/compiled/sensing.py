"""Compiled ``sense`` kernel: the readings of every sensor of every robot of every world,
operation for operation as the numpy reference (``gathering_env.reference.sensing``, which
documents the geometry); and ``CompiledSensorBank``, the same for one team with the numpy
bank's interface."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..khepera import (
    BOTTOM_AHEAD,
    BOTTOM_HEIGHT,
    BOTTOM_RADIUS,
    GAIN,
    MM,
    NORM,
    REFERENCE_RANGE,
    SCALE,
    SHAPE,
)
from .tables import (
    BOTTOM,
    CAMERA,
    F_BLOCK_RAYS,
    F_BOTTOM_KHEPERA,
    F_COLOUR_FARTHER,
    F_IR_GAMMA,
    F_IR_KHEPERA,
    F_WALL_ORIGINAL,
    IR,
    P_ARENA_H,
    P_ARENA_W,
    P_FALLOFF,
    P_IR_GAMMA,
    P_RADIUS,
    P_ZX0,
    P_ZX1,
    P_ZY0,
    P_ZY1,
    T_BEARING,
    T_COS_HALF,
    T_INV_RANGE,
    T_OFFSET,
    T_RANGE,
    T_SIN_HALF,
    T_TYPE,
    US,
    sensor_table,
    world_params,
)


@njit(cache=True)
def _wall_gap(wall, mx, my, hx, hy, cos_half, sin_half, width, height):
    """Distance from a mount to the nearest point of one wall inside its cone (inf if none).

    Walls 0-3 are west, east, south, north, with outward normals (-1, 0), (1, 0), (0, -1),
    (0, 1) and tangents (0, -1), (0, 1), (-1, 0), (1, 0)."""
    if wall == 0:
        cos_d, sin_d, perp = -hx, abs(hy), mx
    elif wall == 1:
        cos_d, sin_d, perp = hx, abs(hy), width - mx
    elif wall == 2:
        cos_d, sin_d, perp = -hy, abs(hx), my
    else:
        cos_d, sin_d, perp = hy, abs(hx), height - my
    perp = max(perp, 0.0)   # a mount outside the arena (robot overlapping a wall) touches it
    cos_eff = 1.0 if cos_d >= cos_half else cos_d * cos_half + sin_d * sin_half
    return perp / cos_eff if cos_eff > 1e-9 else np.inf


@njit(cache=True)
def _wall_distance(mx, my, hx, hy, cos_half, sin_half, width, height):
    """Distance from a mount to the nearest wall point inside its cone (inf if none)."""
    best = np.inf
    for wall in range(4):
        best = min(best, _wall_gap(wall, mx, my, hx, hy, cos_half, sin_half, width, height))
    return best


@njit(cache=True)
def _original_wall_distance(mx, my, hx, hy, cos_half, sin_half, width, height, rng):
    """``gathering_env.reference.sensing.original_wall_distance`` of the nearest wall the cone
    sees (its nearest point in the cone within ``rng``), inf if none."""
    best = np.inf
    g = sin_half / cos_half
    for wall in range(4):
        if _wall_gap(wall, mx, my, hx, hy, cos_half, sin_half, width, height) >= rng:
            continue
        # the wall's ends A, B as the original orders them: west (0, 0)-(0, H), east (W, 0)-(W, H),
        # south (0, 0)-(W, 0), north (0, H)-(W, H)
        ax_w = width if wall == 1 else 0.0
        ay_w = height if wall == 3 else 0.0
        bx_w = 0.0 if wall == 0 else width
        by_w = 0.0 if wall == 2 else height
        ax = (ax_w - mx) * hx + (ay_w - my) * hy
        ay = (ay_w - my) * hx - (ax_w - mx) * hy
        bx = (bx_w - mx) * hx + (by_w - my) * hy
        by = (by_w - my) * hx - (bx_w - mx) * hy
        dx = bx - ax
        dy = by - ay
        if ay <= by:
            v1x, v1y, v2x, v2y = ax, ay, bx, by
        else:
            v1x, v1y, v2x, v2y = bx, by, ax, ay
        if abs(dy) < 1e-6:
            lx, ly = (ax, ay) if ax <= bx else (bx, by)
            dist = math.hypot(max(ly / g, lx), ly)
        elif abs(dx) < 1e-6:
            u1 = max(-g * v1x, v1y)
            u2 = min(g * v2x, v2y)
            if u1 > 0:
                dist = math.hypot(v1x, u1)
            elif u2 < 0:
                dist = math.hypot(v2x, u2)
            else:
                dist = v1x
        else:
            m = dy / dx
            c = v1y - m * v1x
            x1, y1 = (-g - c) / m, -g
            x2, y2 = (g - c) / m, g
            if v1y > y1:
                x1, y1 = v1x, v1y
            if v2y < y2:
                x2, y2 = v2x, v2y
            denominator = my + mx / m - c
            foot = (m + 1.0 / m) / denominator if denominator != 0.0 else math.copysign(np.inf, m + 1.0 / m)
            if foot > x2:
                dist = math.hypot(x2, y2)
            elif foot < x1:
                dist = math.hypot(x1, y1)
            else:
                dist = math.hypot(foot, m * foot + c)
        if dist < best:
            best = dist
    return best


@njit(cache=True)
def _khepera_curve(x):
    """``gathering_env.khepera.curve`` for one x."""
    return min(GAIN * NORM * x ** (SHAPE - 1.0) * math.exp(-x / SCALE), 1.0)


@njit(cache=True)
def _ray_entry(ox, oy, dx, dy, half, length):
    """``gathering_env.reference.sensing.ray_entry`` for one ray."""
    t0 = -np.inf
    t1 = np.inf
    for axis in range(2):
        o = ox if axis == 0 else oy
        d = dx if axis == 0 else dy
        if d == 0.0:
            if abs(o) > half:
                return np.inf
            continue
        ta = (-half - o) / d
        tb = (half - o) / d
        t0 = max(t0, min(ta, tb))
        t1 = min(t1, max(ta, tb))
    if t0 <= t1 and 0.0 <= t0 <= length:
        return t0
    return np.inf


@njit(cache=True)
def _ray_sighting(lx, ly, ax, ay, half, cos_half, sin_half, rng):
    """``gathering_env.reference.sensing.ray_sighting`` for one sensor and block."""
    t = _ray_entry(lx, ly, ax, ay, half, rng)
    if t < np.inf:
        return t
    edge = rng / max(cos_half, 1e-12)
    t = _ray_entry(lx, ly, ax * cos_half - ay * sin_half, ax * sin_half + ay * cos_half, half, edge)
    if t < np.inf:
        return t * cos_half
    t = _ray_entry(lx, ly, ax * cos_half + ay * sin_half, ay * cos_half - ax * sin_half, half, edge)
    if t < np.inf:
        return t * cos_half
    if abs(lx) <= half and abs(ly) <= half:
        return 0.0
    return np.inf


@njit(cache=True)
def sense(robot_pos, robot_angle, block_pos, block_angle, block_half, block_need,
          table, params, flags, active, out):
    """Readings of every sensor of every robot in every active world.

    Args:
        robot_pos (W, N, 2), robot_angle (W, N), block_pos (W, B, 2), block_angle (W, B):
            poses. block_half (B,), block_need (B,) float: static block data.
        table: (S, 7) ``sensor_table``. params, flags: ``world_params``.
        active: (W,) bool, worlds to read (others keep their old readings).
        out: (W, N, S) float32, written in place.
    """
    n_worlds, n = robot_angle.shape
    n_blocks = block_angle.shape[1]
    n_sensors = table.shape[0]
    r = params[P_RADIUS]
    width, height = params[P_ARENA_W], params[P_ARENA_H]
    use_gamma = flags[F_IR_GAMMA] != 0
    farther = flags[F_COLOUR_FARTHER] != 0
    rays = flags[F_BLOCK_RAYS] != 0
    ir_khepera = flags[F_IR_KHEPERA] != 0
    bottom_khepera = flags[F_BOTTOM_KHEPERA] != 0
    wall_original = flags[F_WALL_ORIGINAL] != 0
    gamma = params[P_IR_GAMMA]
    max_range = 0.0
    has_cone = False
    for s in range(n_sensors):
        if int(table[s, T_TYPE]) != BOTTOM:
            has_cone = True
            if table[s, T_RANGE] > max_range:
                max_range = table[s, T_RANGE]
    # squared centre distance below which some sensor / sensor s may see a robot / a block (a
    # mount lies r from its robot's centre; a robot is a disc of radius r, a block a square of
    # half-diagonal half * sqrt(2)); farther objects are skipped, which changes no reading
    robot_reach = (r + max_range + r + 1e-9) ** 2
    block_reach = np.empty(n_blocks)
    for b in range(n_blocks):
        block_reach[b] = (r + max_range + block_half[b] * math.sqrt(2.0) + 1e-9) ** 2
    sensor_robot_reach = np.empty(n_sensors)
    sensor_block_reach = np.empty((n_blocks, n_sensors))
    for s in range(n_sensors):
        sensor_robot_reach[s] = (r + table[s, T_RANGE] + r + 1e-9) ** 2
        for b in range(n_blocks):
            sensor_block_reach[b, s] = (r + table[s, T_RANGE] + block_half[b] * math.sqrt(2.0) + 1e-9) ** 2
    mx = np.empty(n_sensors)
    my = np.empty(n_sensors)
    hx = np.empty(n_sensors)
    hy = np.empty(n_sensors)
    d_robot = np.empty(n_sensors)
    d_block = np.empty(n_sensors)
    robots_seen = np.empty(n_sensors)
    need_seen = np.empty(n_sensors)
    bcos = np.empty(n_blocks)
    bsin = np.empty(n_blocks)
    for w in range(n_worlds):
        if not active[w]:
            continue
        for b in range(n_blocks):
            bcos[b] = math.cos(block_angle[w, b])
            bsin[b] = math.sin(block_angle[w, b])
        for i in range(n):
            px = robot_pos[w, i, 0]
            py = robot_pos[w, i, 1]
            a = robot_angle[w, i]
            for s in range(n_sensors):
                mount = a + table[s, T_BEARING]
                mx[s] = px + r * math.cos(mount)
                my[s] = py + r * math.sin(mount)
                axis = a + table[s, T_OFFSET]
                hx[s] = math.cos(axis)
                hy[s] = math.sin(axis)
                d_robot[s] = np.inf
                d_block[s] = np.inf
                robots_seen[s] = 0.0
                need_seen[s] = 0.0
            if has_cone:
                # other robots: discs of radius r (frame rotation is the identity)
                for k in range(n):
                    if k == i:
                        continue
                    ox = robot_pos[w, k, 0]
                    oy = robot_pos[w, k, 1]
                    cdx = ox - px
                    cdy = oy - py
                    gap = cdx * cdx + cdy * cdy
                    if gap >= robot_reach:
                        continue
                    for s in range(n_sensors):
                        if int(table[s, T_TYPE]) == BOTTOM or gap >= sensor_robot_reach[s]:
                            continue
                        vx = -(mx[s] - ox)
                        vy = -(my[s] - oy)
                        dot = vx * hx[s] + vy * hy[s]
                        centre = math.sqrt(vx * vx + vy * vy)
                        dist = max(centre - r, 0.0)
                        if dot >= centre * table[s, T_COS_HALF] and dist < table[s, T_RANGE]:
                            if dist < d_robot[s]:
                                d_robot[s] = dist
                            robots_seen[s] += 1.0
                # blocks: squares, tested in the block's frame
                for b in range(n_blocks):
                    ox = block_pos[w, b, 0]
                    oy = block_pos[w, b, 1]
                    cdx = ox - px
                    cdy = oy - py
                    gap = cdx * cdx + cdy * cdy
                    if gap >= block_reach[b]:
                        continue
                    c = bcos[b]
                    sn = bsin[b]
                    half = block_half[b]
                    for s in range(n_sensors):
                        if int(table[s, T_TYPE]) == BOTTOM or gap >= sensor_block_reach[b, s]:
                            continue
                        rx = mx[s] - ox
                        ry = my[s] - oy
                        lx = rx * c + ry * sn
                        ly = ry * c - rx * sn
                        vx = min(max(lx, -half), half) - lx
                        vy = min(max(ly, -half), half) - ly
                        dot = vx * (hx[s] * c + hy[s] * sn) + vy * (hy[s] * c - hx[s] * sn)
                        centre = math.sqrt(vx * vx + vy * vy)
                        dist = max(centre, 0.0)
                        if rays:
                            if dist >= table[s, T_RANGE]:
                                continue
                            dist = _ray_sighting(lx, ly, hx[s] * c + hy[s] * sn, hy[s] * c - hx[s] * sn, half,
                                                 table[s, T_COS_HALF], table[s, T_SIN_HALF], table[s, T_RANGE])
                            if dist < np.inf:
                                if dist < d_block[s]:
                                    d_block[s] = dist
                                need_seen[s] += block_need[b]
                        elif dot >= centre * table[s, T_COS_HALF] and dist < table[s, T_RANGE]:
                            if dist < d_block[s]:
                                d_block[s] = dist
                            need_seen[s] += block_need[b]
            for s in range(n_sensors):
                kind = int(table[s, T_TYPE])
                rng = table[s, T_RANGE]
                value = 0.0
                if kind == BOTTOM:
                    bx, by = px, py
                    if bottom_khepera:
                        bx = px + BOTTOM_AHEAD * r * math.cos(a)
                        by = py + BOTTOM_AHEAD * r * math.sin(a)
                    dx = max(max(params[P_ZX0] - bx, bx - params[P_ZX1]), 0.0)
                    dy = max(max(params[P_ZY0] - by, by - params[P_ZY1]), 0.0)
                    if not bottom_khepera:
                        value = min(max(1.0 - math.hypot(dx, dy) / params[P_FALLOFF], 0.0), 1.0)
                    elif math.hypot(dx, dy) < BOTTOM_RADIUS:
                        value = _khepera_curve(MM * ((dx if dx > 0.0 else dy) + BOTTOM_HEIGHT))
                elif kind == CAMERA:
                    team = robots_seen[s] + 1.0
                    if need_seen[s] > 0.0 and team <= need_seen[s]:
                        value = team / need_seen[s]
                else:
                    if wall_original:
                        d_wall = _original_wall_distance(mx[s], my[s], hx[s], hy[s], table[s, T_COS_HALF],
                                                         table[s, T_SIN_HALF], width, height, rng)
                    else:
                        d_wall = _wall_distance(mx[s], my[s], hx[s], hy[s], table[s, T_COS_HALF],
                                                table[s, T_SIN_HALF], width, height)
                    d_any = min(min(d_robot[s], d_block[s]), d_wall)
                    closeness = max(1.0 - d_any * table[s, T_INV_RANGE], 0.0)
                    if kind == IR:
                        if not ir_khepera:
                            value = closeness ** gamma if use_gamma else closeness
                        elif d_any < rng:
                            value = _khepera_curve(MM * REFERENCE_RANGE * d_any * table[s, T_INV_RANGE])
                    elif kind == US:
                        value = min(closeness / 0.95, 1.0)
                    elif d_any < rng or (wall_original and d_any < np.inf):  # colour (an original wall may lie beyond)
                        level = 1.0 - closeness if farther else closeness
                        if d_block[s] <= d_any:
                            value = 0.5 + 0.5 * level
                        elif d_wall <= d_any and d_robot[s] > d_any:
                            value = 0.5 * level
                out[w, i, s] = value


class CompiledSensorBank:
    """``sense`` for one team, with the interface of the numpy ``sensing.SensorBank``.

    Args: as ``SensorBank``: morphology, config, block_half_sizes (B,), block_needs (B,).
    """

    def __init__(self, morphology, config, block_half_sizes, block_needs) -> None:
        self.num_sensors = len(morphology)
        self.table = sensor_table(morphology)
        self.params, self.flags = world_params(config)
        self.block_half = np.asarray(block_half_sizes, dtype=np.float64)
        self.block_need = np.asarray(block_needs, dtype=np.float64)
        self._active = np.ones(1, dtype=np.bool_)

    def read(self, robot_pos, robot_angle, block_pos, block_angle, dtype=np.float32) -> np.ndarray:
        """(N, S) readings (``dtype`` float32 as the env's observations, or float64)."""
        n = len(robot_angle)
        out = np.zeros((1, n, self.num_sensors), dtype=dtype)
        sense(np.ascontiguousarray(robot_pos, dtype=np.float64).reshape(1, n, 2),
              np.ascontiguousarray(robot_angle, dtype=np.float64).reshape(1, n),
              np.ascontiguousarray(block_pos, dtype=np.float64).reshape(1, -1, 2),
              np.ascontiguousarray(block_angle, dtype=np.float64).reshape(1, -1),
              self.block_half, self.block_need, self.table, self.params, self.flags, self._active, out)
        return out[0]
