"""Train a BenchMARL algorithm (IPPO, MAPPO, ...) on a gathering environment and export its policy.

The task is ``gathering_env.rl.benchmarl_task.GatheringTask`` (environments 1-3, the reward
options of docs/rl/README.md); its env is the batched TorchRL env over ``VectorSimulation``
(``--worlds`` worlds per call, one group of N robots, the global state for centralised
critics). BenchMARL's own algorithm, model and experiment classes do the training; the flags
set the few settings that matter (defaults: the shared-parameter PPO settings of
docs/rl/README.md as far as BenchMARL has them)::

    pip install -e ".[marl]"     # torchrl, benchmarl (torch==2.13.0, the CPU build here)
    python examples/benchmarl_run.py --algorithm mappo --environment 1 --env-steps 480000 --out runs/mappo-env1
    python examples/benchmarl_run.py --algorithm ippo --reward-scope team ...
    gathering-compare --environment 1 --steps 2000 --policy benchmarl-sample:runs/mappo-env1/policy.pt --policy wander
    gathering-replay benchmarl:runs/mappo-env1/policy.pt --environment 1 --steps 2000 --out mappo.gif

Budgets count environment steps (one step of one world; BenchMARL's frames); ``--max-minutes``
(or a file ``STOP`` created in ``--out``) stops earlier and exports the policy as it is. Writes into
``--out``: ``policy.pt`` (the actor, for ``benchmarl:PATH`` / ``benchmarl-sample:PATH``),
``curve.csv`` / ``curve.png`` (ft of every finished training episode vs environment steps),
``run.json`` (settings, environment steps trained, minutes, environment steps/s, ft on
``--eval-episodes`` held-out seeds
10 000 onwards with deterministic and sampled actions) and ``benchmarl/`` (BenchMARL's own
logs as CSV, and with ``--checkpoint-every`` its checkpoints; ``--resume CHECKPOINT``
continues a run from one).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import torch  # noqa: E402
from benchmarl.algorithms import IddpgConfig, IppoConfig, IsacConfig, MaddpgConfig, MappoConfig, MasacConfig  # noqa: E402
from benchmarl.experiment import Callback, Experiment, ExperimentConfig  # noqa: E402
from benchmarl.models.mlp import MlpConfig  # noqa: E402

from evolution.compare import compare  # noqa: E402
from evolution.guard import ArgumentParser, UsageError, check_output_dir, command, float_arg, int_arg  # noqa: E402
from evolution.policies.marl import GROUP, benchmarl_policy, save_policy  # noqa: E402
from gathering_env import Morphology  # noqa: E402
from gathering_env.config import ENVIRONMENT_PRESETS, REWARD_SCOPES, REWARDS, WorldConfig  # noqa: E402
from gathering_env.rl.benchmarl_task import GatheringTask, check_task_config  # noqa: E402

ALGORITHMS = {"ippo": IppoConfig, "mappo": MappoConfig, "iddpg": IddpgConfig, "maddpg": MaddpgConfig,
              "isac": IsacConfig, "masac": MasacConfig}
"""BenchMARL's algorithms for continuous actions (QMIX, VDN, IQL need discrete ones)."""
ON_POLICY = ("ippo", "mappo")
EVAL_SEED = 10_000
OUTPUTS = ("policy.pt", "curve.csv", "curve.png", "run.json")


class Stop(Exception):
    """Training stopped early: ``--max-minutes`` passed or a file ``STOP`` appeared in ``--out``."""


class EpisodeLog(Callback):
    """ft of every training episode that ends, with the environment steps and minutes so far;
    stops training (``Stop``) after ``max_minutes`` or when ``stop_file`` exists."""

    def __init__(self, max_minutes: float | None = None, stop_file: Path | None = None) -> None:
        super().__init__()
        self.rows: list[dict] = []
        self.env_steps = 0
        self.start = time.perf_counter()
        self.max_minutes, self.stop_file = max_minutes, stop_file

    def on_train_end(self, training_td, group: str) -> None:
        minutes = (time.perf_counter() - self.start) / 60
        if (self.max_minutes is not None and minutes >= self.max_minutes) or \
                (self.stop_file is not None and self.stop_file.exists()):
            raise Stop(f"stopped after {self.env_steps} environment steps, {minutes:.1f} minutes")

    def on_batch_collected(self, batch) -> None:
        done = batch.get(("next", "done")).squeeze(-1)          # (worlds, steps)
        ft = batch.get(("next", "task_performance"), None)
        if ft is None:                                             # route "wrapper": the infos
            ft = batch.get(("next", GROUP, "info", "task_performance"))[..., 0]
        steps_before = self.env_steps
        self.env_steps += batch.numel()
        minutes = round((time.perf_counter() - self.start) / 60, 3)
        for t, w in torch.nonzero(done.T).tolist():            # in time order
            self.rows.append({"env_steps": steps_before + (t + 1) * done.shape[0], "minutes": minutes,
                              "ft": float(ft[w, t])})


def plot_curve(rows: list[dict], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 3.6), constrained_layout=True)
    if rows:
        steps, ft = np.array([r["env_steps"] for r in rows]), np.array([r["ft"] for r in rows])
        window = max(1, len(rows) // 20)
        ax.plot(steps, ft, ".", color="tab:blue", alpha=0.3, markersize=3)
        ax.plot(steps[window - 1:], np.convolve(ft, np.ones(window) / window, mode="valid"), color="tab:blue",
                label=f"ft (mean of {window} episodes)")
        ax.legend(fontsize=8)
    ax.set_xlabel("environment steps")
    ax.set_ylabel("ft per training episode")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = ArgumentParser(prog="benchmarl_run.py", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    count = int_arg(1, float("inf"))
    p.add_argument("--algorithm", choices=sorted(ALGORITHMS), default="mappo")
    p.add_argument("--environment", type=int, default=1, choices=tuple(ENVIRONMENT_PRESETS))
    p.add_argument("--steps", type=count, default=2000, help="episode length (max_cycles) while training")
    p.add_argument("--robots", type=count, default=20)
    p.add_argument("--worlds", type=count, default=4, help="worlds stepped together (BenchMARL's envs per worker)")
    p.add_argument("--reward", choices=REWARDS, default="shaped")
    p.add_argument("--attach-reward", type=float, default=WorldConfig.attach_reward)
    p.add_argument("--reward-scope", choices=REWARD_SCOPES, default="local")
    p.add_argument("--reward-scale", type=float_arg(0.0, open_low=True), default=10.0,
                   help="rewards are multiplied by this (default 10: about 1 / std of the discounted local return, "
                        "what SB3's VecNormalize divides by in rl_ppo.py)")
    p.add_argument("--env-steps", type=count, default=480_000, help="training budget in environment steps")
    p.add_argument("--frames-per-batch", type=count, default=1024,
                   help="environment steps collected per iteration (default 1024 = 4 worlds x 256 steps)")
    p.add_argument("--epochs", type=count, default=10, help="on-policy: passes over each batch")
    p.add_argument("--minibatch", type=count, default=128, help="on-policy: environment steps per minibatch")
    p.add_argument("--lr", type=float_arg(0.0, open_low=True), default=1e-3)
    p.add_argument("--entropy", type=float_arg(0.0), default=0.003,
                   help="on-policy: entropy bonus (default 0.003; 0.01, PPO's, made IPPO's noise grow without bound "
                        "and 0.001 let MAPPO's collapse: docs/rl/README.md)")
    p.add_argument("--gamma", type=float_arg(0.0, 1.0, open_low=True), default=0.99)
    p.add_argument("--lmbda", type=float_arg(0.0, 1.0), default=0.95, help="on-policy: GAE lambda")
    p.add_argument("--hidden", type=count, nargs="+", default=[64, 64], help="MLP layer sizes (actor and critic)")
    p.add_argument("--normalize-advantage", action=argparse.BooleanOptionalAction, default=True,
                   help="on-policy: standardise the advantages of each minibatch (TorchRL's ClipPPOLoss option; "
                        "SB3's PPO default; BenchMARL turns it off; default on)")
    p.add_argument("--tanh-normal", action=argparse.BooleanOptionalAction, default=False,
                   help="on-policy: BenchMARL's default TanhNormal actions (squashed into [-1, 1]) instead of a "
                        "Gaussian whose samples the env clips, as SB3's PPO (default: Gaussian; docs/rl/README.md)")
    p.add_argument("--seed", type=int_arg(0, 2**31 - 1), default=0)
    p.add_argument("--eval-episodes", type=int_arg(0, 10_000), default=5)
    p.add_argument("--max-minutes", type=float_arg(0.0, open_low=True), default=None,
                   help="stop training after this many minutes (also: create a file STOP in --out) and export "
                        "the policy as it is")
    p.add_argument("--checkpoint-every", type=int_arg(0, float("inf")), default=0,
                   help="save a BenchMARL checkpoint every this many environment steps (0: never)")
    p.add_argument("--resume", type=Path, help="continue from a BenchMARL checkpoint (benchmarl/.../checkpoint_*.pt)")
    p.add_argument("--out", type=Path, default=Path("runs/benchmarl"))
    args = p.parse_args(argv)
    for name in ("env_steps", "checkpoint_every"):
        value = getattr(args, name)
        if value % args.frames_per_batch:
            p.error(f"--{name.replace('_', '-')} {value}: not a multiple of --frames-per-batch {args.frames_per_batch}")
    if args.frames_per_batch % args.worlds:
        p.error(f"--frames-per-batch {args.frames_per_batch}: not a multiple of --worlds {args.worlds}")
    if args.resume is not None and not args.resume.is_file():
        p.error(f"--resume {args.resume}: checkpoint not found; allowed: a checkpoint_*.pt under {args.out}/benchmarl")
    return args


def build_experiment(args: argparse.Namespace, callbacks=(), route: str = "batched") -> Experiment:
    """BenchMARL's experiment for the flags (its own task, algorithm, model and experiment configs);
    ``route``: the task's env, ``batched`` (GatheringTorchEnv) or ``wrapper`` (TorchRL's PettingZooWrapper)."""
    task = getattr(GatheringTask, f"ENV{args.environment}").get_from_yaml()
    task.config.update(num_robots=args.robots, max_cycles=args.steps, reward=args.reward,
                       attach_reward=args.attach_reward, reward_scope=args.reward_scope,
                       reward_scale=args.reward_scale, route=route)
    check_task_config(task.config)
    algorithm = ALGORITHMS[args.algorithm].get_from_yaml()
    if args.algorithm in ON_POLICY:
        algorithm.entropy_coef, algorithm.lmbda = args.entropy, args.lmbda
        algorithm.use_tanh_normal = args.tanh_normal
    model = MlpConfig(num_cells=list(args.hidden), activation_class=torch.nn.Tanh, layer_class=torch.nn.Linear)
    cfg = ExperimentConfig.get_from_yaml()
    cfg.loggers, cfg.render, cfg.evaluation, cfg.create_json = ["csv"], False, False, True
    cfg.sampling_device = cfg.train_device = cfg.buffer_device = "cpu"
    cfg.gamma, cfg.lr, cfg.clip_grad_val = args.gamma, args.lr, 0.5
    cfg.max_n_frames = args.env_steps
    cfg.on_policy_collected_frames_per_batch = cfg.off_policy_collected_frames_per_batch = args.frames_per_batch
    cfg.on_policy_n_envs_per_worker = cfg.off_policy_n_envs_per_worker = args.worlds
    cfg.on_policy_n_minibatch_iters, cfg.on_policy_minibatch_size = args.epochs, args.minibatch
    cfg.save_folder = str(args.out / "benchmarl")
    cfg.checkpoint_interval, cfg.checkpoint_at_end = args.checkpoint_every, args.checkpoint_every > 0
    cfg.restore_file = None if args.resume is None else str(args.resume)
    experiment = Experiment(task=task, algorithm_config=algorithm, model_config=model, critic_model_config=model,
                            seed=args.seed, config=cfg, callbacks=list(callbacks))
    if args.algorithm in ON_POLICY:
        for loss in experiment.losses.values():
            loss.normalize_advantage = args.normalize_advantage
    return experiment


def evaluate(path: Path, args: argparse.Namespace) -> dict:
    seeds = list(range(EVAL_SEED, EVAL_SEED + args.eval_episodes))
    env = {"environment": args.environment, "max_cycles": args.steps, "num_robots": args.robots}
    rows = compare([benchmarl_policy(str(path)), benchmarl_policy(str(path), sample=True)], env, seeds)
    return {"seeds": [seeds[0], seeds[-1]], "deterministic": {k: rows[0][k] for k in ("ft_mean", "ft_std")},
            "sampled": {k: rows[1][k] for k in ("ft_mean", "ft_std")}}


@command
def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    torch.set_num_threads(1)
    if (args.out / "benchmarl").exists() and args.resume is None:
        raise UsageError(f"--out {args.out}: holds an earlier BenchMARL run (benchmarl/); allowed: a new folder, "
                         "or --resume CHECKPOINT to continue it")
    if not (args.out / "benchmarl").exists():
        check_output_dir(args.out, OUTPUTS)       # never overwrite anything but an earlier run's output
    (args.out / "benchmarl").mkdir(parents=True, exist_ok=True)   # every input checked: only now touch the disk
    (args.out / "STOP").unlink(missing_ok=True)
    log = EpisodeLog(args.max_minutes, args.out / "STOP")
    experiment = build_experiment(args, [log])
    start, stopped = time.perf_counter(), None
    try:
        experiment.run()
    except Stop as stop:
        stopped = str(stop)
        print(stopped)
    minutes = (time.perf_counter() - start) / 60
    morphology = Morphology.khepera_iii()
    policy_path = save_policy(args.out / "policy.pt", experiment.group_policies[GROUP], args.algorithm, morphology,
                              args.robots, experiment.task.config)
    with open(args.out / "curve.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=["env_steps", "minutes", "ft"])
        writer.writeheader()
        writer.writerows(log.rows)
    title = (f"{args.algorithm} (BenchMARL), environment {args.environment}, {args.reward} reward, "
             f"{args.reward_scope} credit")
    plot_curve(log.rows, args.out / "curve.png", title)
    run = {"algorithm": args.algorithm, "settings": {k: (str(v) if isinstance(v, Path) else v)
                                                      for k, v in vars(args).items()},
           "env_steps": log.env_steps, "stopped_early": stopped, "minutes": round(minutes, 2),
           "env_steps_per_s": round(log.env_steps / max(minutes * 60, 1e-9), 1),
           "training_episodes": len(log.rows),
           "last_20_episodes_ft": float(np.mean([r["ft"] for r in log.rows[-20:]])) if log.rows else None}
    if args.eval_episodes:
        run["evaluation"] = evaluate(policy_path, args)
    (args.out / "run.json").write_text(json.dumps(run, indent=1))
    print(json.dumps({k: run[k] for k in ("env_steps", "minutes", "env_steps_per_s", "last_20_episodes_ft")}))
    print(f"wrote {policy_path}, {args.out / 'curve.csv'}, {args.out / 'curve.png'}, {args.out / 'run.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
