"""The IPPO / MAPPO figures of docs/rl/README.md: held-out seeds paired against wander, PPO and the champion.

    python examples/marl_figures.py --runs out/marl --out docs/rl     # references from docs/rl/marl-rows.json
    python examples/marl_figures.py --runs out/marl --rows out/rl-figures/rows.json --out docs/rl   # new references

``--runs`` holds BenchMARL runs of ``examples/benchmarl_run.py`` (folders with ``policy.pt``,
``curve.csv``, ``run.json``). Every run's policy plays the paired comparison's 40 held-out seeds
of environment 1 (20 000..20 039, 2 000 steps; the seeds of ``paired-env1-2000.md``) with
deterministic and sampled actions; ``random``, ``wander``, the quick champion and the PPO run are
read from ``--rows`` (rl_figures.py's per-seed cache ``rows.json`` on the same seeds, or this
script's own ``marl-rows.json``, which keeps them), after replaying ``wander`` on a few seeds to
check the episodes are still the ones stored. Writes into ``--out``:

* ``paired-marl-env1-2000.md``: ft mean ± standard error per policy; paired differences (mean ±
  SE, Wilcoxon signed-rank p, two-sided) against wander, the champion and shaped PPO;
* ``curves-marl-env1.png``: ft of every training episode (smoothed) vs environment steps;
* ``budgets-marl.md``: environment steps, minutes and environment steps/s of every run;
* ``curve-<run>.csv``: each run's training curve; ``marl-rows.json``: the rows of the table (the
  BenchMARL policies' keyed by their file's content, and the reference rows).
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import shutil
import sys
from pathlib import Path

import numpy as np

from evolution.compare import run_episode
from evolution.guard import ArgumentParser, UsageError, command, int_arg
from evolution.policies import make_policy
from gathering_env import parallel_env

SEEDS = list(range(20_000, 20_040))
STEPS = 2000
REFERENCES = {"wander": "wander", "champion": "champion:quick", "PPO": "ppo-sample:ppo-shaped-local-env1"}
"""Reference policies of the paired table (names as in rows.json): shaped PPO with local credit,
training seed 0, sampled actions: the PPO run of docs/rl/README.md at the same budget."""


def stored_rows(path: Path) -> dict[str, list[float]]:
    """Per-seed ft of the policies rl_figures.py ran on SEEDS (by policy name)."""
    suffix = f"|env1|{STEPS}|seeds{SEEDS[0]}-{SEEDS[-1]}"
    return {row["policy"]: row["ft"] for key, row in json.loads(path.read_text()).items() if key.endswith(suffix)}


def evaluate(spec: str, cache: dict, cache_path: Path, used: set[str], seeds: list[int] = SEEDS) -> list[float]:
    """ft on every seed, all 40 worlds stepped together (``VectorSimulation``: each world's episode is
    the env's for its seed; deterministic actions give exactly gathering-compare's episodes, sampled
    ones draw their noise from one torch generator seeded with the first seed). The cache is keyed by
    the policy file's content; ``used`` collects the keys of this run."""
    import torch

    from evolution.policies.marl import read_policy_file, worlds_actor
    from gathering_env import Morphology
    from gathering_env.vector import VectorSimulation

    kind, _, path = spec.partition(":")
    digest = hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16]  # the policy file's content, not its place
    key = f"{kind}:{digest}|env1|{STEPS}|seeds{seeds[0]}-{seeds[-1]}"
    used.add(key)
    if key not in cache:
        data = read_policy_file(path)
        act = worlds_actor(data, sample=kind == "benchmarl-sample", path=path)
        sims = VectorSimulation(len(seeds), environment=1, max_cycles=STEPS, num_robots=20,
                                morphology=Morphology.coerce(data["morphology"]))
        obs = sims.reset(seeds)
        torch.manual_seed(seeds[0])
        while sims.active.any():
            obs, _, _, _ = sims.step(act(obs))
        cache[key] = {"policy": make_policy(spec).name, "ft": sims.task_performance().tolist()}
        cache_path.write_text(json.dumps(cache, indent=1))
    return cache[key]["ft"]


def paired_table(by_name: dict[str, np.ndarray], seeds: list[int] = SEEDS) -> str:
    from scipy.stats import wilcoxon

    def versus(ft: np.ndarray, ref: np.ndarray) -> str:
        d = ft - ref
        if not d.any():
            return "— | —"
        return f"{d.mean():+.2f} ± {d.std(ddof=1) / np.sqrt(len(d)):.2f} | {wilcoxon(ft, ref).pvalue:.2g}"

    refs = {label: name for label, name in REFERENCES.items() if name in by_name}
    lines = [f"environment 1, 20 robots, {STEPS:,}-step episodes, {len(seeds)} held-out seeds ({seeds[0]}..{seeds[-1]}), "
             "every policy on the same seeds; ± is the standard error; p: Wilcoxon signed-rank test of the per-seed "
             f"differences (two-sided); PPO = {REFERENCES['PPO']}", "",
             "| policy | ft | " + " | ".join(f"vs {label}: difference | p" for label in refs) + " |",
             "|---|---|" + "---|---|" * len(refs)]
    for name, ft in by_name.items():
        cells = " | ".join(versus(ft, by_name[r]) if r != name else "— | —" for r in refs.values())
        lines.append(f"| {name} | {ft.mean():.2f} ± {ft.std(ddof=1) / np.sqrt(len(ft)):.2f} | {cells} |")
    return "\n".join(lines) + "\n"


def read_curve(path: Path) -> tuple[np.ndarray, np.ndarray]:
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return np.array([float(r["env_steps"]) for r in rows]), np.array([float(r["ft"]) for r in rows])


def plot_curves(curves: dict[str, tuple[np.ndarray, np.ndarray]], wander: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.0, 3.8), constrained_layout=True)
    for name, (steps, ft) in curves.items():
        window = max(1, len(ft) // 25)
        line, = ax.plot(steps[window - 1:], np.convolve(ft, np.ones(window) / window, mode="valid"), label=name)
        ax.plot(steps, ft, ".", color=line.get_color(), alpha=0.15, markersize=2)
    ax.axhline(wander, color="grey", linestyle="--", linewidth=1, label=f"wander on the held-out seeds ({wander:.1f})")
    ax.set_xlabel("environment steps")
    ax.set_ylabel("ft per training episode (smoothed)")
    ax.set_title("BenchMARL in environment 1 (2 000-step episodes, shaped reward, local credit)", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def confirm(args: argparse.Namespace) -> None:
    """``--confirm FIRST_SEED``: every run of ``--runs`` and the references (``--reference
    NAME=POLICY``: evaluated here, episode by episode as gathering-compare) on 40 seeds from
    FIRST_SEED that no setting was chosen on; writes ``paired-marl-env1-2000-seeds<FIRST>.md`` and
    its rows (``marl-confirm-rows.json``) into ``--out``."""
    seeds = list(range(args.confirm, args.confirm + len(SEEDS)))
    references = []
    for ref in ["random", "wander", *args.reference]:  # every policy checked before any work
        name, _, spec = ref.partition("=") if "=" in ref else (ref, "", ref)
        try:
            references.append((name, make_policy(spec)))
        except ValueError as err:
            raise UsageError(f"--reference {ref}: {err}") from None
    args.out.mkdir(parents=True, exist_ok=True)
    env = parallel_env(environment=1, max_cycles=STEPS, num_robots=20)
    cache_path = args.out / "marl-confirm-rows.json"
    cache = json.loads(cache_path.read_text()) if cache_path.exists() else {}
    used: set[str] = set()
    by_name = {}
    for name, policy in references:
        key = f"reference:{name}|env1|{STEPS}|seeds{seeds[0]}-{seeds[-1]}"
        if key not in cache:
            cache[key] = {"policy": name, "ft": [run_episode(env, policy, s)["ft"] for s in seeds]}
            cache_path.write_text(json.dumps(cache, indent=1))
        used.add(key)
        by_name[name] = np.array(cache[key]["ft"])
    for run in sorted(p for p in args.runs.iterdir() if (p / "policy.pt").exists()):
        for kind in ("benchmarl-sample", "benchmarl"):
            by_name[f"{kind}:{run.name}"] = np.array(evaluate(f"{kind}:{run / 'policy.pt'}", cache, cache_path,
                                                              used, seeds))
    cache_path.write_text(json.dumps({k: v for k, v in cache.items() if k in used}, indent=1))
    out = args.out / f"paired-marl-env1-{STEPS}-seeds{seeds[0]}.md"
    out.write_text(paired_table(by_name, seeds))
    print(out.read_text())


@command
def main(argv: list[str] | None = None) -> int:
    parser = ArgumentParser(prog="marl_figures.py", description=__doc__,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=Path, default=Path("out/marl"))
    parser.add_argument("--rows", type=Path, default=Path("docs/rl/marl-rows.json"),
                        help="per-seed rows of wander, random, the champion and PPO: rl_figures.py's cache (rows.json) "
                             "or this script's own marl-rows.json, which keeps the rows it used")
    parser.add_argument("--out", type=Path, default=Path("docs/rl"))
    parser.add_argument("--confirm", type=int_arg(0, 2**31 - 1 - len(SEEDS)), default=None, metavar="FIRST_SEED",
                        help="instead: a confirmation on 40 fresh seeds from FIRST_SEED (see confirm())")
    parser.add_argument("--reference", action="append", default=[], metavar="NAME=POLICY",
                        help="with --confirm: a reference policy (e.g. champion=champion:out/quick/champion.json, "
                             "PPO=ppo-sample:out/rl/ppo-shaped-local-env1/model.zip); random and wander always")
    args = parser.parse_args(argv)
    if not args.runs.is_dir():
        raise UsageError(f"--runs {args.runs}: not a folder; allowed: a folder of examples/benchmarl_run.py runs")
    if args.confirm is not None:
        confirm(args)
        return 0
    if not args.rows.is_file():
        raise UsageError(f"--rows {args.rows}: missing; allowed: rl_figures.py's rows.json or a marl-rows.json")
    stored = stored_rows(args.rows)
    args.out.mkdir(parents=True, exist_ok=True)
    env = parallel_env(environment=1, max_cycles=STEPS, num_robots=20)
    wander = make_policy("wander")
    replayed = [run_episode(env, wander, s)["ft"] for s in SEEDS[:3]]
    if replayed != stored["wander"][:3]:
        raise SystemExit(f"wander's episodes changed ({replayed} vs stored {stored['wander'][:3]}): rerun rl_figures.py")
    cache_path = args.out / "marl-rows.json"
    cache = json.loads(cache_path.read_text()) if cache_path.exists() else {}
    by_name = {name: np.array(stored[name]) for name in ("random", *REFERENCES.values()) if name in stored}
    curves, budgets, used = {}, [], set()
    runs = sorted(p for p in args.runs.iterdir() if (p / "policy.pt").exists())
    for run in runs:
        for kind in ("benchmarl-sample", "benchmarl"):
            ft = evaluate(f"{kind}:{run / 'policy.pt'}", cache, cache_path, used)
            by_name[f"{kind}:{run.name}"] = np.array(ft)
        alone = [run_episode(env, make_policy(f"benchmarl:{run / 'policy.pt'}"), s)["ft"] for s in SEEDS[:2]]
        if alone != ft[:2]:                   # the batched evaluation must be gathering-compare's episodes
            raise SystemExit(f"{run}: batched ft {ft[:2]} != episode by episode {alone}")
        curves[run.name] = read_curve(run / "curve.csv")
        shutil.copy(run / "curve.csv", args.out / f"curve-{run.name}.csv")
        info = json.loads((run / "run.json").read_text())
        budgets.append(f"| {run.name} | {info['algorithm']} | {info['env_steps']:,} | {info['minutes']:.1f} | "
                       f"{info['env_steps_per_s']:.0f} |")
    for extra in sorted(args.runs.glob("*-partial/curve.csv")):      # runs stopped early: curve only
        curves[extra.parent.name] = read_curve(extra)
        shutil.copy(extra, args.out / f"curve-{extra.parent.name}.csv")
    # this table's rows only: the BenchMARL policies' and the reference rows read from --rows, so the
    # file alone regenerates the table (--rows docs/rl/marl-rows.json, the default)
    kept = {k: v for k, v in cache.items() if k in used}
    for name in ("random", *REFERENCES.values()):
        if name in stored:
            kept[f"reference:{name}|env1|{STEPS}|seeds{SEEDS[0]}-{SEEDS[-1]}"] = {"policy": name, "ft": stored[name]}
    cache_path.write_text(json.dumps(kept, indent=1))
    (args.out / "paired-marl-env1-2000.md").write_text(paired_table(by_name))
    (args.out / "budgets-marl.md").write_text(
        "| run | algorithm | env steps | minutes (this machine) | env steps/s |\n|---|---|---|---|---|\n"
        + "\n".join(budgets) + "\n")
    plot_curves(curves, float(np.mean(stored["wander"])), args.out / "curves-marl-env1.png")
    print((args.out / "paired-marl-env1-2000.md").read_text())
    print((args.out / "budgets-marl.md").read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
