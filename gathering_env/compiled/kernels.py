"""Compiled (numba) kernels of the simulation step: everything but pymunk's own calls.

Three kernels, each over a batch of W independent worlds of the same configuration
(a single episode is W = 1):

* ``drive``: wheel clipping, collision avoidance, attached-robot drive and the
  differential-drive control velocities, written straight into the per-world velocity
  arrays that ``pymunk.batch.set_space_bodies`` reads.
* ``settle``: after the physics step, unpack the bodies' poses from pymunk's batch buffer,
  find gathered blocks, run the pickup heuristic (attach decisions and releases, reported
  as events for the few pymunk joint calls), and optionally ``sense``.
* ``sense``: the readings of every sensor of every robot of every world.

Each kernel is a plain loop (worlds x robots x objects x sensors) and reproduces the
numpy reference (``gathering_env.reference.sensing``, ``heuristics``, ``scoring`` and
``GatheringWorld``) operation for operation, so both give the same numbers; the tests
compare them. Geometry and readings are documented in ``gathering_env.reference.sensing``.

Kernels are compiled on first use and cached on disk (``cache=True``), so later imports,
and process-pool workers, load the machine code instead of compiling again.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..drive import (
    FADE_END,
    FADE_START,
    IMPULSE_CAP,
    SPIN_TRACTION,
    TRACTION,
    WHEEL_FORCE,
    WHEEL_OFFSET,
    robot_moment,
    spin_limit,
    substep_keep,
)
from ..sensors import TYPE_CODES

IR, US, COLOUR, CAMERA, BOTTOM = (TYPE_CODES[t] for t in ("infrared", "ultrasonic", "colour", "camera", "bottom"))

# Columns of the sensor table (one row per sensor, see ``sensor_table``).
T_TYPE, T_BEARING, T_OFFSET, T_RANGE, T_COS_HALF, T_SIN_HALF, T_INV_RANGE = range(7)
# Entries of the float parameter vector (see ``world_params``).
(P_RADIUS, P_ARENA_W, P_ARENA_H, P_ZX0, P_ZY0, P_ZX1, P_ZY1, P_FALLOFF, P_IR_GAMMA, P_DT,
 P_MAX_SPEED, P_ZONE_CX, P_ZONE_CY, P_AVOID_DIST, P_BOX_W, P_BOX_D, P_REACH, P_TOTAL_VALUE,
 P_MAX_CYCLES, P_BOX_OFFSET, P_DEAD_BAND, P_MASS, P_MOMENT, P_SUBSTEPS, P_KEEP, P_SPIN_LIMIT) = range(26)
# Entries of the integer flag vector.
F_IR_GAMMA, F_AVOIDANCE, F_PICKUP, F_FORCE_DRIVE = range(4)
# Event kinds reported by ``settle`` (rows of the int event table: kind, world, robot, block, slot).
EV_ATTACH, EV_RELEASE = 1, 2

_SIDE_NX = (1.0, 0.0, -1.0, 0.0)   # outward normal of block side 0..3 (E, N, W, S), block frame
_SIDE_NY = (0.0, 1.0, 0.0, -1.0)
_SIDE_TX = (0.0, -1.0, 0.0, 1.0)   # tangent along the side
_SIDE_TY = (1.0, 0.0, -1.0, 0.0)


def sensor_table(morphology) -> np.ndarray:
    """(S, 7) float64 table of a morphology for ``sense``: type code, bearing, axis offset
    (bearing + orientation), range, cos and sin of half the FOV, 1 / range (0 if no range)."""
    table = np.zeros((len(morphology), 7))
    for row, s in enumerate(morphology):
        half = 0.5 * s.fov
        table[row] = (TYPE_CODES[s.type], s.bearing, s.bearing + s.orientation, s.range,
                      math.cos(half), math.sin(half), 1.0 / s.range if s.range > 0 else 0.0)
    return table


def world_params(config) -> tuple[np.ndarray, np.ndarray]:
    """(float parameters, integer flags) of a ``WorldConfig`` for the kernels."""
    x0, y0, x1, y1 = config.zone_rect
    cx, cy = config.zone_centre
    params = np.array([
        config.robot_radius, config.arena_width, config.arena_height, x0, y0, x1, y1,
        config.bottom_falloff, config.ir_gamma, config.dt, config.robot_max_speed, cx, cy,
        config.collision_avoidance_distance, config.pickup_box_width, config.pickup_box_depth,
        config.pickup_reach, config.total_value, config.max_cycles, config.pickup_box_offset,
        config.drive_dead_band, config.robot_mass, robot_moment(config), config.physics_substeps, substep_keep(config),
        spin_limit(config),
    ], dtype=np.float64)
    flags = np.array([config.ir_response == "gamma", config.collision_avoidance, config.pickup_heuristic,
                      config.drive_model == "force"], dtype=np.int64)
    return params, flags


@njit(cache=True)
def _dead_band(command, band):
    """A wheel command after the dead band (``WorldConfig.drive_dead_band``)."""
    if band == 0.0:
        return command
    magnitude = max(abs(command) - band, 0.0) / (1.0 - band)
    return magnitude if command >= 0.0 else -magnitude


@njit(cache=True)
def _wheel_force(command, vx):
    """'force' drive: the push of a wheel at ``command`` (``gathering_env.drive.wheel_force``)."""
    along = abs(vx) if np.sign(vx) == np.sign(command) else 0.0
    fade = min(max((FADE_END - along) / (FADE_END - FADE_START), 0.0), 1.0)
    return command * WHEEL_FORCE * fade


@njit(cache=True)
def _wrap(angle):
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True)
def _wall_distance(mx, my, hx, hy, cos_half, sin_half, width, height):
    """Distance from a mount to the nearest wall point inside its cone (inf if none).

    Walls in the order west, east, south, north, with outward normals (-1, 0), (1, 0),
    (0, -1), (0, 1) and tangents (0, -1), (0, 1), (-1, 0), (1, 0)."""
    best = np.inf
    for wall in range(4):
        if wall == 0:
            cos_d, sin_d, perp = -hx, abs(-hy), mx
        elif wall == 1:
            cos_d, sin_d, perp = hx, abs(hy), width - mx
        elif wall == 2:
            cos_d, sin_d, perp = -hy, abs(-hx), my
        else:
            cos_d, sin_d, perp = hy, abs(hx), height - my
        perp = max(perp, 0.0)   # a mount outside the arena (robot overlapping a wall) touches it
        if cos_d >= cos_half:
            cos_eff = 1.0
        else:
            cos_eff = cos_d * cos_half + sin_d * sin_half
        if cos_eff > 1e-9:
            dist = perp / cos_eff
            if dist < best:
                best = dist
    return best


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
    gamma = params[P_IR_GAMMA]
    max_range = 0.0
    has_cone = False
    for s in range(n_sensors):
        if int(table[s, T_TYPE]) != BOTTOM:
            has_cone = True
            if table[s, T_RANGE] > max_range:
                max_range = table[s, T_RANGE]
    # squared centre distance below which some sensor may see a robot / a block
    robot_reach = (r + max_range + r + 1e-9) ** 2
    block_reach = np.empty(n_blocks)
    for b in range(n_blocks):
        block_reach[b] = (r + max_range + block_half[b] * math.sqrt(2.0) + 1e-9) ** 2
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
                    if cdx * cdx + cdy * cdy >= robot_reach:
                        continue
                    for s in range(n_sensors):
                        if int(table[s, T_TYPE]) == BOTTOM:
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
                    if cdx * cdx + cdy * cdy >= block_reach[b]:
                        continue
                    c = bcos[b]
                    sn = bsin[b]
                    half = block_half[b]
                    for s in range(n_sensors):
                        if int(table[s, T_TYPE]) == BOTTOM:
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
                        if dot >= centre * table[s, T_COS_HALF] and dist < table[s, T_RANGE]:
                            if dist < d_block[s]:
                                d_block[s] = dist
                            need_seen[s] += block_need[b]
            for s in range(n_sensors):
                kind = int(table[s, T_TYPE])
                rng = table[s, T_RANGE]
                value = 0.0
                if kind == BOTTOM:
                    dx = max(max(params[P_ZX0] - px, px - params[P_ZX1]), 0.0)
                    dy = max(max(params[P_ZY0] - py, py - params[P_ZY1]), 0.0)
                    value = min(max(1.0 - math.hypot(dx, dy) / params[P_FALLOFF], 0.0), 1.0)
                elif kind == CAMERA:
                    team = robots_seen[s] + 1.0
                    if need_seen[s] > 0.0 and team <= need_seen[s]:
                        value = team / need_seen[s]
                else:
                    d_wall = _wall_distance(mx[s], my[s], hx[s], hy[s], table[s, T_COS_HALF],
                                            table[s, T_SIN_HALF], width, height)
                    d_any = min(min(d_robot[s], d_block[s]), d_wall)
                    closeness = max(1.0 - d_any * table[s, T_INV_RANGE], 0.0)
                    if kind == IR:
                        value = closeness ** gamma if use_gamma else closeness
                    elif kind == US:
                        value = min(closeness / 0.95, 1.0)
                    elif d_any < rng:  # colour
                        if d_block[s] <= d_any:
                            value = 0.5 + 0.5 * closeness
                        elif d_wall <= d_any and d_robot[s] > d_any:
                            value = 0.5 * closeness
                out[w, i, s] = value


@njit(cache=True)
def drive(wheels, robot_pos, robot_angle, robot_attached, robot_rows, control_rows, raw, params, flags,
          active, times, vel):
    """Wheel commands -> control-body (and, in the 'force' drive, robot) velocities for the next
    physics step (``gathering_env.drive``).

    Args:
        wheels: (W, N, 2) finite controller commands (clipped here to [-1, 1]).
        robot_pos (W, N, 2), robot_angle (W, N), robot_attached (W, N): current state.
        robot_rows, control_rows: (W, N) row of each robot and of its control body in pymunk's
            body order.
        raw: (W, rows, 6) bodies as last read (x, y, angle, vx, vy, angular velocity).
        active: (W,) bool. times: (W, N) int, how often each robot's force drive acts before
            this step (1 under the fixed schedule; ``gathering_env.drive.shuffled_times``). vel: (W, rows, 3 or 6) written in place: every body's velocity,
            the control bodies' replaced by the drive, and under the force drive the robots'
            forces and torques (what ``GatheringWorld.set_drive`` reads).
    """
    n_worlds, n = robot_angle.shape
    n_rows = raw.shape[1]
    r = params[P_RADIUS]
    max_speed = params[P_MAX_SPEED]
    band = params[P_DEAD_BAND]
    half_dt = 0.5 * params[P_DT]
    dt = params[P_DT]
    force_drive = flags[F_FORCE_DRIVE] != 0
    mass, moment = params[P_MASS], params[P_MOMENT]
    arm = WHEEL_OFFSET * r
    spin_cap = params[P_SPIN_LIMIT]
    h = dt / params[P_SUBSTEPS]
    keep = params[P_KEEP]
    avoidance = flags[F_AVOIDANCE] != 0
    reach = r + params[P_AVOID_DIST]
    cx, cy = params[P_ZONE_CX], params[P_ZONE_CY]
    left = np.empty(n)
    right = np.empty(n)
    for w in range(n_worlds):
        if not active[w]:
            continue
        for i in range(n):
            left[i] = min(max(wheels[w, i, 0], -1.0), 1.0)
            right[i] = min(max(wheels[w, i, 1], -1.0), 1.0)
        if avoidance:
            for i in range(n):
                if robot_attached[w, i] >= 0:
                    continue
                hx = math.cos(robot_angle[w, i])
                hy = math.sin(robot_angle[w, i])
                side = 0.0
                ahead_any = False
                for j in range(n):
                    if j == i:
                        continue
                    dx = robot_pos[w, j, 0] - robot_pos[w, i, 0]
                    dy = robot_pos[w, j, 1] - robot_pos[w, i, 1]
                    along = dx * hx + dy * hy
                    across = -dx * hy + dy * hx
                    if along > 0 and along < reach + r and abs(across) < 2 * r:
                        ahead_any = True
                        side += across
                fx = robot_pos[w, i, 0] + reach * hx
                fy = robot_pos[w, i, 1] + reach * hy
                wall = fx < 0 or fx > params[P_ARENA_W] or fy < 0 or fy > params[P_ARENA_H]
                if ahead_any or wall:
                    turn = -1.0 if side < 0 else 1.0
                    left[i] = turn
                    right[i] = -turn
        for i in range(n):
            if robot_attached[w, i] < 0:
                continue
            bearing = math.atan2(cy - robot_pos[w, i, 1], cx - robot_pos[w, i, 0])
            error = _wrap(bearing - robot_angle[w, i])
            direction = 1.0
            if abs(error) > 0.5 * math.pi:
                direction = -1.0
                error = _wrap(error - math.pi)
            turn = min(max(2.0 * error / (0.5 * math.pi), -1.0), 1.0)
            lw = direction - turn
            rw = direction + turn
            scale = max(max(abs(lw), abs(rw)), 1.0)
            left[i] = lw / scale
            right[i] = rw / scale
        for row in range(n_rows):
            vel[w, row, 0] = raw[w, row, 3]
            vel[w, row, 1] = raw[w, row, 4]
            vel[w, row, 2] = raw[w, row, 5]
        if force_drive:
            for i in range(n):
                row = robot_rows[w, i]
                vx, vy, spin = raw[w, row, 3], raw[w, row, 4], raw[w, row, 5]
                hx, hy = math.cos(robot_angle[w, i]), math.sin(robot_angle[w, i])
                wheel_sum = 0.0
                wheel_diff = 0.0
                removed = 0.0
                for _ in range(times[w, i]):
                    f_left = _wheel_force(left[i], vx)
                    f_right = _wheel_force(right[i], vx)
                    taken = TRACTION * min(max(mass * (vx * hx + vy * hy), -IMPULSE_CAP), IMPULSE_CAP)
                    wheel_sum = wheel_sum + (f_left + f_right)
                    wheel_diff = wheel_diff + (f_right - f_left)
                    removed = removed + taken
                    vx = vx - taken / mass * hx
                    vy = vy - taken / mass * hy
                    spin = (1.0 - TRACTION * SPIN_TRACTION) * spin
                push = keep * (dt * wheel_sum - removed) / h
                new_spin = spin + dt * arm * wheel_diff / moment
                vel[w, row, 3] = push * hx
                vel[w, row, 4] = push * hy
                vel[w, row, 5] = keep * moment * (min(max(new_spin, -spin_cap), spin_cap) - raw[w, row, 5]) / h
                row = control_rows[w, i]
                vel[w, row, 0] = 0.0
                vel[w, row, 1] = 0.0
                vel[w, row, 2] = 0.0
            continue
        for i in range(n):
            v_left = _dead_band(left[i], band) * max_speed
            v_right = _dead_band(right[i], band) * max_speed
            forward = 0.5 * (v_left + v_right)
            spin = (v_right - v_left) / (2.0 * r)
            heading = robot_angle[w, i] + half_dt * spin
            row = control_rows[w, i]
            vel[w, row, 0] = forward * math.cos(heading)
            vel[w, row, 1] = forward * math.sin(heading)
            vel[w, row, 2] = spin


@njit(cache=True)
def unpack(raw, robot_rows, block_rows, active, robot_pos, robot_angle, block_pos, block_angle):
    """Copy the poses of robots and blocks out of pymunk's body rows (x, y, angle, ...)."""
    n_worlds, n = robot_rows.shape
    n_blocks = block_rows.shape[1]
    for w in range(n_worlds):
        if not active[w]:
            continue
        for i in range(n):
            row = robot_rows[w, i]
            robot_pos[w, i, 0] = raw[w, row, 0]
            robot_pos[w, i, 1] = raw[w, row, 1]
            robot_angle[w, i] = raw[w, row, 2]
        for b in range(n_blocks):
            row = block_rows[w, b]
            block_pos[w, b, 0] = raw[w, row, 0]
            block_pos[w, b, 1] = raw[w, row, 1]
            block_angle[w, b] = raw[w, row, 2]


@njit(cache=True)
def _in_zone(x, y, angle, half, params):
    """A block counts as gathered while its axis-aligned bounding box lies wholly in the zone."""
    extent = half * (abs(math.cos(angle)) + abs(math.sin(angle)))
    return ((x - extent >= params[P_ZX0]) and (x + extent <= params[P_ZX1])
            and (y - extent >= params[P_ZY0]) and (y + extent <= params[P_ZY1]))


@njit(cache=True)
def gathered_blocks(block_pos, block_angle, block_half, params, active, gathered):
    """(W, B) bool in place: the block's bounding box lies wholly inside the zone."""
    n_worlds, n_blocks = block_angle.shape
    for w in range(n_worlds):
        if not active[w]:
            continue
        for b in range(n_blocks):
            gathered[w, b] = _in_zone(block_pos[w, b, 0], block_pos[w, b, 1], block_angle[w, b], block_half[b], params)


@njit(cache=True)
def _in_pickup_box(px, py, a, bx, by, ba, half, params):
    """Does the block's nearest point to the robot's pickup-box centre lie in the box?"""
    box_w, box_d = params[P_BOX_W], params[P_BOX_D]
    hx = math.cos(a)
    hy = math.sin(a)
    centre_offset = params[P_BOX_OFFSET]
    box_x = px + centre_offset * hx
    box_y = py + centre_offset * hy
    cb = math.cos(ba)
    sb = math.sin(ba)
    rx = box_x - bx
    ry = box_y - by
    lx = min(max(rx * cb + ry * sb, -half), half)
    ly = min(max(-rx * sb + ry * cb, -half), half)
    qx = bx + lx * cb - ly * sb - box_x
    qy = by + lx * sb + ly * cb - box_y
    along = qx * hx + qy * hy
    across = -qx * hy + qy * hx
    return abs(along) <= 0.5 * box_d and abs(across) <= 0.5 * box_w


@njit(cache=True)
def settle(raw, robot_rows, block_rows, active, block_half, block_need, block_value, params, flags,
           robot_pos, robot_angle, block_pos, block_angle, robot_attached, sticky, anchor_owner,
           gathered, gathered_value, steps, reward, terminated, truncated, events, weld_points):
    """After the physics step: poses, gathered blocks, pickup (attach), release on gathering,
    and the step's bookkeeping: ``steps`` += 1, ``reward`` = 100 * (change in gathered value) /
    total value (0 for worlds not stepped), ``terminated`` (every block gathered) and
    ``truncated`` (``max_cycles`` reached first); ended worlds are cleared from ``active``.

    Attachments follow ``GatheringWorld.try_attach``: free robots in index order, blocks in
    index order; the nearest free anchor (any side for a fresh block, the sticky side after
    the first robot) within ``pickup_reach`` robot radii of the robot's front. Every change
    is applied to the arrays here and reported as a row of ``events`` (kind, world, robot,
    block, slot) with the weld point (the robot's front) in ``weld_points``, for the pymunk
    joints. Newly gathered blocks release their robots (``EV_RELEASE`` rows).

    Returns the number of event rows written.
    """
    unpack(raw, robot_rows, block_rows, active, robot_pos, robot_angle, block_pos, block_angle)
    n_worlds, n = robot_angle.shape
    n_blocks = block_angle.shape[1]
    r = params[P_RADIUS]
    pickup = flags[F_PICKUP] != 0
    prefilter = params[P_BOX_OFFSET] + 0.5 * (params[P_BOX_D] + params[P_BOX_W])
    reach_limit = params[P_REACH] * r
    count = 0
    now = np.empty(n_blocks, dtype=np.bool_)
    for w in range(n_worlds):
        if not active[w]:
            reward[w] = 0.0
            continue
        for b in range(n_blocks):
            now[b] = _in_zone(block_pos[w, b, 0], block_pos[w, b, 1], block_angle[w, b], block_half[b], params)
        if pickup:
            for i in range(n):
                if robot_attached[w, i] >= 0:
                    continue
                px = robot_pos[w, i, 0]
                py = robot_pos[w, i, 1]
                a = robot_angle[w, i]
                for b in range(n_blocks):
                    if robot_attached[w, i] >= 0:
                        break
                    if now[b]:
                        continue
                    # open: no sticky side yet, or a free anchor on it (as seen before any
                    # attachment this step; a block filled meanwhile refuses in the anchor scan)
                    reach = prefilter + block_half[b] * math.sqrt(2.0)
                    dx = block_pos[w, b, 0] - px
                    dy = block_pos[w, b, 1] - py
                    if dx * dx + dy * dy > reach * reach:
                        continue
                    if not _in_pickup_box(px, py, a, block_pos[w, b, 0], block_pos[w, b, 1],
                                          block_angle[w, b], block_half[b], params):
                        continue
                    # nearest free anchor to the robot's front
                    fx = px + r * math.cos(a)
                    fy = py + r * math.sin(a)
                    k = int(block_need[b])
                    half = block_half[b]
                    c = math.cos(block_angle[w, b])
                    sn = math.sin(block_angle[w, b])
                    side0 = 0
                    side1 = 4
                    if sticky[w, b] >= 0:
                        side0 = sticky[w, b]
                        side1 = side0 + 1
                    best = np.inf
                    best_side = -1
                    best_slot = -1
                    for side in range(side0, side1):
                        for slot in range(k):
                            if sticky[w, b] >= 0 and anchor_owner[w, b, slot] >= 0:
                                continue
                            offset = ((slot + 0.5) / k * 2.0 - 1.0) * half
                            lx = _SIDE_NX[side] * half + offset * _SIDE_TX[side]
                            ly = _SIDE_NY[side] * half + offset * _SIDE_TY[side]
                            ax = block_pos[w, b, 0] + (lx * c + ly * -sn)
                            ay = block_pos[w, b, 1] + (lx * sn + ly * c)
                            dist = math.hypot(ax - fx, ay - fy)
                            if best_side < 0 or dist < best:
                                best = dist
                                best_side = side
                                best_slot = slot
                    if best_side < 0 or best > reach_limit:
                        continue
                    sticky[w, b] = best_side
                    anchor_owner[w, b, best_slot] = i
                    robot_attached[w, i] = b
                    events[count, 0] = EV_ATTACH
                    events[count, 1] = w
                    events[count, 2] = i
                    events[count, 3] = b
                    events[count, 4] = best_slot
                    weld_points[count, 0] = fx
                    weld_points[count, 1] = fy
                    count += 1
        value = 0.0
        for b in range(n_blocks):
            if now[b] and not gathered[w, b]:
                for i in range(n):
                    if robot_attached[w, i] == b:
                        robot_attached[w, i] = -1
                        events[count, 0] = EV_RELEASE
                        events[count, 1] = w
                        events[count, 2] = i
                        events[count, 3] = b
                        events[count, 4] = -1
                        count += 1
                for slot in range(anchor_owner.shape[2]):
                    anchor_owner[w, b, slot] = -1
                sticky[w, b] = -1
            gathered[w, b] = now[b]
            if now[b]:
                value += block_value[b]
        reward[w] = 100.0 * (value - gathered_value[w]) / params[P_TOTAL_VALUE]
        gathered_value[w] = value
        steps[w] += 1
        everything = True
        for b in range(n_blocks):
            everything = everything and now[b]
        terminated[w] = everything
        truncated[w] = (not everything) and steps[w] >= params[P_MAX_CYCLES]
        if terminated[w] or truncated[w]:
            active[w] = False
    return count


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

