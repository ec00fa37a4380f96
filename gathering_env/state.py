"""The global state of a world: what a centralised critic (MAPPO, QMIX, MADDPG) sees.

One float32 vector of length ``5 * N + 5 * B + 1`` (N robots, B blocks; environment 1:
20 robots, 15 blocks, 176 entries), in this order:

* per robot i (``5 * i`` .. ``5 * i + 4``): x / arena_width, y / arena_height, cos(heading),
  sin(heading), attached (1.0 while the pickup heuristic holds it to a block, else 0.0);
* per block b (offset ``5 * N + 5 * b``): x / arena_width, y / arena_height, cos(angle),
  sin(angle), gathered (1.0 once it lies wholly inside the zone);
* last entry: the step fraction, steps / max_cycles.

Blocks are in world order (``GatheringWorld.block_type``: all small blocks, then medium,
then large). ``state_space(config)`` is the matching ``Box``; ``world_state`` builds the vector
from a world's arrays (the PettingZoo env's ``state()``; ``VectorSimulation.states()`` stacks
one per world).
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from .config import WorldConfig

ROBOT_FIELDS = ("x", "y", "cos_heading", "sin_heading", "attached")
BLOCK_FIELDS = ("x", "y", "cos_angle", "sin_angle", "gathered")


def state_size(config: WorldConfig) -> int:
    """Length of the state vector: 5 per robot, 5 per block, 1 for the step fraction."""
    return len(ROBOT_FIELDS) * config.num_robots + len(BLOCK_FIELDS) * config.num_blocks + 1


def state_space(config: WorldConfig) -> spaces.Box:
    """``Box`` of the state: positions and flags in [0, 1], cos/sin in [-1, 1], step fraction in [0, 1]."""
    row_low = np.array([0.0, 0.0, -1.0, -1.0, 0.0], dtype=np.float32)
    low = np.concatenate([np.tile(row_low, config.num_robots), np.tile(row_low, config.num_blocks), [0.0]])
    return spaces.Box(low.astype(np.float32), np.ones_like(low, dtype=np.float32), dtype=np.float32)


def world_state(config: WorldConfig, robot_pos: np.ndarray, robot_angle: np.ndarray,
                robot_attached: np.ndarray, block_pos: np.ndarray, block_angle: np.ndarray,
                gathered: np.ndarray, steps: int) -> np.ndarray:
    """The state vector (see the module docstring) from one world's arrays."""
    scale = np.array([config.arena_width, config.arena_height])
    # A body pressed against a wall may sit a hair outside the arena; keep the Box honest.
    robots = np.column_stack([np.clip(robot_pos / scale, 0.0, 1.0), np.cos(robot_angle), np.sin(robot_angle),
                              (np.asarray(robot_attached) >= 0).astype(float)])
    blocks = np.column_stack([np.clip(block_pos / scale, 0.0, 1.0), np.cos(block_angle), np.sin(block_angle),
                              np.asarray(gathered, dtype=float)])
    return np.concatenate([robots.ravel(), blocks.ravel(), [min(steps / config.max_cycles, 1.0)]]).astype(np.float32)


__all__ = ["BLOCK_FIELDS", "ROBOT_FIELDS", "state_size", "state_space", "world_state"]
