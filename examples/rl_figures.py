"""The figures of docs/rl/README.md: every policy on the same held-out seeds, and learning curves.

    python examples/rl_figures.py --runs out/rl --champion out/quick --out docs/rl

Reads the PPO runs ``RUNS/ppo-<reward>-<scope>-env<E>/`` written by examples/rl_ppo.py and
the quick evolution run (``CHAMPION/champion.json``, ``stats.csv``), runs
``gathering-compare``'s code on environments 1 and 2 with 2 000- and 10 000-step episodes
(seeds 10 000..10 004, used by no training run), and writes into ``OUT``:

* ``compare-env<E>-<steps>.md|csv|png``: ft per policy (random, heuristic, wander, the
  champion, the PPO runs of that environment);
* ``curves-env<E>.png``: ft of the training episodes vs environment steps of every PPO run,
  with the evolution run's budget and best training ft marked;
* ``paired-env1-<steps>.md``: environment 1 on more held-out seeds (``--paired-seeds``, default
  40 for 2 000 steps and 20 for 10 000, seeds 20 000 onwards), every policy on the same seeds, with the paired
  difference to ``wander`` and to the champion (mean ± standard error of the per-seed
  differences) and the Wilcoxon signed-rank p-value (scipy) — which differences are more than
  noise; PPO snapshots (``model-ENV_STEPS.zip``) are included, so PPO is also compared at the
  evolution run's budget;
* ``budgets.md``: training budget of each trained policy in environment steps and minutes;
* ``summary.md``: ft of every policy in every setting in one table;
* ``rows.json``: every policy's row, computed once per model file content (rerun after more
  runs finish; a retrained model is evaluated again).
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import os
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import numpy as np  # noqa: E402

from evolution.compare import compare, run_episode, write_outputs
from evolution.policies import make_policy  # noqa: E402
from gathering_env import parallel_env  # noqa: E402

SEEDS = list(range(10_000, 10_005))
PAIRED = {2000: 40, 10_000: 20}
"""Episode length -> number of held-out seeds of the paired comparison (PAIRED_FIRST_SEED on)."""
PAIRED_FIRST_SEED = 20_000
"""The paired comparison's seeds start here: apart from 10 000.., on which PPO's settings were
chosen (docs/rl/README.md), so the final figures carry no selection effect."""


def cache_key(spec: str, *parts: object) -> str:
    """A policy's cache key: its spec plus, for a trained policy (PPO model, champion), a digest
    of its file, so a retrained model at the same path is evaluated again."""
    kind, _, path = spec.partition(":")
    digest = hashlib.sha1(Path(path).read_bytes()).hexdigest()[:10] if path else ""
    return "|".join([spec + (f"#{digest}" if digest else ""), *map(str, parts)])


def ppo_runs(runs: Path, environment: int) -> list[Path]:
    return sorted(p for p in runs.glob(f"ppo-*-env{environment}") if (p / "model.zip").exists())


def read_curve(run: Path) -> tuple[np.ndarray, np.ndarray]:
    rows = list(csv.DictReader(open(run / "curve.csv")))
    return np.array([int(r["env_steps"]) for r in rows]), np.array([float(r["ft"]) for r in rows])


def plot_curves(runs: list[Path], evolution: dict, path: Path, environment: int) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10.0, 4.0), constrained_layout=True)
    for run in runs:
        steps, ft = read_curve(run)
        if len(ft) == 0:
            continue
        window = max(1, min(20, len(ft) // 10))
        ax.plot(steps[window - 1:], np.convolve(ft, np.ones(window) / window, mode="valid"),
                label=f"{run.name} (mean of {window} episodes)")
    if evolution and evolution["environment"] == environment:
        ax.axvline(evolution["env_steps"], color="grey", ls="--", lw=1)
        ax.plot([evolution["env_steps"]], [evolution["best_ft"]], "k*", markersize=10,
                label=f"quick evolution: best training ft ({evolution['max_cycles']}-step trials) at {evolution['env_steps']:,} env steps")
    ax.set_xlabel("environment steps (one step of one 20-robot world)")
    ax.set_ylabel("ft of training episodes (2 000 steps)")
    ax.set_title(f"PPO learning curves, environment {environment}", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def evolution_budget(run: Path) -> dict:
    rows = list(csv.DictReader(open(run / "stats.csv")))
    config = json.loads((run / "experiment.json").read_text())
    env = config.get("environment", {})
    return {"env_steps": sum(int(r["steps"]) for r in rows), "minutes": sum(float(r["seconds"]) for r in rows) / 60,
            "best_ft": max(float(r["task_best"]) for r in rows), "generations": len(rows),
            "environment": env.get("environment", 1), "max_cycles": env.get("max_cycles")}


def write_summary(cache: dict, path: Path, steps_list: list[int]) -> None:
    """One row per policy, one column per (environment, episode length): ft mean ± std."""
    columns = [(e, n) for e in (1, 2) for n in steps_list]
    names: dict[str, dict] = {}
    for key, row in cache.items():
        if key.count("|") != 2:
            continue                      # the paired comparison's per-episode lists
        spec, env, steps = key.split("|")
        names.setdefault(row["policy"], {})[(int(env[3:]), int(steps))] = row
    header = "| policy | " + " | ".join(f"env {e}, {n:,} steps" for e, n in columns) + " |"
    lines = [header, "|---" * (len(columns) + 1) + "|"]
    for name, cells in names.items():
        lines.append(f"| {name} | " + " | ".join(
            f"{cells[c]['ft_mean']:.1f} ± {cells[c]['ft_std']:.1f}" if c in cells else "—" for c in columns) + " |")
    path.write_text("ft (mean ± std over the 5 held-out episodes, seeds 10 000..10 004)\n\n" + "\n".join(lines) + "\n")


def paired_episodes(spec: str, environment: int, steps: int, seeds: list[int], cache: dict, cache_path: Path
                    ) -> np.ndarray:
    key = cache_key(spec, f"env{environment}", steps, f"seeds{seeds[0]}-{seeds[-1]}")
    if key not in cache:
        env = parallel_env(environment=environment, max_cycles=steps, num_robots=20)
        policy = make_policy(spec)
        cache[key] = {"policy": policy.name, "ft": [run_episode(env, policy, s)["ft"] for s in seeds]}
        cache_path.write_text(json.dumps(cache, indent=1))
    return cache[key]


def write_paired(entries: list[dict], path: Path, environment: int, steps: int, seeds: list[int]) -> None:
    """Mean ± standard error per policy; paired differences to wander and the champion with the
    Wilcoxon signed-rank p-value (two-sided; '—' when every difference is 0)."""
    from scipy.stats import wilcoxon

    by_name = {e["policy"]: np.array(e["ft"]) for e in entries}
    refs = [name for name in by_name if name == "wander" or name.startswith("champion:")]

    def versus(ft: np.ndarray, ref: np.ndarray) -> str:
        d = ft - ref
        if not d.any():
            return "— | —"
        return f"{d.mean():+.2f} ± {d.std(ddof=1) / np.sqrt(len(d)):.2f} | {wilcoxon(ft, ref).pvalue:.2g}"

    lines = [f"environment {environment}, 20 robots, {steps:,}-step episodes, {len(seeds)} held-out seeds "
             f"({seeds[0]}..{seeds[-1]}), every policy on the same seeds; ± is the standard error; p: "
             "Wilcoxon signed-rank test of the per-seed differences (two-sided)", "",
             "| policy | ft | " + " | ".join(f"vs {r}: difference | p" for r in refs) + " |",
             "|---|---|" + "---|---|" * len(refs)]
    for name, ft in by_name.items():
        cells = " | ".join(versus(ft, by_name[r]) if r != name else "— | —" for r in refs)
        lines.append(f"| {name} | {ft.mean():.2f} ± {ft.std(ddof=1) / np.sqrt(len(ft)):.2f} | {cells} |")
    path.write_text("\n".join(lines) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=Path, default=Path("out/rl"))
    parser.add_argument("--champion", type=Path, default=Path("out/quick"))
    parser.add_argument("--out", type=Path, default=Path("docs/rl"))
    parser.add_argument("--steps", type=int, nargs="+", default=[2000, 10_000])
    parser.add_argument("--only-baselines", action="store_true", help="fill the cache with the baselines' rows")
    parser.add_argument("--paired-seeds", nargs="+", default=None, metavar="STEPS=SEEDS",
                        help="episode length=seed count of the paired comparison in environment 1 "
                             f"(default {' '.join(f'{k}={v}' for k, v in PAIRED.items())})")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    cache_path = args.out / "rows.json"
    cache = json.loads(cache_path.read_text()) if cache_path.exists() else {}
    evolution = evolution_budget(args.champion)
    budgets = ["| policy | trained in | env steps | robot-steps | minutes (this machine) |", "|---|---|---|---|---|",
               f"| champion:{args.champion.name} (HyperNEAT-M, {evolution['generations']} generations) | env "
               f"{evolution['environment']}, {evolution['max_cycles']}-step trials | {evolution['env_steps']:,} | "
               f"{evolution['env_steps'] * 20:,} | {evolution['minutes']:.1f} |"]
    for environment in (1, 2):
        runs = [] if args.only_baselines else ppo_runs(args.runs, environment)
        for run in runs:
            report = json.loads((run / "evaluation.json").read_text())
            budgets.append(f"| ppo:{run.name} | env {environment}, {report['train_steps']}-step episodes | "
                           f"{report['env_steps']:,} | {report['robot_steps']:,} | {report['train_minutes']:.1f} |")
        plot_curves(runs, evolution, args.out / f"curves-env{environment}.png", environment)
        specs = ["random", "heuristic", "wander", f"champion:{args.champion / 'champion.json'}"]
        specs += [f"{kind}:{run / 'model.zip'}" for run in runs for kind in ("ppo", "ppo-sample")]
        for steps in args.steps:
            rows = []
            for spec in specs:
                key = cache_key(spec, f"env{environment}", steps)
                if key not in cache:    # a policy's row is computed once; delete rows.json to redo
                    config = {"environment": environment, "max_cycles": steps, "num_robots": 20}
                    cache[key] = compare([make_policy(spec)], config, SEEDS)[0]
                    cache_path.write_text(json.dumps(cache, indent=1))
                rows.append(cache[key])
            title = (f"environment {environment}, 20 robots, {steps} steps, 5 held-out episodes "
                     f"(seeds {SEEDS[0]}..{SEEDS[-1]})")
            md, csv_path, png = write_outputs(rows, args.out / "tmp", title)
            for src, suffix in ((md, "md"), (csv_path, "csv"), (png, "png")):
                src.replace(args.out / f"compare-env{environment}-{steps}.{suffix}")
            print((args.out / f"compare-env{environment}-{steps}.md").read_text())
        if environment == 1:
            paired = dict(PAIRED) if args.paired_seeds is None else dict(map(int, x.split("=")) for x in args.paired_seeds)
            snapshots = [p for run in runs for p in sorted(run.glob("model-*.zip"))]
            specs_paired = ["random", "wander", f"champion:{args.champion / 'champion.json'}"]
            specs_paired += [f"{kind}:{model}" for model in [run / "model.zip" for run in runs] + snapshots
                             for kind in ("ppo-sample", "ppo")]
            for steps, count in paired.items():
                seeds = list(range(PAIRED_FIRST_SEED, PAIRED_FIRST_SEED + count))
                entries = [paired_episodes(spec, 1, steps, seeds, cache, cache_path) for spec in specs_paired]
                write_paired(entries, args.out / f"paired-env1-{steps}.md", 1, steps, seeds)
                print((args.out / f"paired-env1-{steps}.md").read_text())
    (args.out / "tmp").rmdir()
    write_summary(cache, args.out / "summary.md", args.steps)
    (args.out / "budgets.md").write_text("\n".join(budgets) + "\n")
    print("\n".join(budgets))


if __name__ == "__main__":
    main()
