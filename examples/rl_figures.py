"""The figures of docs/rl/README.md: every policy on the same held-out seeds, and learning curves.

    python examples/rl_figures.py --runs out/rl --champion out/quick --out out/rl-figures

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
import math
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import numpy as np  # noqa: E402

from evolution.compare import compare, run_episode, write_outputs  # noqa: E402
from evolution.guard import ArgumentParser, UsageError, check_output_dir, command, int_arg, writing  # noqa: E402
from evolution.policies import make_policy  # noqa: E402
from evolution.run.champion import load_champion  # noqa: E402
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
    path = run / "curve.csv"
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        steps = np.array([int(r["env_steps"]) for r in rows])
        ft = np.array([float(r["ft"]) for r in rows])
    except FileNotFoundError:
        raise UsageError(f"{path}: missing; allowed: a run written by examples/rl_ppo.py") from None
    except (KeyError, TypeError, ValueError, UnicodeDecodeError, csv.Error):
        raise UsageError(f"{path}: not a curve.csv of examples/rl_ppo.py (columns env_steps, ft); allowed: "
                         "the run's own file") from None
    if not np.isfinite(ft).all():
        raise UsageError(f"{path}: ft holds a value that is not finite; allowed: finite numbers")
    return steps, ft


def read_json_file(path: Path, what: str) -> dict:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UsageError(f"{path}: missing; allowed: {what}") from None
    except (json.JSONDecodeError, UnicodeDecodeError, RecursionError):
        raise UsageError(f"{path}: not valid JSON; allowed: {what}") from None
    if not isinstance(doc, dict):
        raise UsageError(f"{path}: not a JSON object; allowed: {what}")
    return doc


def read_evaluation(run: Path) -> dict:
    path = run / "evaluation.json"
    report = read_json_file(path, "the evaluation.json examples/rl_ppo.py wrote")
    for key in ("train_steps", "env_steps", "robot_steps", "train_minutes"):
        value = report.get(key)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise UsageError(f"{path}: {key} = {value!r}; allowed: a finite number")
    return report


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
    with writing(path):
        fig.savefig(path, dpi=110)
    plt.close(fig)


def evolution_budget(run: Path) -> dict:
    """Budget and best training ft of the evolution run (its stats.csv, experiment.json, champion.json)."""
    if not run.is_dir():
        raise UsageError(f"--champion {run}: not a folder; allowed: a run directory written by gathering-evolve")
    load_champion(run / "champion.json")  # a readable champion (ValueError naming the file otherwise)
    path = run / "stats.csv"
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        budget = {"env_steps": sum(int(r["steps"]) for r in rows),
                  "minutes": sum(float(r["seconds"]) for r in rows) / 60,
                  "best_ft": max(float(r["task_best"]) for r in rows), "generations": len(rows)}
    except FileNotFoundError:
        raise UsageError(f"{path}: missing; allowed: a run directory written by gathering-evolve") from None
    except (KeyError, TypeError, ValueError, UnicodeDecodeError, csv.Error):
        raise UsageError(f"{path}: not a gathering-evolve stats.csv (columns steps, seconds, task_best, one row "
                         "per generation); allowed: the run's own file") from None
    env = read_json_file(run / "experiment.json", "the run's experiment.json").get("environment", {})
    if not isinstance(env, dict):
        raise UsageError(f"{run / 'experiment.json'}: environment is not an object; allowed: the run's own file")
    return {**budget, "environment": env.get("environment", 1), "max_cycles": env.get("max_cycles")}


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
    with writing(path):
        path.write_text("ft (mean ± std over the 5 held-out episodes, seeds 10 000..10 004)\n\n" + "\n".join(lines) + "\n")


def paired_episodes(spec: str, environment: int, steps: int, seeds: list[int], cache: dict, cache_path: Path
                    ) -> np.ndarray:
    key = cache_key(spec, f"env{environment}", steps, f"seeds{seeds[0]}-{seeds[-1]}")
    if key not in cache:
        env = parallel_env(environment=environment, max_cycles=steps, num_robots=20)
        policy = make_policy(spec)
        cache[key] = {"policy": policy.name, "ft": [run_episode(env, policy, s)["ft"] for s in seeds]}
        save_cache(cache, cache_path)
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
    with writing(path):
        path.write_text("\n".join(lines) + "\n")


def save_cache(cache: dict, path: Path) -> None:
    with writing(path):
        path.write_text(json.dumps(cache, indent=1))


def load_cache(path: Path) -> dict:
    """The rows computed before (``rows.json``); a file of that name that is not such a cache is refused."""
    if not path.exists():
        return {}
    what = "the rows.json this script wrote (delete it to recompute every row)"
    cache = read_json_file(path, what)
    for key, row in cache.items():
        if not isinstance(row, dict) or not isinstance(row.get("policy"), str):
            raise UsageError(f"{path}: entry {key!r} is not a policy's row; allowed: {what}")
        values = row.get("ft") if key.count("|") == 3 else [row.get("ft_mean"), row.get("ft_std")]
        if not isinstance(values, list) or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values):
            raise UsageError(f"{path}: entry {key!r} holds a score that is not a finite number; allowed: {what}")
    return cache


def parse_paired(items: list[str] | None) -> dict[int, int]:
    """``--paired-seeds STEPS=SEEDS ...`` -> {episode length: seed count}."""
    if items is None:
        return dict(PAIRED)
    paired = {}
    for item in items:
        steps, sep, count = item.partition("=")
        if not (sep and steps.isdigit() and count.isdigit() and int(steps) >= 1 and 2 <= int(count) <= 10_000):
            raise UsageError(f"--paired-seeds {item!r}: not STEPS=SEEDS; allowed: e.g. 2000=40 (steps >= 1, "
                             "2..10000 seeds)")
        paired[int(steps)] = int(count)
    return paired


def output_files(steps_list: list[int], paired: dict[int, int]) -> list[str]:
    """Every file this script writes into --out (the folder may hold these from an earlier run)."""
    names = ["rows.json", "summary.md", "budgets.md"] + [f"curves-env{e}.png" for e in (1, 2)]
    names += [f"compare-env{e}-{n}.{suffix}" for e in (1, 2) for n in steps_list for suffix in ("md", "csv", "png")]
    return names + [f"paired-env1-{n}.md" for n in paired]


@command
def main(argv: list[str] | None = None) -> int:
    parser = ArgumentParser(prog="rl_figures.py", description=__doc__,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=Path, default=Path("out/rl"))
    parser.add_argument("--champion", type=Path, default=Path("out/quick"))
    parser.add_argument("--out", type=Path, default=Path("out/rl-figures"),
                        help="a missing or empty folder, or one holding only this script's earlier output")
    parser.add_argument("--steps", type=int_arg(1, 10**6), nargs="+", default=[2000, 10_000])
    parser.add_argument("--only-baselines", action="store_true", help="fill the cache with the baselines' rows")
    parser.add_argument("--paired-seeds", nargs="+", default=None, metavar="STEPS=SEEDS",
                        help="episode length=seed count of the paired comparison in environment 1 "
                             f"(default {' '.join(f'{k}={v}' for k, v in PAIRED.items())})")
    args = parser.parse_args(argv)
    paired = parse_paired(args.paired_seeds)
    outputs = output_files(args.steps, paired)
    check_output_dir(args.out, outputs)   # never overwrite a file it did not write
    present = sorted(name for name in outputs if (args.out / name).exists())
    if present and "rows.json" not in present:  # an earlier run of this script always leaves rows.json
        raise UsageError(f"--out {args.out}: holds {', '.join(present[:3])} but no rows.json, so not an earlier "
                         "output of this script; allowed: a missing or empty folder, or this script's earlier "
                         "output")
    if not args.only_baselines and not args.runs.is_dir():
        raise UsageError(f"--runs {args.runs}: not a folder; allowed: the folder of examples/rl_ppo.py runs "
                         "(ppo-<reward>-<scope>-env<E>/), or --only-baselines")
    cache_path = args.out / "rows.json"
    cache = load_cache(cache_path)
    evolution = evolution_budget(args.champion)
    runs_of = {e: [] if args.only_baselines else ppo_runs(args.runs, e) for e in (1, 2)}
    reports = {run: read_evaluation(run) for runs in runs_of.values() for run in runs}
    for runs in runs_of.values():   # every input read before the first minute of work
        for run in runs:
            read_curve(run)
            make_policy(f"ppo:{run / 'model.zip'}")
    args.out.mkdir(parents=True, exist_ok=True)
    work = args.out / ".tmp"
    budgets = ["| policy | trained in | env steps | robot-steps | minutes (this machine) |", "|---|---|---|---|---|",
               f"| champion:{args.champion.name} (HyperNEAT-M, {evolution['generations']} generations) | env "
               f"{evolution['environment']}, {evolution['max_cycles']}-step trials | {evolution['env_steps']:,} | "
               f"{evolution['env_steps'] * 20:,} | {evolution['minutes']:.1f} |"]
    for environment in (1, 2):
        runs = runs_of[environment]
        for run in runs:
            report = reports[run]
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
                    save_cache(cache, cache_path)
                rows.append(cache[key])
            title = (f"environment {environment}, 20 robots, {steps} steps, 5 held-out episodes "
                     f"(seeds {SEEDS[0]}..{SEEDS[-1]})")
            md, csv_path, png = write_outputs(rows, work, title)
            for src, suffix in ((md, "md"), (csv_path, "csv"), (png, "png")):
                src.replace(args.out / f"compare-env{environment}-{steps}.{suffix}")
            print((args.out / f"compare-env{environment}-{steps}.md").read_text())
        if environment == 1:
            snapshots = [p for run in runs for p in sorted(run.glob("model-*.zip"))]
            specs_paired = ["random", "wander", f"champion:{args.champion / 'champion.json'}"]
            specs_paired += [f"{kind}:{model}" for model in [run / "model.zip" for run in runs] + snapshots
                             for kind in ("ppo-sample", "ppo")]
            for steps, count in paired.items():
                seeds = list(range(PAIRED_FIRST_SEED, PAIRED_FIRST_SEED + count))
                entries = [paired_episodes(spec, 1, steps, seeds, cache, cache_path) for spec in specs_paired]
                write_paired(entries, args.out / f"paired-env1-{steps}.md", 1, steps, seeds)
                print((args.out / f"paired-env1-{steps}.md").read_text())
    if work.is_dir():
        work.rmdir()
    write_summary(cache, args.out / "summary.md", args.steps)
    with writing(args.out / "budgets.md"):
        (args.out / "budgets.md").write_text("\n".join(budgets) + "\n")
    print("\n".join(budgets))
    return 0


if __name__ == "__main__":
    sys.exit(main())
