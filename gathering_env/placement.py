"""Where an episode's robots and blocks start: random, non-overlapping, outside the zone.

Blocks are placed first, then robots, each at uniform random positions (from the episode's
generator) until it clears the zone and every object placed before it by ``_PLACEMENT_GAP``.
Worlds that cannot be laid out fail with one ``ValueError`` naming the parameters: at once if
certainly impossible (``check_room``), else within a bounded number of attempts.
"""

from __future__ import annotations

import math

import numpy as np

from .config import WorldConfig

_PLACEMENT_GAP = 0.05
"""Clearance (units) between objects laid out at reset."""
_PLACEMENT_ATTEMPTS = 10_000
"""Random positions tried per object; all objects together get this many per 10 objects."""
_MAX_COVER = 0.45
"""Largest fraction of the floor outside the zone that objects (with clearance) may cover."""


def lay_out(cfg: WorldConfig, block_half: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Random non-overlapping positions outside the zone: blocks first, then robots."""
    radii = np.concatenate([
        block_half * math.sqrt(2.0),
        np.full(cfg.num_robots, cfg.robot_radius),
    ])
    zx0, zy0, zx1, zy1 = cfg.zone_rect
    placed = np.zeros((len(radii), 2))
    gap = _PLACEMENT_GAP
    check_room(cfg, radii)
    budget = _PLACEMENT_ATTEMPTS * (1 + len(radii) // 10)  # all objects together
    for i, rad in enumerate(radii):
        margin = rad + gap
        for _attempt in range(min(_PLACEMENT_ATTEMPTS, budget)):
            budget -= 1
            x = rng.uniform(margin, cfg.arena_width - margin)
            y = rng.uniform(margin, cfg.arena_height - margin)
            # keep the whole object outside the zone
            dx = max(zx0 - x, 0.0, x - zx1)
            dy = max(zy0 - y, 0.0, y - zy1)
            if math.hypot(dx, dy) <= margin:
                continue
            if i and np.any(np.hypot(placed[:i, 0] - x, placed[:i, 1] - y) < radii[:i] + margin):
                continue
            placed[i] = (x, y)
            break
        else:
            raise ValueError(
                f"could not place all robots and blocks without overlap (gave up at object {i + 1} of "
                f"{len(radii)}): the arena "
                f"({cfg.arena_width} x {cfg.arena_height}) is too small for "
                f"{cfg.num_robots} robots and block_counts={cfg.block_counts}"
            )
    nb = len(block_half)
    return placed[:nb], placed[nb:]


def check_placement(config: WorldConfig, seed: int = 0) -> None:
    """Raise ``ValueError`` unless the robots and blocks of ``config`` can be laid out once.

    Worlds that cannot work (a block wider than the arena, more object area than free
    floor) fail at once; crowded ones fail within a bounded number of attempts.
    """
    types = np.repeat(np.arange(3), config.block_counts)
    lay_out(config, 0.5 * np.asarray(config.block_sizes, dtype=float)[types], np.random.default_rng(seed))


def check_room(cfg: WorldConfig, radii: np.ndarray) -> None:
    """Raise ``ValueError`` for worlds whose objects certainly cannot be laid out."""
    if not len(radii):
        return
    margin = float(radii.max()) + _PLACEMENT_GAP
    zx0, zy0, zx1, zy1 = cfg.zone_rect
    room = f"the arena ({cfg.arena_width} x {cfg.arena_height}, zone {cfg.zone_width} x {cfg.zone_depth})"
    if 2 * margin >= cfg.arena_width or 2 * margin >= cfg.arena_height:
        raise ValueError(f"block_sizes={cfg.block_sizes}: an object of radius {margin - _PLACEMENT_GAP:.3g} does "
                         f"not fit into {room}; allowed: objects smaller than the arena")
    # Outside the zone: above it, or beside it if the zone leaves room at the sides.
    above = cfg.arena_height - margin > zy1 + margin
    beside = zx0 - margin > margin
    if not (above or beside):
        raise ValueError(f"block_sizes={cfg.block_sizes}: no room outside the gathering zone in {room} for an "
                         f"object of radius {margin - _PLACEMENT_GAP:.3g}; allowed: smaller objects or zone")
    free = cfg.arena_width * cfg.arena_height - cfg.zone_width * cfg.zone_depth
    need = float(np.sum(math.pi * (radii + 0.5 * _PLACEMENT_GAP) ** 2))
    if need > _MAX_COVER * free:
        raise ValueError(
            f"num_robots={cfg.num_robots}, block_counts={cfg.block_counts}: the robots and blocks would cover "
            f"{need / free:.0%} of the free floor of {room}; allowed: at most {_MAX_COVER:.0%} (random "
            "placement jams near 55 %): fewer or smaller objects, or a larger arena")
