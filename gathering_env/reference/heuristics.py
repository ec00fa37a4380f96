"""Team heuristics as array operations: pickup detection, attached-robot drive, avoidance.

* **Pickup** (docs/model.md §2, on by default): a robot whose pickup box (``pickup_box_width``
  wide, ``pickup_box_depth`` deep, in front of its rim, or with ``pickup_box = "centre"``
  centred on the robot's centre as in the original code) holds an ungathered block with a
  free anchor attaches to it (``GatheringWorld.try_attach``).
* **Attached drive**: an attached robot ignores its controller and drives at full power
  towards the gathering zone's centre, forwards when the centre lies ahead of it and
  backwards (pulling its block) when it lies behind, its inner wheel slowed with the heading
  error (``WorldConfig.attached_steering``: stopped from 45 degrees off, or from 90 as the
  original's ``Heuristic``).
* **Collision avoidance** (optional, off by default): a free robot with another robot or
  a wall closer than ``collision_avoidance_distance`` ahead of its front turns on the spot,
  away from the obstacle, instead of following its controller.
"""

from __future__ import annotations

import math

import numpy as np

from ..world import GatheringWorld


def pickup_candidates(world: GatheringWorld, gathered: np.ndarray) -> list[tuple[int, int]]:
    """(robot, block) pairs where a free robot has an attachable block in its pickup box.

    Args:
        world: the current world.
        gathered: (B,) bool, blocks wholly inside the zone (never picked up).
    """
    cfg = world.config
    free_robots = np.flatnonzero(world.robot_attached < 0)
    if free_robots.size == 0:
        return []
    owners = (world.anchor_owner >= 0).sum(axis=1)
    open_blocks = ~gathered & ((world.block_sticky_side < 0) | (owners < world.block_need))
    blocks = np.flatnonzero(open_blocks)
    if blocks.size == 0:
        return []
    # Cheap prefilter on centre distances; the exact box test runs on the few survivors.
    reach = cfg.pickup_box_offset + 0.5 * (cfg.pickup_box_depth + cfg.pickup_box_width)
    reach = reach + world.block_half[blocks] * math.sqrt(2.0)
    dx = world.block_pos[blocks, 0] - world.robot_pos[free_robots, 0:1]
    dy = world.block_pos[blocks, 1] - world.robot_pos[free_robots, 1:2]
    near_r, near_b = np.nonzero(dx * dx + dy * dy <= reach * reach)
    if near_r.size == 0:
        return []
    free_robots, blocks = free_robots[near_r], blocks[near_b]       # candidate pairs
    pos = world.robot_pos[free_robots]
    ang = world.robot_angle[free_robots]
    hx, hy = np.cos(ang), np.sin(ang)
    centre_offset = cfg.pickup_box_offset
    box_x = pos[:, 0] + centre_offset * hx                         # (P,)
    box_y = pos[:, 1] + centre_offset * hy
    # Nearest block point to the box centre, per (robot, block).
    cb, sb = np.cos(world.block_angle[blocks]), np.sin(world.block_angle[blocks])
    half = world.block_half[blocks]
    rx = box_x - world.block_pos[blocks, 0]
    ry = box_y - world.block_pos[blocks, 1]
    lx = np.clip(rx * cb + ry * sb, -half, half)
    ly = np.clip(-rx * sb + ry * cb, -half, half)
    px = world.block_pos[blocks, 0] + lx * cb - ly * sb - box_x
    py = world.block_pos[blocks, 1] + lx * sb + ly * cb - box_y
    along = px * hx + py * hy
    across = -px * hy + py * hx
    inside = (np.abs(along) <= 0.5 * cfg.pickup_box_depth) & (np.abs(across) <= 0.5 * cfg.pickup_box_width)
    return [(int(r), int(b)) for r, b in zip(free_robots[inside], blocks[inside])]


def zone_heading_error(world: GatheringWorld, robots: np.ndarray) -> np.ndarray:
    """Each robot's heading error to the zone centre: the bearing of the centre less the robot's
    heading, in [-pi, pi) (positive: the centre lies to its left)."""
    cx, cy = world.config.zone_centre
    # libm's atan2 (as the compiled kernel uses), not numpy's own SIMD arctan2, which differs
    # from it in the last bit: both kernels must steer identically.
    bearing = np.array([math.atan2(cy - y, cx - x) for x, y in world.robot_pos[robots].tolist()])
    return _wrap(bearing - world.robot_angle[robots])


def attached_wheels(world: GatheringWorld, robots: np.ndarray) -> np.ndarray:
    """(len(robots), 2) full-power wheel commands steering towards the zone centre
    (``WorldConfig.attached_steering``)."""
    cfg = world.config
    error = zone_heading_error(world, robots)
    if cfg.attached_steering == "original":
        # Heuristic.wheelDriveForTargetAngle's quadrants: backwards from +90 degrees on, forwards
        # at -90; the outer wheel at full power, the inner one slowed linearly to 0 at 90 degrees.
        backwards = (error >= 0.5 * math.pi) | (error < -0.5 * math.pi)
        direction = np.where(backwards, -1.0, 1.0)
        error = np.where(backwards, _wrap(error - math.pi), error)
        inner = direction * (1.0 - np.abs(error) / (0.5 * math.pi))
        left_inner = error * direction >= 0.0
        return np.stack([np.where(left_inner, inner, direction), np.where(left_inner, direction, inner)], axis=1)
    backwards = np.abs(error) > 0.5 * math.pi
    direction = np.where(backwards, -1.0, 1.0)
    error = np.where(backwards, _wrap(error - math.pi), error)
    turn = np.clip(2.0 * error / (0.5 * math.pi), -1.0, 1.0)
    left = direction - turn
    right = direction + turn
    scale = np.maximum(np.maximum(np.abs(left), np.abs(right)), 1.0)
    return np.stack([left / scale, right / scale], axis=1)


def avoidance_turns(world: GatheringWorld, wheels: np.ndarray) -> np.ndarray:
    """Wheel commands with a turn on the spot for free robots facing a near obstacle."""
    cfg = world.config
    free = world.robot_attached < 0
    pos, ang = world.robot_pos, world.robot_angle
    hx, hy = np.cos(ang), np.sin(ang)
    reach = cfg.robot_radius + cfg.collision_avoidance_distance
    dx = pos[None, :, 0] - pos[:, None, 0]
    dy = pos[None, :, 1] - pos[:, None, 1]
    along = dx * hx[:, None] + dy * hy[:, None]
    across = -dx * hy[:, None] + dy * hx[:, None]
    ahead = (along > 0) & (along < reach + cfg.robot_radius) & (np.abs(across) < 2 * cfg.robot_radius)
    np.fill_diagonal(ahead, False)
    robot_side = np.where(ahead, across, 0.0).sum(axis=1)         # > 0: obstacle on the left
    front_x = pos[:, 0] + reach * hx
    front_y = pos[:, 1] + reach * hy
    wall = (front_x < 0) | (front_x > cfg.arena_width) | (front_y < 0) | (front_y > cfg.arena_height)
    blocked = free & (ahead.any(axis=1) | wall)
    turn_right = np.where(robot_side > 0, 1.0, np.where(robot_side < 0, -1.0, 1.0))
    out = wheels.copy()
    out[blocked, 0] = turn_right[blocked]
    out[blocked, 1] = -turn_right[blocked]
    return out


def _wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi
