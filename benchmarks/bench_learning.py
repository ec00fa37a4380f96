"""Does evolution learn? S1 and M1 at a mid budget, then their champions against scripted teams
on the same held-out layouts.

    python benchmarks/bench_learning.py [--out runs/bench-learning] [--workers 2] [--resume]
        [--population 150] [--trials 2] [--steps 3000] [--generations 40] [--seed 7]
        [--heldout 20] [--heldout-steps 10000]

(``make bench-learning``.) Evolves the ``S1`` and ``M1`` presets (environment 1, HyperNEAT-M;
single- and multi-objective) at the stated budget (printed first) into ``OUT/S1`` and
``OUT/M1`` — resumable with ``--resume`` after a kill, like any run — and then runs, on the
same ``--heldout`` layouts (the held-out seeds of ``evolution.analysis.reevaluate``: no
training seed among them) at ``--heldout-steps`` steps:

* ``S1``: the single-objective champion (``champion.json``);
* ``M1-max``, ``M1-knee``, ``M1-epsilon``, ``M1-mean``: the genomes of M1's final front at
  the paper's four selection points (by training scores; for ``mean``, the front genome
  nearest the front's mean point after normalising both objectives);
* ``wander`` and ``random``: the scripted baselines (``evolution.policies.scripted``).

It prints the learning curves (best and mean ft, mean simplicity C, sensors per robot,
species and compatibility threshold per generation, every fifth generation) and the paired
comparison (held-out ft mean +- standard error, ratio and paired difference to ``wander``,
two-sided Wilcoxon signed-rank p, scipy), and writes ``OUT/learning.json``, ``OUT/learning.md``
and ``OUT/learning.png``. Nothing is timed here: the figures are what evolution reaches.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

from evolution.analysis.fronts import selection_points  # noqa: E402
from evolution.analysis.reevaluate import heldout_seeds  # noqa: E402
from evolution.compare import paired_difference, run_episode  # noqa: E402
from evolution.policies import make_policy  # noqa: E402
from evolution.run.champion import champion_objectives, read_json  # noqa: E402
from evolution.run.experiment import load_experiment  # noqa: E402
from evolution.run.presets import preset_path  # noqa: E402
from evolution.run.stats import read_stats  # noqa: E402
from evolution.run.trainer import Trainer  # noqa: E402
from gathering_env import parallel_env  # noqa: E402

EXPERIMENTS = ("S1", "M1")


def parse(argv: list[str] | None) -> argparse.Namespace:
    from evolution.guard import ArgumentParser, int_arg

    p = ArgumentParser(prog="bench_learning.py", description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, default=Path("runs/bench-learning"))
    p.add_argument("--workers", type=int_arg(1, 64), default=2)
    p.add_argument("--resume", action="store_true", help="continue the runs in OUT (after a kill)")
    p.add_argument("--population", type=int_arg(2, 10_000), default=150)
    p.add_argument("--trials", type=int_arg(1, 100), default=2)
    p.add_argument("--steps", type=int_arg(10, 100_000), default=3000)
    p.add_argument("--generations", type=int_arg(1, 10_000), default=40)
    p.add_argument("--seed", type=int_arg(0, 2**31), default=7)
    p.add_argument("--heldout", type=int_arg(2, 1000), default=20)
    p.add_argument("--heldout-steps", type=int_arg(10, 100_000), default=10_000)
    return p.parse_args(argv)


def evolve(name: str, args: argparse.Namespace) -> Path:
    run_dir = args.out / name
    exp = load_experiment(preset_path(name), {
        "name": name, "population": args.population, "trials": args.trials, "generations": args.generations,
        "seed": args.seed, "environment.max_cycles": args.steps, "convergence_stop": False,
    })
    resume = args.resume and (run_dir / "checkpoints").is_dir()
    Trainer(None if resume else exp, run_dir, workers=args.workers, resume=resume, progress=False).run()
    return run_dir


def front_points(run_dir: Path) -> dict[str, Path]:
    """The front file at each selection point (by training scores)."""
    files = sorted((run_dir / "front").glob("genome-*.json"))
    points = []
    for f in files:
        objectives = champion_objectives(f, read_json(f, "front file"))
        points.append((objectives["task"], objectives["morphology"]))
    front = np.array(points)
    chosen = {}
    span = np.where(np.ptp(front, axis=0) > 0, np.ptp(front, axis=0), 1.0)
    for point, value in selection_points(front).items():
        nearest = int(np.argmin(np.hypot(*((front - np.array(value)) / span).T)))
        chosen[point] = files[nearest]
    return chosen


def heldout_scores(policies: dict[str, str], args: argparse.Namespace, seeds: list[int]) -> dict[str, list[float]]:
    env = parallel_env(environment=1, max_cycles=args.heldout_steps)
    scores = {}
    for label, spec in policies.items():
        policy = make_policy(spec)
        scores[label] = [run_episode(env, policy, s)["ft"] for s in seeds]
        print(f"  {label:<11} {np.mean(scores[label]):7.2f}", flush=True)
    return scores


def paired(scores: dict[str, list[float]], baseline: str = "wander") -> list[dict]:
    base = np.array(scores[baseline])
    rows = []
    for label, values in scores.items():
        v = np.array(values)
        d = paired_difference(v, base)
        rows.append({"policy": label, "mean": float(v.mean()), "se": float(v.std(ddof=1) / np.sqrt(len(v))),
                     "ratio_to_wander": float(v.mean() / base.mean()) if base.mean() else float("nan"),
                     "diff_to_wander": d["diff"], "diff_se": d["diff_se"], "wilcoxon_p": d["wilcoxon_p"]})
    return rows


def curves(run_dir: Path) -> list[dict]:
    keys = ("generation", "task_best", "task_mean", "morphology_mean", "num_sensors_mean", "species", "threshold")
    return [{k: r.get(k) for k in keys} for r in read_stats(run_dir / "stats.jsonl")]


def print_curves(name: str, rows: list[dict]) -> None:
    print(f"\n{name}: gen  best ft  mean ft  mean C  sensors  species  threshold")
    for r in rows:
        if r["generation"] % 5 == 0 or r is rows[-1]:
            print(f"    {r['generation']:4d} {r['task_best']:8.2f} {r['task_mean']:8.2f} {r['morphology_mean']:7.1f} "
                  f"{r['num_sensors_mean']:8.2f} {r['species']:8d} {r['threshold'] or float('nan'):10.3f}")


def figure(data: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 4, figsize=(17, 3.8), constrained_layout=True)
    for name, colour in zip(EXPERIMENTS, ("tab:red", "tab:blue")):
        rows = data["curves"][name]
        gen = [r["generation"] for r in rows]
        axes[0].plot(gen, [r["task_best"] for r in rows], color=colour, label=f"{name} best")
        axes[0].plot(gen, [r["task_mean"] for r in rows], color=colour, ls="--", label=f"{name} mean")
        axes[1].plot(gen, [r["species"] for r in rows], color=colour, label=name)
        axes[2].plot(gen, [r["morphology_mean"] for r in rows], color=colour, label=f"{name} mean C")
        twin = axes[2] if name == "S1" else axes[2]
        twin.plot(gen, [10 * r["num_sensors_mean"] for r in rows], color=colour, ls=":",
                  label=f"{name} sensors x10")
    axes[0].set(xlabel="generation", ylabel="training ft (eq. 1)", title="learning curves")
    axes[1].set(xlabel="generation", ylabel="species", title="species per generation", ylim=(0, None))
    axes[2].set(xlabel="generation", ylabel="C (eq. 2); sensors x 10", title="simplicity and sensors", ylim=(0, 105))
    rows = data["paired"]
    names = [r["policy"] for r in rows]
    axes[3].bar(names, [r["mean"] for r in rows], yerr=[r["se"] for r in rows], capsize=3,
                color=["tab:red" if n == "S1" else "tab:blue" if n.startswith("M1") else "tab:gray" for n in names])
    axes[3].set(ylabel=f"held-out ft ({data['budget']['heldout']} layouts, {data['budget']['heldout_steps']} steps)",
                title="held-out, mean +- SE")
    axes[3].tick_params(axis="x", rotation=35)
    for ax in axes[:3]:
        ax.legend(fontsize=7)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def markdown(data: dict) -> str:
    b = data["budget"]
    lines = [f"Budget: {b['population']} genomes x {b['trials']} trials x {b['steps']} steps x {b['generations']} "
             f"generations per experiment (seed {b['seed']}); held-out: {b['heldout']} layouts x "
             f"{b['heldout_steps']} steps, environment 1.", "",
             "| policy | held-out ft (mean +- SE) | / wander | paired difference to wander | Wilcoxon p |",
             "|---|---|---|---|---|"]
    for r in data["paired"]:
        p = "" if r["policy"] == "wander" else f"{r['wilcoxon_p']:.3g}"
        lines.append(f"| {r['policy']} | {r['mean']:.1f} +- {r['se']:.1f} | {r['ratio_to_wander']:.2f} | "
                     f"{r['diff_to_wander']:+.1f} +- {r['diff_se']:.1f} | {p} |")
    return "\n".join(lines) + "\n"


def _main(argv: list[str] | None = None) -> int:
    from evolution.guard import UsageError

    args = parse(argv)
    if args.out.exists() and not args.out.is_dir():
        raise UsageError(f"{args.out}: is a file; allowed: a folder for the two runs and the results")
    if not args.resume and args.out.exists() and any(args.out.iterdir()):
        raise UsageError(f"{args.out}: not empty; allowed: a new folder, or --resume to continue its runs")
    budget = {k: getattr(args, k) for k in ("population", "trials", "steps", "generations", "seed", "heldout",
                                            "heldout_steps", "workers")}
    print("budget per experiment: " + ", ".join(f"{k} {v}" for k, v in budget.items()), flush=True)
    runs = {name: evolve(name, args) for name in EXPERIMENTS}
    exp = load_experiment(preset_path("S1"), {"trials": args.trials, "generations": args.generations,
                                              "seed": args.seed})
    seeds = heldout_seeds(args.seed, args.generations, args.trials, args.heldout)
    policies = {"S1": f"champion:{runs['S1'] / 'champion.json'}"}
    for point, path in front_points(runs["M1"]).items():
        policies[f"M1-{point}"] = f"champion:{path}"
    policies.update({"wander": "wander", "random": "random"})
    print(f"\nheld-out ft on {len(seeds)} layouts of environment {exp.environment['environment']}:", flush=True)
    scores = heldout_scores(policies, args, seeds)
    relative = {k: v.replace(f"{args.out}{os.sep}", "") for k, v in policies.items()}  # no machine's paths
    data = {"budget": budget, "seeds": seeds, "policies": relative,
            "curves": {name: curves(path) for name, path in runs.items()}, "scores": scores,
            "paired": paired(scores)}
    for name in EXPERIMENTS:
        print_curves(name, data["curves"][name])
    print()
    print(markdown(data))
    (args.out / "learning.json").write_text(json.dumps(data, indent=1) + "\n")
    (args.out / "learning.md").write_text(markdown(data))
    figure(data, args.out / "learning.png")
    print(f"wrote {args.out / 'learning.json'}, learning.md, learning.png")
    return 0


def main(argv: list[str] | None = None) -> int:
    """One line and exit status 2 for bad input (the commands' guard), also from the runs (a
    second copy on the same folder meets the run lock)."""
    from evolution.guard import command

    return command(_main)(argv)


if __name__ == "__main__":
    sys.exit(main())
