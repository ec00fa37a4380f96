"""Compiled ``settle`` kernel (after the physics step: poses, gathered blocks, pickup and
release, the step's bookkeeping) and ``gathered_blocks``, operation for operation as the numpy
reference (``gathering_env.reference.heuristics`` and ``scoring``, ``GatheringWorld``)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .tables import (
    EV_ATTACH,
    EV_RELEASE,
    F_PICKUP,
    P_BOX_D,
    P_BOX_OFFSET,
    P_BOX_W,
    P_MAX_CYCLES,
    P_RADIUS,
    P_REACH,
    P_TOTAL_VALUE,
    P_ZX0,
    P_ZX1,
    P_ZY0,
    P_ZY1,
)

_SIDE_NX = (1.0, 0.0, -1.0, 0.0)   # outward normal of block side 0..3 (E, N, W, S), block frame
_SIDE_NY = (0.0, 1.0, 0.0, -1.0)
_SIDE_TX = (0.0, -1.0, 0.0, 1.0)   # tangent along the side
_SIDE_TY = (1.0, 0.0, -1.0, 0.0)


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
