"""PPO training throughput (robot-steps per second): SuperSuit route vs ``GatheringVecEnv``.

    OMP_NUM_THREADS=1 python benchmarks/bench_rl.py [--timesteps 40960] [--worlds 1 4]

Same PPO settings on each route (the ones of examples/rl_ppo.py), environment 1, 20 robots,
2 000-step episodes, one torch thread. Routes:

* ``supersuit``: the unchanged PettingZoo env through ``pettingzoo_env_to_vec_env_v1`` and
  ``concat_vec_envs_v1`` (one world, one process), as examples/rl_ppo.py did before.
* ``vecenv W=...``: ``gathering_env.rl.sb3.GatheringVecEnv`` with W worlds stepped together.

Prints, per route, robot-steps per second of the whole ``learn`` call (rollout collection +
gradient updates) and of the rollout collection alone (SB3's ``time/fps`` excludes
nothing, so collection is timed with a random policy stepping the same vector env).
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import numpy as np  # noqa: E402
import torch  # noqa: E402

PPO_SETTINGS = dict(n_steps=256, batch_size=1280, n_epochs=4, learning_rate=3e-4, gamma=0.99,
                    ent_coef=0.01, device="cpu", verbose=0)


def supersuit_env(robots: int, steps: int):
    import supersuit as ss

    from gathering_env import parallel_env

    env = parallel_env(environment=1, num_robots=robots, max_cycles=steps)
    env.reset(seed=0)
    venv = ss.pettingzoo_env_to_vec_env_v1(env)
    return ss.concat_vec_envs_v1(venv, 1, num_cpus=0, base_class="stable_baselines3")


def vec_env(worlds: int, robots: int, steps: int):
    from gathering_env.rl.sb3 import GatheringVecEnv

    return GatheringVecEnv(worlds, seed=0, environment=1, num_robots=robots, max_cycles=steps)


def collection_rate(venv, robot_steps: int) -> float:
    rng = np.random.default_rng(0)
    venv.reset()
    calls = max(1, robot_steps // venv.num_envs)
    start = time.perf_counter()
    for _ in range(calls):
        venv.step(rng.uniform(-1, 1, (venv.num_envs, 2)).astype(np.float32))
    return calls * venv.num_envs / (time.perf_counter() - start)


def training_rate(venv, timesteps: int) -> float:
    from stable_baselines3 import PPO

    model = PPO("MlpPolicy", venv, **PPO_SETTINGS)
    start = time.perf_counter()
    model.learn(total_timesteps=timesteps)
    return model.num_timesteps / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--timesteps", type=int, default=40_960, help="robot-steps of PPO per route")
    parser.add_argument("--worlds", type=int, nargs="+", default=[1, 4])
    parser.add_argument("--robots", type=int, default=20)
    parser.add_argument("--steps", type=int, default=2000)
    args = parser.parse_args()
    torch.set_num_threads(1)
    routes = [("supersuit", lambda: supersuit_env(args.robots, args.steps))]
    routes += [(f"vecenv W={w}", lambda w=w: vec_env(w, args.robots, args.steps)) for w in args.worlds]
    print(f"PPO {PPO_SETTINGS}, environment 1, {args.robots} robots, {args.steps}-step episodes")
    print(f"{'route':<14} {'collect robot-steps/s':>22} {'PPO robot-steps/s':>18}")
    for name, make in routes:
        collect = collection_rate(make(), args.timesteps // 4)
        train = training_rate(make(), args.timesteps)
        print(f"{name:<14} {collect:>22.0f} {train:>18.0f}")


if __name__ == "__main__":
    main()
