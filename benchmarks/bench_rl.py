"""Training throughput of every RL route: SuperSuit and ``GatheringVecEnv`` (SB3 PPO), TorchRL's
``PettingZooWrapper`` and the batched ``GatheringTorchEnv`` (BenchMARL IPPO / MAPPO).

    OMP_NUM_THREADS=1 python benchmarks/bench_rl.py [--timesteps 40960] [--worlds 1 4] [--marl-frames 8192]

Same PPO settings on each route (the ones of examples/rl_ppo.py), environment 1, 20 robots,
2 000-step episodes, one torch thread. Routes:

* ``supersuit``: the unchanged PettingZoo env through ``pettingzoo_env_to_vec_env_v1`` and
  ``concat_vec_envs_v1`` (one world, one process), as examples/rl_ppo.py did before.
* ``vecenv W=...``: ``gathering_env.rl.sb3.GatheringVecEnv`` with W worlds stepped together.

Prints, per route, robot-steps per second of the whole ``learn`` call (rollout collection +
gradient updates) and of the rollout collection alone (SB3's ``time/fps`` excludes
nothing, so collection is timed with a random policy stepping the same vector env).

With TorchRL and BenchMARL installed (``[marl]``) it then prints the same for the MARL routes,
in environment steps per second (x robots = robot-steps) next to the SB3 vector env's:

* ``torchrl wrapper``: ``PettingZooWrapper(parallel_env(...))``, one world per env (BenchMARL
  stacks W of them in a ``SerialEnv``), task option ``route: wrapper``.
* ``torchrl batched W=...``: ``gathering_env.rl.torchrl_env.GatheringTorchEnv``, W worlds per call.

Stepping is ``rollout`` with random actions; training is a BenchMARL experiment (the settings of
examples/benchmarl_run.py: 1 024 environment steps per batch, 10 epochs of 128-step minibatches,
64-64 MLPs) for ``--marl-frames`` environment steps.
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


def torchrl_stepping_rate(route: str, worlds: int, robots: int, steps: int, env_steps: int) -> float:
    """Environment steps per second of ``rollout`` with random actions."""
    from gathering_env.rl.benchmarl_task import GatheringTask

    task = GatheringTask.ENV1.get_task({"environment": 1, "num_robots": robots, "max_cycles": steps, "route": route})
    env = task.get_env_fun(worlds, True, 0, "cpu")()
    if route == "wrapper" and worlds > 1:
        from torchrl.envs import SerialEnv

        env = SerialEnv(worlds, task.get_env_fun(1, True, 0, "cpu"))
    env.rollout(3, break_when_any_done=False)
    calls = max(1, env_steps // worlds)
    start = time.perf_counter()
    env.rollout(calls, break_when_any_done=False)
    return calls * worlds / (time.perf_counter() - start)


def benchmarl_rate(algorithm: str, route: str, worlds: int, robots: int, steps: int, frames: int) -> float:
    """Environment steps per second of a BenchMARL experiment (collection + training)."""
    import sys
    import tempfile
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
    import benchmarl_run

    with tempfile.TemporaryDirectory() as tmp:
        args = benchmarl_run.parse_args(["--algorithm", algorithm, "--robots", str(robots), "--steps", str(steps),
                                         "--worlds", str(worlds), "--env-steps", str(frames), "--out", tmp])
        (Path(tmp) / "benchmarl").mkdir()
        experiment = benchmarl_run.build_experiment(args, route=route)
        start = time.perf_counter()
        experiment.run()
        return experiment.total_frames / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--timesteps", type=int, default=40_960, help="robot-steps of PPO per route")
    parser.add_argument("--worlds", type=int, nargs="+", default=[1, 4])
    parser.add_argument("--robots", type=int, default=20)
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--marl-frames", type=int, default=8192, help="environment steps of each BenchMARL run")
    parser.add_argument("--marl-worlds", type=int, nargs="+", default=[1, 4, 8])
    parser.add_argument("--skip-sb3", action="store_true", help="only the TorchRL / BenchMARL routes")
    args = parser.parse_args()
    torch.set_num_threads(1)
    routes = [("supersuit", lambda: supersuit_env(args.robots, args.steps))]
    routes += [(f"vecenv W={w}", lambda w=w: vec_env(w, args.robots, args.steps)) for w in args.worlds]
    if not args.skip_sb3:
        print(f"PPO {PPO_SETTINGS}, environment 1, {args.robots} robots, {args.steps}-step episodes")
        print(f"{'route':<24} {'collect env-steps/s':>20} {'robot-steps/s':>14} {'PPO env-steps/s':>16} "
              f"{'robot-steps/s':>14}")
        for name, make in routes:
            collect = collection_rate(make(), args.timesteps // 4)
            train = training_rate(make(), args.timesteps)
            print(f"{name:<24} {collect / args.robots:>20.0f} {collect:>14.0f} {train / args.robots:>16.0f} "
                  f"{train:>14.0f}")
    try:
        import benchmarl  # noqa: F401
    except ImportError:
        print("TorchRL / BenchMARL routes skipped: pip install -e '.[marl]'")
        return
    print(f"BenchMARL, environment 1, {args.robots} robots, {args.steps}-step episodes, {args.marl_frames} env steps")
    print(f"{'route':<24} {'collect env-steps/s':>20} {'IPPO env-steps/s':>17} {'MAPPO env-steps/s':>18}")
    marl = [("wrapper", 4)] + [("batched", w) for w in args.marl_worlds]
    for route, w in marl:
        collect = torchrl_stepping_rate(route, w, args.robots, args.steps, min(args.marl_frames, 2048))
        ippo = benchmarl_rate("ippo", route, w, args.robots, args.steps, args.marl_frames)
        mappo = benchmarl_rate("mappo", route, w, args.robots, args.steps, args.marl_frames)
        name = f"torchrl {route} W={w}"
        print(f"{name:<24} {collect:>20.0f} {ippo:>17.0f} {mappo:>18.0f}")


if __name__ == "__main__":
    main()
