"""Environment throughput: steps/s through the PettingZoo API, the batched path, and bare pymunk.

Setting (the paper's): environment 2, 20 robots, Khepera III morphology, pickup heuristic
on, uniformly random wheel commands (drawn up front so sampling is not timed), one process.

    python benchmarks/bench_env.py [--steps 10000] [--repeats 3]

Prints, for each path, the best of ``--repeats`` runs: env steps/s, robot-steps/s and the
time of one 10 000-step trial. "bare pymunk" steps the same world (robots, blocks, ground
friction joints, drive through control bodies) with no sensing, heuristics, scoring or API.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from gathering_env import parallel_env
from gathering_env.config import WorldConfig
from gathering_env.simulation import GatheringSimulation


def run_api(steps: int, actions: np.ndarray) -> float:
    env = parallel_env(environment=2, num_robots=20, max_cycles=steps)
    env.reset(seed=0)
    agents = list(env.possible_agents)
    start = time.perf_counter()
    for t in range(steps):
        env.step(dict(zip(agents, actions[t])))
    return time.perf_counter() - start


def run_batched(steps: int, actions: np.ndarray) -> float:
    env = parallel_env(environment=2, num_robots=20, max_cycles=steps)
    env.reset(seed=0)
    start = time.perf_counter()
    for t in range(steps):
        env.step_batch(actions[t])
    return time.perf_counter() - start


def run_bare(steps: int, actions: np.ndarray) -> float:
    sim = GatheringSimulation(WorldConfig.from_kwargs(environment=2, num_robots=20, max_cycles=steps))
    sim.reset(seed=0)
    world = sim.world
    start = time.perf_counter()
    for t in range(steps):
        world.apply_drive(actions[t])
        world.step_physics()
    return time.perf_counter() - start


def run_sensing_only(steps: int, actions: np.ndarray) -> float:
    sim = GatheringSimulation(WorldConfig.from_kwargs(environment=2, num_robots=20, max_cycles=steps))
    sim.reset(seed=0)
    w = sim.world
    start = time.perf_counter()
    for _ in range(steps):
        sim.bank.read(w.robot_pos, w.robot_angle, w.block_pos, w.block_angle)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=10_000, help="steps per timed run (default 10000)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per path; the best is reported")
    args = parser.parse_args()
    actions = np.random.default_rng(0).uniform(-1, 1, size=(args.steps, 20, 2))
    print(f"collective gathering, environment 2, 20 robots, Khepera III, pickup on, {args.steps} steps")
    print(f"{'path':<28}{'steps/s':>10}{'robot-steps/s':>16}{'10k-step trial (s)':>20}")
    for name, fn in (("PettingZoo parallel API", run_api), ("batched (step_batch)", run_batched),
                     ("bare pymunk (no sensing)", run_bare), ("sensing kernel alone", run_sensing_only)):
        best = min(fn(args.steps, actions) for _ in range(args.repeats))
        rate = args.steps / best
        print(f"{name:<28}{rate:>10.0f}{rate * 20:>16.0f}{10_000 / rate:>20.2f}")


if __name__ == "__main__":
    main()
