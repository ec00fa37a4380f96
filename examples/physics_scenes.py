"""Scripted physics scenes: this simulator's pushing beside the original code's, measured.

Each scene drives robots with constant wheel commands and no grips (pickup off) and measures
what the original's Java classes were measured doing in the same scene (its compiled 2018
code, jbox2d, ``world.step(0.1, 6, 3)``; robots heading +y unless said; figures below as
"fixed order / shuffled": every robot then the world, or MASON's shuffled schedule as the
original runs, median of 20 seeds). Worlds compared: ``paper`` (this package's defaults),
``original`` (the physics keys of ``protocol = "original"``'s version 2: mass friction, Box2D
restitution, the original robot's push and top speed on the velocity drive) and ``force`` (the same with the
original's robot as ``drive_model = "force"`` models it: wheel forces, traction impulse, its
own ground friction, Box2D damping 0.1) and ``shuffled`` (the force drive under MASON's shuffled
schedule, ``schedule = "shuffled"``: the median over the schedules of seeds 0..19, as the
original's shuffled figures are). Speeds are the mean over the last 20 steps.

    python examples/physics_scenes.py            # prints a markdown table (about 10 s)
"""

from __future__ import annotations

import math

import numpy as np

from evolution.guard import ArgumentParser, command
from evolution.run.protocol import (
    ORIGINAL_FORCE_DRIVE,
    ORIGINAL_PHYSICS,
    ORIGINAL_SCHEDULE,
    ORIGINAL_VELOCITY_DRIVE,
    protocol_values,
)
from gathering_env.config import WorldConfig
from gathering_env.simulation import GatheringSimulation

START = (4.0, 2.0)
"""Where the pushed block starts: west of the zone, pushed north, 38 units from the far wall."""

#: scene -> (what is measured, the original's figure fixed order, shuffled schedule)
ORIGINAL = {
    "free robot, full drive, heading +y": ("speed (units/s)", 0.637, 0.838),
    "free robot, full drive, heading +x": ("speed (units/s)", 0.256, 0.441),
    "free robot, drive 0.5, heading +y": ("speed (units/s)", 0.196, 0.202),
    "free robot, drive 0.3, heading +y": ("speed (units/s)", 0.0, 0.0665),
    "block sliding from 0.5 units/s": ("distance to rest", 0.098, 0.098),
    "1 robot, small block": ("moved in 500 steps", 22.7, 31.8),
    "1 robot, medium block": ("moved in 500 steps", 7.33, 17.1),
    "1 robot, large block": ("moved in 500 steps", 2.01, 3.19),
    "2 robots, medium block": ("moved in 500 steps", 4.79, 2.51),
    "2 robots, large block": ("moved in 500 steps", 2.59, 1.52),
    "3 robots, large block": ("moved in 500 steps", 3.50, 2.08),
}


SHUFFLED_SEEDS = range(20)
"""The schedules the 'shuffled' world's figures are the median over (the original's: 20 seeds)."""


def physics(world: str) -> dict:
    """World overrides of a compared world (pickup off in all)."""
    keys = {}
    if world in ("original", "force", "shuffled"):
        env = protocol_values("original", 2)["environment"]  # version 2: the velocity drive's model
        keys = {key: env[key] for key in ORIGINAL_PHYSICS}
    if world in ("force", "shuffled"):
        for key in ORIGINAL_VELOCITY_DRIVE:
            del keys[key]
        keys.update(ORIGINAL_FORCE_DRIVE)
    if world == "shuffled":
        keys.update(ORIGINAL_SCHEDULE)
    return keys


def simulation(world: str, block_type: int, robots: int, seed: int = 0) -> GatheringSimulation:
    counts = [0, 0, 0]
    counts[block_type] = 1
    cfg = WorldConfig.from_kwargs(environment=None, block_counts=counts, num_robots=robots,
                                  pickup_heuristic=False, max_cycles=100_000, **physics(world))
    sim = GatheringSimulation(cfg)
    sim.reset(seed=seed)   # every body is placed by hand: the seed only picks the schedule
    return sim


def free_drive(world: str, heading: float, steps: int = 300, drive: float = 1.0, last: int = 20,
               seed: int = 0) -> float:
    """Mean speed over the ``last`` of ``steps`` steps (the force drive heading +x stops and goes)."""
    sim = simulation(world, 0, 1, seed)
    sim.world.place_block(0, 35.0, 35.0, 0.0)
    sim.world.place_robot(0, 2.0, 2.0, heading)
    for _ in range(steps - last):
        sim.step(np.full((1, 2), drive))
    before = sim.world.robot_pos[0].copy()
    for _ in range(last):
        sim.step(np.full((1, 2), drive))
    return float(np.hypot(*(sim.world.robot_pos[0] - before)) / (last * sim.config.dt))


def slide(world: str, speed: float = 0.5, seed: int = 0) -> float:
    sim = simulation(world, 0, 1, seed)
    w = sim.world
    w.place_robot(0, 35.0, 35.0, 0.0)
    w.place_block(0, *START, 0.0)
    w.block_bodies[0].velocity = (0.0, speed)
    w.read_state()
    for _ in range(200):
        sim.step(np.zeros((1, 2)))
    return float(np.hypot(*(w.block_pos[0] - START)))


def push(world: str, block_type: int, robots: int, steps: int = 500, seed: int = 0) -> float:
    """``robots`` side by side (0.32 apart) 0.01 below the block's south face, heading north."""
    sim = simulation(world, block_type, robots, seed)
    w, cfg = sim.world, sim.config
    w.place_block(0, *START, 0.0)
    for i in range(robots):
        dx = (i - (robots - 1) / 2) * 0.32
        w.place_robot(i, START[0] + dx, START[1] - w.block_half[0] - cfg.robot_radius - 0.01, math.pi / 2)
    for _ in range(steps):
        sim.step(np.ones((robots, 2)))
    return float(np.hypot(*(w.block_pos[0] - START)))


def measure(world: str) -> dict[str, float]:
    """Every scene's figure in ``world`` (under 'shuffled' the median over ``SHUFFLED_SEEDS``)."""
    if world == "shuffled":
        runs = [measure_once(world, seed) for seed in SHUFFLED_SEEDS]
        return {scene: float(np.median([run[scene] for run in runs])) for scene in runs[0]}
    return measure_once(world, 0)


def measure_once(world: str, seed: int) -> dict[str, float]:
    return {
        "free robot, full drive, heading +y": free_drive(world, math.pi / 2, seed=seed),
        "free robot, full drive, heading +x": free_drive(world, 0.0, seed=seed),
        "free robot, drive 0.5, heading +y": free_drive(world, math.pi / 2, drive=0.5, seed=seed),
        "free robot, drive 0.3, heading +y": free_drive(world, math.pi / 2, drive=0.3, seed=seed),
        "block sliding from 0.5 units/s": slide(world, seed=seed),
        "1 robot, small block": push(world, 0, 1, seed=seed),
        "1 robot, medium block": push(world, 1, 1, seed=seed),
        "1 robot, large block": push(world, 2, 1, seed=seed),
        "2 robots, medium block": push(world, 1, 2, seed=seed),
        "2 robots, large block": push(world, 2, 2, seed=seed),
        "3 robots, large block": push(world, 2, 3, seed=seed),
    }


@command
def main(argv: list[str] | None = None) -> int:
    ArgumentParser(description=__doc__.splitlines()[0]).parse_args(argv)
    ours = {world: measure(world) for world in ("paper", "original", "force", "shuffled")}
    print("| scene | measured | original (fixed order / shuffled) | here, original protocol version 2 | here, paper "
          "| here, force drive | here, force drive, shuffled (version 3) |")
    print("|---|---|---|---|---|---|---|")
    for scene, (what, fixed, shuffled) in ORIGINAL.items():
        print(f"| {scene} | {what} | {fixed:.3g} / {shuffled:.3g} | {ours['original'][scene]:.3g} "
              f"| {ours['paper'][scene]:.3g} | {ours['force'][scene]:.3g} | {ours['shuffled'][scene]:.3g} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
