"""Shared-parameter PPO for the whole team (Stable-Baselines3) on the many-worlds vector env.

Every robot of every world is one sub-environment of ``gathering_env.rl.sb3.GatheringVecEnv``,
so one PPO policy is trained on all robots' experience at once and drives every robot at
test time. The reward is shaped by default (``--reward shaped``: potential-based shaping
towards the zone plus an attachment term) with local credit (``--reward-scope local``: each
robot is paid for the blocks it moves); ``--reward task`` is the task's own sparse reward and
``--reward-scope team`` pays every robot the team reward. The PPO settings (10 epochs per
rollout, step size 1e-3, rewards scaled by SB3's ``VecNormalize``) are the ones docs/rl/README.md
measured; the flags change them.

    pip install -e ".[rl]"          # stable-baselines3, torch==2.13.0 (the CPU build here)
    python examples/rl_ppo.py --environment 1 --env-steps 500000 --out runs/ppo-env1
    python examples/rl_ppo.py --reward-scope team --max-minutes 10 ...
    python examples/rl_ppo.py --morphology runs/quick/champion.json ...   # an evolved champion's sensors

Budgets count environment steps (one step of one world of N robots = N robot-steps, what
SB3 calls timesteps); ``--max-minutes`` stops earlier on wall-clock. Writes into ``--out``:
``model.zip`` (the policy), ``model.morphology.json`` (its sensors), ``model-ENV_STEPS.zip``
for every ``--snapshots`` budget (the policy as it was then), ``progress.csv`` (SB3's
log, plus ``rollout/ft_mean`` and ``rollout/team_return_mean``), ``curve.csv`` (one row per
finished training episode: env steps, minutes, ft, team return), ``curve.png`` (ft and team
return vs environment steps) and ``evaluation.json`` (ft over ``--eval-episodes`` held-out
seeds, 10 000 onwards, never used in training; with the policy's mean actions and with actions
sampled as in training).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")   # two processes on 2 cores otherwise thrash

import numpy as np  # noqa: E402
import torch  # noqa: E402
from stable_baselines3 import PPO  # noqa: E402
from stable_baselines3.common.callbacks import BaseCallback  # noqa: E402
from stable_baselines3.common.logger import configure  # noqa: E402
from stable_baselines3.common.vec_env import VecMonitor, VecNormalize  # noqa: E402

from evolution.compare import compare
from evolution.guard import (  # noqa: E402
    ArgumentParser,
    UsageError,
    check_output_dir,
    command,
    float_arg,
    int_arg,
    writing,
)
from evolution.policies.learned import ppo_policy  # noqa: E402
from evolution.run.champion import load_champion  # noqa: E402
from gathering_env import Morphology  # noqa: E402
from gathering_env.config import ENVIRONMENT_PRESETS, REWARD_SCOPES, REWARDS, WorldConfig  # noqa: E402
from gathering_env.rl.sb3 import MAX_WHEEL_LEVELS, GatheringVecEnv  # noqa: E402

DEFAULT_ENV_STEPS = 500_000
EVAL_SEED = 10_000
"""First held-out evaluation seed (training episode seeds come from the --seed generator)."""


class EpisodeLog(BaseCallback):
    """Records ft and the team's (shaped) return of every finished training episode."""

    def __init__(self, path: Path, num_robots: int, max_minutes: float | None,
                 snapshots: list[int] = (), morphology: Morphology | None = None) -> None:
        super().__init__()
        self.path, self.num_robots, self.max_minutes = path, num_robots, max_minutes
        self.snapshots, self.morphology = sorted(snapshots), morphology
        self.rows: list[dict] = []
        self.start = time.perf_counter()

    def _on_step(self) -> bool:
        minutes = (time.perf_counter() - self.start) / 60
        while self.snapshots and self.num_timesteps // self.num_robots >= self.snapshots[0]:
            save_model(self.model, self.path.parent / f"model-{self.snapshots.pop(0)}.zip", self.morphology)
        for k, info in enumerate(self.locals["infos"]):
            if k % self.num_robots == 0 and "task_performance" in info:   # one row per world
                self.rows.append({"env_steps": self.num_timesteps // self.num_robots, "minutes": round(minutes, 3),
                                  "ft": info["task_performance"], "team_return": info["team_return"]})
        return self.max_minutes is None or minutes < self.max_minutes

    def _on_rollout_end(self) -> None:
        recent = self.rows[-20:]
        if recent:
            self.logger.record("rollout/ft_mean", float(np.mean([r["ft"] for r in recent])))
            self.logger.record("rollout/team_return_mean", float(np.mean([r["team_return"] for r in recent])))
            self.save()

    def save(self) -> None:
        with writing(self.path), open(self.path, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=["env_steps", "minutes", "ft", "team_return"])
            writer.writeheader()
            writer.writerows(self.rows)


def save_model(model: PPO, path: Path, morphology: Morphology) -> None:
    """The policy and, next to it, its morphology (what ``gathering-compare --policy ppo:PATH`` reads)."""
    with writing(path):
        model.save(path)
    with writing(path.with_suffix(".morphology.json")):
        path.with_suffix(".morphology.json").write_text(json.dumps(morphology.to_dict(), indent=1))


def plot_curve(rows: list[dict], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 3.6), constrained_layout=True)
    if rows:
        steps = np.array([r["env_steps"] for r in rows])
        ft = np.array([r["ft"] for r in rows])
        ret = np.array([r["team_return"] for r in rows])
        window = max(1, len(rows) // 20)
        smooth = np.convolve(ft, np.ones(window) / window, mode="valid")
        ax.plot(steps, ft, ".", color="tab:blue", alpha=0.3, markersize=3)
        ax.plot(steps[window - 1:], smooth, color="tab:blue", label=f"ft (mean of {window} episodes)")
        ax.plot(steps, ret, ".", color="tab:orange", alpha=0.3, markersize=3)
        ax.plot(steps[window - 1:], np.convolve(ret, np.ones(window) / window, mode="valid"), color="tab:orange",
                label="team return (training reward)")
        ax.legend(fontsize=8)
    ax.set_xlabel("environment steps (world steps; x robots = SB3 timesteps)")
    ax.set_ylabel("per training episode")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    with writing(path):
        fig.savefig(path, dpi=110)
    plt.close(fig)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = ArgumentParser(prog="rl_ppo.py", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    count = int_arg(1, float("inf"))
    p.add_argument("--environment", type=int, default=1, choices=tuple(ENVIRONMENT_PRESETS))
    p.add_argument("--steps", type=count, default=2000, help="episode length (max_cycles) while training")
    p.add_argument("--eval-steps", type=count, default=None, help="episode length for the evaluation (default: --steps)")
    p.add_argument("--robots", type=count, default=20)
    p.add_argument("--worlds", type=count, default=4, help="worlds stepped together (sub-environments = worlds x robots)")
    p.add_argument("--reward", choices=REWARDS, default="shaped")
    p.add_argument("--attach-reward", type=float, default=WorldConfig.attach_reward,
                   help=f"bonus per attachment with --reward shaped (default {WorldConfig.attach_reward})")
    p.add_argument("--reward-scope", choices=REWARD_SCOPES, default="local",
                   help="credit: every robot the team reward, or local rewards (default local)")
    p.add_argument("--wheel-levels", type=int_arg(2, MAX_WHEEL_LEVELS), default=None, metavar="K",
                   help="discrete actions: K evenly spaced commands per wheel (MultiDiscrete([K, K]); "
                        "default: continuous wheel commands with Gaussian noise)")
    p.add_argument("--morphology", type=Path, help="champion JSON whose morphology to use (default: Khepera III)")
    p.add_argument("--env-steps", type=count, default=None,
                   help=f"training budget in environment steps (default {DEFAULT_ENV_STEPS:,})")
    p.add_argument("--timesteps", type=count, default=None,
                   help="training budget in robot-steps (SB3 timesteps) instead of --env-steps (not both)")
    p.add_argument("--snapshots", type=count, nargs="*", default=[], metavar="ENV_STEPS",
                   help="also save the policy as model-ENV_STEPS.zip when training passes these budgets "
                        "(e.g. an evolution run's budget, to compare at equal environment steps)")
    p.add_argument("--max-minutes", type=float_arg(0.0, open_low=True), default=None, help="stop training after this many minutes")
    p.add_argument("--n-steps", type=int_arg(2, float("inf")), default=256, help="PPO rollout length per sub-environment")
    p.add_argument("--gamma", type=float_arg(0.0, 1.0, open_low=True), default=0.99)
    p.add_argument("--ent-coef", type=float_arg(0.0), default=0.01,
                   help="entropy bonus (default 0.01; with 0 training collapsed, see docs/rl/README.md)")
    p.add_argument("--log-std-init", type=float_arg(-20.0, 20.0), default=0.0,
                   help="initial log standard deviation of the Gaussian action noise (SB3 default 0)")
    p.add_argument("--n-epochs", type=int_arg(1, 1000), default=10, help="gradient epochs per rollout (default 10)")
    p.add_argument("--learning-rate", type=float_arg(0.0, open_low=True), default=1e-3, help="Adam step size (default 1e-3)")
    p.add_argument("--norm-reward", action=argparse.BooleanOptionalAction, default=True,
                   help="scale rewards by a running estimate of the return's std (SB3 VecNormalize, rewards "
                        "only; default on)")
    p.add_argument("--seed", type=int_arg(0, 2**32 - 1), default=0)
    p.add_argument("--eval-episodes", type=count, default=5)
    p.add_argument("--out", type=Path, default=Path("runs/ppo"))
    args = p.parse_args(argv)
    if args.timesteps is not None and args.env_steps is not None:
        raise UsageError(f"--timesteps {args.timesteps}: conflicts with --env-steps {args.env_steps} (both set the "
                         "training budget); allowed: one of them")
    if args.eval_steps is None:
        args.eval_steps = args.steps
    return args


OUTPUTS = ("model.zip", "model.morphology.json", "progress.csv", "curve.csv", "curve.png", "evaluation.json")
"""The files a run writes into --out (plus model-ENV_STEPS.zip / .morphology.json per snapshot)."""


@command
def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    torch.set_num_threads(1)
    snapshots = [f"model-{n}{suffix}" for n in args.snapshots for suffix in (".zip", ".morphology.json")]
    check_output_dir(args.out, [*OUTPUTS, *snapshots])       # never overwrite anything but an earlier run's output
    trained = sorted(p.name for p in args.out.glob("model*.zip")) if args.out.is_dir() else []
    if trained:                                               # ... and never a trained model
        raise UsageError(f"--out {args.out}: holds a trained model ({', '.join(trained)}), which is never "
                         "overwritten; allowed: a new --out (or move the model away)")

    # 1. The morphology: Khepera III or an evolved champion's sensors.
    if args.morphology:
        morphology = load_champion(args.morphology).morphology
    else:
        morphology = Morphology.khepera_iii()

    # 2. W worlds x N robots as one SB3 vector env; every robot is a sub-environment.
    world = {"environment": args.environment, "num_robots": args.robots, "max_cycles": args.steps,
             "reward": args.reward, "attach_reward": args.attach_reward, "reward_scope": args.reward_scope}
    venv = VecMonitor(GatheringVecEnv(args.worlds, seed=args.seed, morphology=morphology,
                                      wheel_levels=args.wheel_levels, **world))
    if args.norm_reward:
        venv = VecNormalize(venv, norm_obs=False, norm_reward=True, gamma=args.gamma)

    # 3. PPO with one shared policy; logs to stdout and CSV.
    model = PPO("MlpPolicy", venv, n_steps=args.n_steps, batch_size=min(2048, args.n_steps * venv.num_envs),
                n_epochs=args.n_epochs, learning_rate=args.learning_rate, gamma=args.gamma, gae_lambda=0.95,
                ent_coef=args.ent_coef,
                policy_kwargs={} if args.wheel_levels else {"log_std_init": args.log_std_init},
                seed=args.seed, verbose=1, device="cpu")
    args.out.mkdir(parents=True, exist_ok=True)           # every input checked: only now touch the disk
    model.set_logger(configure(str(args.out), ["stdout", "csv"]))
    log = EpisodeLog(args.out / "curve.csv", args.robots, args.max_minutes, args.snapshots, morphology)
    start = time.perf_counter()
    budget = args.timesteps if args.timesteps is not None else (args.env_steps or DEFAULT_ENV_STEPS) * args.robots
    model.learn(total_timesteps=budget, callback=log, progress_bar=False)
    minutes = (time.perf_counter() - start) / 60
    log.save()
    env_steps = model.num_timesteps // args.robots
    model_path = args.out / "model.zip"
    save_model(model, model_path, morphology)
    title = (f"PPO env {args.environment}, reward={args.reward} ({args.reward_scope}), {args.worlds} worlds x "
             f"{args.robots} robots, {args.steps}-step episodes")
    plot_curve(log.rows, args.out / "curve.png", title)

    # 4. Evaluation on held-out seeds, through the same code path as gathering-compare.
    eval_steps = args.eval_steps
    seeds = list(range(EVAL_SEED, EVAL_SEED + args.eval_episodes))
    row, sampled = compare([ppo_policy(str(model_path)), ppo_policy(str(model_path), sample=True)],
                           {"environment": args.environment, "max_cycles": eval_steps, "num_robots": args.robots},
                           seeds)
    report = {"environment": args.environment, "reward": args.reward, "attach_reward": args.attach_reward,
              "reward_scope": args.reward_scope, "wheel_levels": args.wheel_levels, "worlds": args.worlds,
              "train_steps": args.steps,
              "env_steps": env_steps, "robot_steps": model.num_timesteps, "train_minutes": round(minutes, 2),
              "eval_steps": eval_steps, "eval_seeds": seeds, **row,
              "sampled": {"ft_mean": sampled["ft_mean"], "ft_std": sampled["ft_std"]}}
    with writing(args.out / "evaluation.json"):
        (args.out / "evaluation.json").write_text(json.dumps(report, indent=1))
    print(f"trained {env_steps} env steps ({model.num_timesteps} robot-steps) in {minutes:.1f} min; "
          f"ft over {len(seeds)} held-out episodes of {eval_steps} steps: {row['ft_mean']:.2f} +- {row['ft_std']:.2f} "
          f"(mean actions), {sampled['ft_mean']:.2f} +- {sampled['ft_std']:.2f} (sampled actions)")
    print(f"wrote {model_path}, {args.out / 'curve.png'}, {args.out / 'evaluation.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
