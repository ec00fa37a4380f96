"""Shared-parameter PPO for the whole team (Stable-Baselines3 + SuperSuit), on a fixed morphology.

Every robot is one "environment" of a vectorised env (SuperSuit's PettingZoo-to-vec-env
wrappers, the route PettingZoo's documentation shows), so one PPO policy is trained on all
robots' experience at once and drives every robot at test time.

    pip install -e ".[rl]"          # supersuit, stable-baselines3, torch==2.13.0 (the CPU build here)
    python examples/rl_ppo.py --environment 1 --timesteps 200000 --out runs/ppo-env1
    python examples/rl_ppo.py --morphology runs/quick/champion.json ...   # an evolved champion's sensors

Writes ``model.zip`` (the policy), ``model.morphology.json`` (the sensors it was trained with),
``progress.csv`` (SB3's training log; TensorBoard too if ``tensorboard`` is installed) and
``evaluation.json`` (ft over ``--eval-episodes`` fresh seeds). Timesteps count robot-steps:
``--timesteps 200000`` with 20 robots is 10 000 environment steps.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import time
from pathlib import Path

import supersuit as ss
from stable_baselines3 import PPO
from stable_baselines3.common.logger import configure
from stable_baselines3.common.utils import set_random_seed
from stable_baselines3.common.vec_env import VecMonitor

from evolution.compare import compare, ppo_policy
from gathering_env import Morphology, parallel_env


def parse_args() -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--environment", type=int, default=1, choices=(1, 2, 3))
    p.add_argument("--steps", type=int, default=1000, help="episode length (max_cycles) while training")
    p.add_argument("--eval-steps", type=int, default=None, help="episode length for the evaluation (default: --steps)")
    p.add_argument("--robots", type=int, default=20)
    p.add_argument("--morphology", type=Path, help="champion JSON whose morphology to use (default: Khepera III)")
    p.add_argument("--timesteps", type=int, default=200_000, help="robot-steps of training")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--eval-episodes", type=int, default=5)
    p.add_argument("--out", type=Path, default=Path("runs/ppo"))
    return p.parse_args()


def main() -> None:
    args = parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    # 1. The morphology: Khepera III or an evolved champion's sensors.
    if args.morphology:
        morphology = Morphology.from_dict(json.loads(args.morphology.read_text())["morphology"])
    else:
        morphology = Morphology.khepera_iii()

    # 2. The team env, unchanged, turned into a vector env with one entry per robot.
    env = parallel_env(environment=args.environment, num_robots=args.robots, max_cycles=args.steps,
                       morphology=morphology)
    # SuperSuit 3.11's SB3 wrapper cannot forward seeds (its ConcatVecEnv has no seed()), so the
    # episodes are seeded on the env itself: later resets continue its seeded random stream.
    env.reset(seed=args.seed)
    vec_env = ss.pettingzoo_env_to_vec_env_v1(env)
    vec_env = ss.concat_vec_envs_v1(vec_env, 1, num_cpus=0, base_class="stable_baselines3")
    vec_env = VecMonitor(vec_env)  # episode return/length in the logs (rollout/ep_rew_mean)
    set_random_seed(args.seed)  # numpy, torch, python

    # 3. PPO with one shared policy; logs to stdout, CSV (and TensorBoard when available).
    formats = ["stdout", "csv"] + (["tensorboard"] if importlib.util.find_spec("tensorboard") else [])
    model = PPO("MlpPolicy", vec_env, n_steps=256, batch_size=1024, learning_rate=3e-4, gamma=0.995,
                ent_coef=0.01, verbose=1, device="cpu")
    model.set_logger(configure(str(args.out), formats))
    start = time.perf_counter()
    model.learn(total_timesteps=args.timesteps, progress_bar=False)
    minutes = (time.perf_counter() - start) / 60
    model_path = args.out / "model.zip"
    model.save(model_path)
    (args.out / "model.morphology.json").write_text(json.dumps(morphology.to_dict(), indent=1))

    # 4. Evaluation on fresh seeds, through the same code path as gathering-compare.
    eval_steps = args.eval_steps or args.steps
    seeds = list(range(10_000, 10_000 + args.eval_episodes))
    row = compare([ppo_policy(str(model_path))],
                  {"environment": args.environment, "max_cycles": eval_steps, "num_robots": args.robots}, seeds)[0]
    report = {"environment": args.environment, "timesteps": args.timesteps,
              "env_steps": args.timesteps // args.robots, "train_minutes": round(minutes, 2),
              "eval_steps": eval_steps, "eval_seeds": seeds, **row}
    (args.out / "evaluation.json").write_text(json.dumps(report, indent=1))
    print(f"trained {args.timesteps} robot-steps ({args.timesteps // args.robots} env steps) in {minutes:.1f} min; "
          f"ft over {len(seeds)} episodes of {eval_steps} steps: {row['ft_mean']:.2f} +- {row['ft_std']:.2f}")
    print(f"wrote {model_path}, {args.out / 'progress.csv'}, {args.out / 'evaluation.json'}")


if __name__ == "__main__":
    main()
