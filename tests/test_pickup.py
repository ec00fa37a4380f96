"""Pickup heuristic rules (docs/model.md §2) on hand-placed scenes: box, reach, sticky side, full blocks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gathering_env.config import WorldConfig
from gathering_env.simulation import GatheringSimulation

BLOCK = (20.0, 30.0)  # block centre, far from the zone and the walls


def world(block_type: int, robots: int) -> GatheringSimulation:
    counts = [0, 0, 0]
    counts[block_type] = 1
    cfg = WorldConfig.from_kwargs(environment=None, block_counts=counts, num_robots=robots, max_cycles=1000)
    sim = GatheringSimulation(cfg)
    sim.reset(seed=1)
    sim.world.place_block(0, *BLOCK, 0.0)
    for i in range(robots):  # park every robot far away, facing west
        sim.world.place_robot(i, 3.0 + 0.5 * i, 36.0, math.pi)
    return sim


def north(sim: GatheringSimulation, robot: int, gap: float, dx: float = 0.0, angle: float = -math.pi / 2) -> None:
    """Put ``robot`` north of the block, ``gap`` between its rim and the block's north face."""
    half, r = sim.world.block_half[0], sim.config.robot_radius
    sim.world.place_robot(robot, BLOCK[0] + dx, BLOCK[1] + half + r + gap, angle)


def step(sim: GatheringSimulation) -> np.ndarray:
    sim.step(np.zeros((sim.config.num_robots, 2)))
    return sim.world.robot_attached.copy()


def test_pickup_box_depth_and_facing():
    cfg = WorldConfig()
    assert (cfg.pickup_box_width, cfg.pickup_box_depth) == (0.1, 0.2)   # docs/model.md §2: 0.1 wide x 0.2 deep
    near = world(0, 1)
    north(near, 0, gap=0.15)                  # face within the 0.2-deep box
    assert step(near)[0] == 0
    far = world(0, 1)
    north(far, 0, gap=0.3)                    # beyond the box
    assert step(far)[0] == -1
    back = world(0, 1)
    north(back, 0, gap=0.05, angle=math.pi / 2)  # touching, but facing away
    assert step(back)[0] == -1


def test_pickup_box_width():
    # Facing south beside the block: the box (0.05 either side of the heading line) misses it.
    half = world(0, 1).world.block_half[0]
    beside = world(0, 1)
    north(beside, 0, gap=0.05, dx=half + 0.08)
    assert step(beside)[0] == -1
    inside = world(0, 1)
    north(inside, 0, gap=0.05, dx=half + 0.02)
    assert step(inside)[0] == 0


def test_reach_to_an_anchor():
    # A large block (3 anchors per side at -2/3, 0, 2/3 of the half side); try_attach alone.
    sim = world(2, 1)
    w, r = sim.world, sim.config.robot_radius
    half = w.block_half[0]
    reach = sim.config.pickup_reach * r                     # 2.5 robot radii
    # The robot's front straight north of the north side's last anchor, just beyond / within reach.
    anchor = (BLOCK[0] + 2.0 / 3.0 * half, BLOCK[1] + half)
    w.place_robot(0, anchor[0], anchor[1] + reach + 0.02 + r, -math.pi / 2)
    assert not w.try_attach(0, 0)
    w.place_robot(0, anchor[0], anchor[1] + reach - 0.02 + r, -math.pi / 2)
    assert w.try_attach(0, 0)


def test_sticky_side():
    sim = world(2, 3)                          # a large block needs 3 robots
    north(sim, 0, gap=0.05)
    assert step(sim)[0] == 0
    assert sim.world.block_sticky_side[0] >= 0
    half, r = sim.world.block_half[0], sim.config.robot_radius
    # A robot touching the south face, facing north: its nearest anchor is on the south side,
    # more than the reach away from every north anchor -> refused.
    sim.world.place_robot(1, BLOCK[0], BLOCK[1] - half - r - 0.05, math.pi / 2)
    attached = step(sim)
    assert attached[1] == -1
    # A second robot on the sticky (north) side is accepted.
    north(sim, 2, gap=0.05, dx=2.0 / 3.0 * half)
    assert step(sim)[2] == 0


@pytest.mark.parametrize("block_type", [0, 1])
def test_a_full_block_refuses_more_robots(block_type):
    need = block_type + 1
    sim = world(block_type, need + 1)
    half = sim.world.block_half[0]
    offsets = ((np.arange(need) + 0.5) / need * 2 - 1) * half     # the side's anchor points
    for i in range(need):
        north(sim, i, gap=0.05, dx=float(offsets[i]))
    attached = step(sim)
    assert (attached[:need] == 0).all()
    north(sim, need, gap=0.05, dx=0.0)         # one more robot at the full block's sticky side
    assert step(sim)[need] == -1
    assert (sim.world.anchor_owner[0, :need] >= 0).all()
