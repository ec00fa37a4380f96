"""Contact restitution of robots, blocks and walls, mixed the way Box2D mixes it.

A contact's restitution is the larger of its two shapes' restitutions (Box2D, the engine of
the original code); pymunk instead multiplies its shapes' ``elasticity``. ``apply_restitution``
gives each kind of shape an elasticity whose products equal the larger of the two for as many
kinds of contact as it can (robot contacts first: they are the common ones) and registers a
pre-solve handler, which sets the arbiter's restitution itself, for the kinds of contact left.
With the original's values (robots 1, blocks 0.4, walls 1) that is one handler, for the rare
block-on-block contact; with every restitution 0 (the default) there is none.
"""

from __future__ import annotations

import itertools

import pymunk

from .config import WorldConfig

ROBOT, BLOCK, WALL = 1, 2, 3
"""pymunk collision types of robot, block and wall shapes."""
_KIND = {"robot": ROBOT, "block": BLOCK, "wall": WALL}
_PAIRS = (("robot", "robot", 4), ("robot", "block", 4), ("robot", "wall", 4),
          ("block", "block", 1), ("block", "wall", 1))
"""Kinds of contact (walls never touch walls), each with how common it is."""


def restitutions(config: WorldConfig) -> dict[str, float]:
    """{kind: restitution} of robots, blocks and walls."""
    return {"robot": config.robot_restitution, "block": config.block_restitution,
            "wall": config.wall_restitution}


def mixing(config: WorldConfig) -> tuple[dict[str, float], list[tuple[str, str, float]]]:
    """(elasticity of each kind of shape, [(kind, kind, restitution) of the contacts whose
    elasticity product is not the larger restitution and need a handler]).

    Each kind takes its own restitution or 1 (the product of 1 and r is r), whichever leaves
    the fewest common contacts to handlers."""
    e = restitutions(config)
    best: tuple[int, dict[str, float], list] | None = None
    for ones in itertools.product((False, True), repeat=len(e)):
        x = {kind: 1.0 if one else e[kind] for kind, one in zip(e, ones)}
        wrong = [(a, b, w) for a, b, w in _PAIRS if x[a] * x[b] != max(e[a], e[b])]
        left = [(a, b, max(e[a], e[b])) for a, b, _ in wrong]
        cost = sum(w for _, _, w in wrong)
        if best is None or cost < best[0]:
            best = (cost, x, left)
    return best[1], best[2]


def _set_restitution(arbiter: pymunk.Arbiter, space: pymunk.Space, value: float) -> None:
    arbiter.restitution = value


def apply_restitution(space: pymunk.Space, shapes: dict[str, list[pymunk.Shape]],
                      config: WorldConfig) -> None:
    """Tag ``shapes`` ({kind: shapes}) with their collision type and elasticity and register
    the handlers ``mixing`` leaves."""
    elasticity, left = mixing(config)
    for kind, group in shapes.items():
        for shape in group:
            shape.collision_type = _KIND[kind]
            shape.elasticity = elasticity[kind]
    for a, b, value in left:
        space.on_collision(_KIND[a], _KIND[b], pre_solve=_set_restitution, data=value)


__all__ = ["BLOCK", "ROBOT", "WALL", "apply_restitution", "mixing", "restitutions"]
