"""Compare team policies on the same seeds: random, a fixed search pattern, a privileged oracle, evolved champions, PPO.

``gathering-compare --policy random --policy heuristic --policy wander --policy champion:run/champion.json
--policy ppo:ppo/model.zip --environment 2 --episodes 5 --out compare/`` runs every policy on
the same environment and episode seeds and writes ``compare.md`` / ``compare.csv`` (mean ± standard error of
ft, blocks gathered by type, time to finish), ``compare-episodes.csv`` (one row per policy and seed) and
``compare.png`` (a bar plot). Since every policy meets the same seeds, ``compare.md`` also pairs
each policy with the first one named: the mean per-seed difference of ft ± its standard error,
how many seeds it scored higher, equal and lower, and the two-sided Wilcoxon signed-rank p
(scipy's ``wilcoxon``; zero differences dropped).

``--protocol original`` runs them in the original protocol's world (``evolution.run.protocol``:
zone 20 x 4, the pickup box at the robot's centre, the original's sensor readings), where a champion of
an ``S1-original`` run was evolved; the default is the paper's world. ``--world-from
CHAMPION.json`` runs them in the world a champion was evolved in (its ``environment`` keys, such
as ``drive_model`` or ``schedule``, but not a one-layout run's ``layout_seed``: the episodes' seeds
lay out fresh worlds (with ``--own-layout`` they keep it, and the seeds vary only the shuffled
schedule: how robust a one-layout champion is on its own layout); also its preset, steps and team
size unless ``--environment``, ``--steps`` or ``--robots`` is given). ``--world KEY=VALUE`` (repeatable)
then sets one world parameter (a ``WorldConfig`` field; VALUE is read as TOML, else as a bare string:
``--world weld_spin=free --world block_counts=[3,2,1]``), to ask what a champion would score in a
world changed in one respect; ``--paired-with FOLDER`` then pairs each policy with itself in an
earlier comparison written to FOLDER (the same policies and seeds, in the world before the change),
seed by seed as above, in a second table of ``compare.md``. A champion evolved in another world
than the one compared in is named in a note on standard output.

Policies: ``evolution.policies`` (the names ``--policy`` takes are listed there).
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import sys
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np

from evolution.guard import (
    ArgumentParser,
    UsageError,
    check_output_dir,
    command,
    int_arg,
    with_world_settings,
    world_setting,
    writing,
)
from evolution.policies import POLICY_NAMES, Policy, make_policy
from evolution.run.experiment import LIMITS
from evolution.run.lock import LOCK_FILE, RunLock
from evolution.run.protocol import PROTOCOLS, protocol_values
from gathering_env import WorldConfig, parallel_env
from gathering_env.config import ENVIRONMENT_PRESETS, INT_RANGES


def run_episode(env, policy: Policy, seed: int) -> dict[str, Any]:
    obs_dict, _ = env.reset(seed=seed, options={"morphology": policy.morphology})
    policy.reset(seed)
    if policy.bind is not None:
        policy.bind(env.sim)
    obs = np.stack([obs_dict[a] for a in env.possible_agents])
    if obs.shape[1] != len(policy.morphology):
        raise ValueError(f"policy {policy.name}: observation width {obs.shape[1]} != {len(policy.morphology)}")
    terminated = truncated = False
    while not (terminated or truncated):
        wheels = np.asarray(policy.act(obs), dtype=np.float64)
        if wheels.shape != (obs.shape[0], 2):
            raise ValueError(f"policy {policy.name} returned actions of shape {wheels.shape}; "
                             f"expected ({obs.shape[0]}, 2)")
        obs, _, terminated, truncated = env.step_batch(wheels)
    info = env.team_info()
    return {"ft": info["task_performance"], "by_type": info["blocks_gathered_by_type"],
            "finished": terminated, "steps": info["steps"]}


def compare(policies: list[Policy], env_config: dict[str, Any], seeds: list[int]) -> list[dict[str, Any]]:
    """One row per policy: ft's mean, standard deviation (``ft_std``, ddof 0) and standard error
    of the mean (``ft_se`` = sample std / sqrt(episodes), None for one episode), mean blocks by
    type, mean steps to finish, finished count; and under ``PER_EPISODE`` its episodes, one dict
    per seed in ``seeds`` order."""
    env = parallel_env(**env_config)
    rows = []
    for policy, name in zip(policies, row_names(policies)):
        episodes = [run_episode(env, policy, s) for s in seeds]
        ft = np.array([e["ft"] for e in episodes])
        by_type = np.array([e["by_type"] for e in episodes], dtype=float)
        done = [e["steps"] for e in episodes if e["finished"]]
        rows.append({
            "policy": name, "sensors": len(policy.morphology), "episodes": len(seeds),
            "ft_mean": float(ft.mean()), "ft_std": float(ft.std()), "ft_se": standard_error(ft),
            "small": float(by_type[:, 0].mean()), "medium": float(by_type[:, 1].mean()),
            "large": float(by_type[:, 2].mean()),
            "finished": len(done), "steps_to_finish": float(np.mean(done)) if done else None,
            PER_EPISODE: [{"policy": name, "seed": s, "ft": float(e["ft"]), "small": int(e["by_type"][0]),
                           "medium": int(e["by_type"][1]), "large": int(e["by_type"][2]),
                           "finished": bool(e["finished"]), "steps": int(e["steps"])}
                          for s, e in zip(seeds, episodes)],
        })
    return rows


def row_names(policies: list[Policy]) -> list[str]:
    """Each policy's row name: its name, and ``name#k`` for the k-th policy of one name."""
    seen: dict[str, int] = {}
    names = []
    for policy in policies:
        seen[policy.name] = seen.get(policy.name, 0) + 1
        names.append(policy.name if seen[policy.name] == 1 else f"{policy.name}#{seen[policy.name]}")
    return names


def champion_world(champion: Policy, path: Path, own_layout: bool) -> dict[str, Any]:
    """The world keys a champion was evolved in, for its episodes here: a one-layout run's layout
    (``layout_seed``) is dropped, so the episodes' seeds lay out fresh worlds, unless ``own_layout``
    (``--own-layout``: then the seeds vary only the shuffled schedule), which needs that key."""
    world = dict(champion.environment or {})
    if own_layout and "layout_seed" not in world:
        raise UsageError(f"--own-layout: {path} has no layout_seed (not a one-layout run under the "
                         "shuffled schedule); allowed: such a champion, or no --own-layout")
    if not own_layout:
        world.pop("layout_seed", None)
    return world


def world_notes(policies: list[Policy], env_config: dict[str, Any]) -> list[str]:
    """One line per policy whose own world (a champion's ``environment``; a key it does not record
    has its default) differs from ``env_config`` in a key other than the ones a comparison sets on
    purpose (preset, steps, team size, and the layout: a one-layout run's ``layout_seed``)."""
    notes = []
    set_on_purpose = ("environment", "max_cycles", "num_robots", "layout_seed")
    compared = WorldConfig.from_kwargs(**env_config)
    for policy in policies:
        if not policy.environment:
            continue
        own = WorldConfig.from_kwargs(**{**{k: v for k, v in policy.environment.items() if k not in set_on_purpose},
                                         **{k: env_config[k] for k in set_on_purpose if k in env_config}})
        changed = [f"{f.name} = {getattr(own, f.name)!r} (here {getattr(compared, f.name)!r})"
                   for f in fields(WorldConfig) if f.name not in set_on_purpose
                   and getattr(own, f.name) != getattr(compared, f.name)]
        if changed:
            notes.append(f"note: {policy.name} was made in another world: {', '.join(changed)}")
    return notes


def standard_error(sample: np.ndarray) -> float | None:
    """Standard error of the mean, std(ddof=1) / sqrt(n); None for fewer than two values."""
    return float(sample.std(ddof=1) / np.sqrt(len(sample))) if len(sample) > 1 else None


def paired_difference(values: Any, baseline: Any) -> dict[str, Any]:
    """``values`` against ``baseline``, episode by episode (the same seeds in the same order):
    mean and standard error of the differences, how many are > 0, = 0, < 0, and the two-sided
    Wilcoxon signed-rank p (scipy; zero differences dropped; NaN when every difference is 0)."""
    from scipy.stats import wilcoxon

    v, base = np.asarray(values, dtype=float), np.asarray(baseline, dtype=float)
    if v.shape != base.shape or v.ndim != 1 or len(v) == 0:
        raise ValueError(f"paired samples need the same episodes; got {v.shape} and {base.shape}")
    diff = v - base
    return {"diff": float(diff.mean()), "diff_se": standard_error(diff),
            "higher": int(np.sum(diff > 0)), "equal": int(np.sum(diff == 0)), "lower": int(np.sum(diff < 0)),
            "wilcoxon_p": float(wilcoxon(v, base).pvalue) if np.any(diff != 0) else float("nan")}


def paired_lines(rows: list[dict[str, Any]]) -> list[str]:
    """The paired table of ``compare.md``: every policy after the first against the first."""
    if len(rows) < 2 or any(PER_EPISODE not in r for r in rows) or rows[0]["episodes"] < 2:
        return []
    first = rows[0]
    base = [e["ft"] for e in first[PER_EPISODE]]
    return paired_table(f"Paired with {first['policy']} on the same seeds (difference = policy − {first['policy']}):",
                        [(r["policy"], [e["ft"] for e in r[PER_EPISODE]], base) for r in rows[1:]])


def paired_table(heading: str, pairs: list[tuple[str, list[float], list[float]]]) -> list[str]:
    """A paired table of ``compare.md``: one row per (name, values, baseline), the values against
    the baseline seed by seed (``paired_difference``)."""
    lines = ["", heading, "",
             "| policy | ft difference (mean ± standard error) | seeds higher / equal / lower | Wilcoxon signed-rank p |",
             "|---|---|---|---|"]
    for name, values, baseline in pairs:
        d = paired_difference(values, baseline)
        p = "—" if np.isnan(d["wilcoxon_p"]) else f"{d['wilcoxon_p']:.2g}"
        lines.append(f"| {name} | {d['diff']:+.2f} ± {d['diff_se']:.2f} | "
                     f"{d['higher']} / {d['equal']} / {d['lower']} | {p} |")
    return lines


def earlier_episodes(folder: Path, names: list[str], seeds: list[int]) -> dict[str, list[float]]:
    """``--paired-with FOLDER``: the ft of each policy in ``names`` on each of ``seeds``, from the
    ``compare-episodes.csv`` an earlier ``gathering-compare`` wrote there (the same policies, named
    as there, on the same seeds); anything else is a ``UsageError`` naming the file."""
    path = folder / "compare-episodes.csv"
    if not path.is_file():
        raise UsageError(f"--paired-with {folder}: no compare-episodes.csv in it; allowed: the --out folder of an "
                         "earlier gathering-compare")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise UsageError(f"{path}: not UTF-8 text; allowed: the file as gathering-compare wrote it") from None
    found: dict[str, dict[int, float]] = {}
    rows = csv.DictReader(io.StringIO(text, newline=""))
    line = 1
    try:
        for number, row in enumerate(rows, start=2):
            line = number
            ft = float(row["ft"])
            if not math.isfinite(ft):
                raise ValueError(ft)
            found.setdefault(row["policy"], {})[int(row["seed"])] = ft
    except (KeyError, TypeError, ValueError, csv.Error):
        raise UsageError(f"{path}:{line}: not a row of policy, seed and a finite ft; allowed: the file as "
                         "gathering-compare wrote it") from None
    for name in names:
        if name not in found:
            raise UsageError(f"--paired-with {folder}: no episodes of {name} in {path.name}; allowed: the policies "
                             f"compared there ({', '.join(sorted(found))})")
        if sorted(found[name]) != sorted(seeds):
            raise UsageError(f"--paired-with {folder}: {name} ran seeds {min(found[name])}..{max(found[name])} "
                             f"({len(found[name])}) there; allowed: the same --seed and --episodes")
    return {name: [found[name][s] for s in seeds] for name in names}


def paired_with_lines(rows: list[dict[str, Any]], earlier: dict[str, list[float]], where: Path) -> list[str]:
    """The table of ``--paired-with``: each policy here against itself in the earlier comparison."""
    return paired_table(f"Paired with the same policies in {where} on the same seeds (difference = here − there):",
                        [(r["policy"], [e["ft"] for e in r[PER_EPISODE]], earlier[r["policy"]]) for r in rows])


#: Every file ``write_outputs`` writes: the output folder may hold these (an earlier
#: comparison, replaced) and nothing else.
COMPARE_FILES = ("compare.csv", "compare.md", "compare.png", "compare-episodes.csv")
#: The key of a ``compare`` row that holds its episodes (written to compare-episodes.csv, not compare.csv).
PER_EPISODE = "per_episode"


def write_outputs(rows: list[dict[str, Any]], out: Path, title: str,
                  extra: list[str] = ()) -> tuple[Path, Path, Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    check_output_dir(out, (*COMPARE_FILES, LOCK_FILE))
    out.mkdir(parents=True, exist_ok=True)
    csv_path = out / "compare.csv"
    summary = [{k: v for k, v in r.items() if k != PER_EPISODE} for r in rows]
    with writing(csv_path), open(csv_path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(summary[0]))
        writer.writeheader()
        writer.writerows(summary)
    episodes = [e for r in rows for e in r.get(PER_EPISODE, [])]
    if episodes:
        episodes_path = out / "compare-episodes.csv"
        with writing(episodes_path), open(episodes_path, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(episodes[0]))
            writer.writeheader()
            writer.writerows(episodes)
    lines = ["| policy | sensors | ft (mean ± standard error) | small | medium | large | finished | steps to finish |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        steps = f"{r['steps_to_finish']:.0f}" if r["steps_to_finish"] is not None else "—"
        se = f" ± {r['ft_se']:.2f}" if r["ft_se"] is not None else " (one episode: no error)"
        lines.append(f"| {r['policy']} | {r['sensors']} | {r['ft_mean']:.2f}{se} | {r['small']:.1f} | "
                     f"{r['medium']:.1f} | {r['large']:.1f} | {r['finished']}/{r['episodes']} | {steps} |")
    md_path = out / "compare.md"
    with writing(md_path):
        md_path.write_text(f"{title}\n\n" + "\n".join(lines + paired_lines(rows) + list(extra)) + "\n")
    fig, ax = plt.subplots(figsize=(1.6 + 1.3 * len(rows), 3.6), constrained_layout=True)
    ax.bar(range(len(rows)), [r["ft_mean"] for r in rows], yerr=[r["ft_se"] or 0.0 for r in rows], capsize=4,
           color="tab:blue")
    ax.set_xticks(range(len(rows)), [r["policy"] for r in rows], rotation=15, fontsize=8)
    ax.set_ylabel("task performance ft (mean ± standard error)")
    ax.set_title(title, fontsize=9)
    png_path = out / "compare.png"
    with writing(png_path):
        fig.savefig(png_path, dpi=110)
    plt.close(fig)
    return md_path, csv_path, png_path


@command
def compare_main(argv: list[str] | None = None) -> int:
    parser = ArgumentParser(prog="gathering-compare", description=__doc__,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--policy", action="append", required=True,
                        help=f"{POLICY_NAMES.replace(', ', ' | ')} (repeat)")
    parser.add_argument("--environment", type=int, choices=tuple(ENVIRONMENT_PRESETS),
                        help="environment preset (paper Table 2; default 2, or --world-from's)")
    parser.add_argument("--steps", type=int_arg(*INT_RANGES["max_cycles"]),
                        help="max_cycles per episode (default 10000, or --world-from's)")
    parser.add_argument("--robots", type=int_arg(*INT_RANGES["num_robots"]), help="team size (default 20, or --world-from's)")
    parser.add_argument("--episodes", type=int_arg(1, 10_000), default=5, help="episodes (seeds 0..n-1) per policy")
    parser.add_argument("--seed", type=int_arg(*LIMITS["seed"]), default=0, help="first episode seed")
    parser.add_argument("--protocol", choices=PROTOCOLS, default=None,
                        help="whose world: paper (default) or original (zone 20 x 4, centre pickup box, "
                             "the original's sensor readings; evolution.run.protocol)")
    parser.add_argument("--world-from", type=Path, metavar="CHAMPION",
                        help="the world a champion.json was evolved in (its environment keys; its preset, "
                             "steps and team size unless given); not with --protocol")
    parser.add_argument("--own-layout", action="store_true",
                        help="with --world-from a one-layout run's champion under the shuffled schedule: keep "
                             "its layout (layout_seed); the episodes' seeds then vary only the schedule")
    parser.add_argument("--world", type=world_setting, action="append", default=[], metavar="KEY=VALUE",
                        help="set one world parameter (a WorldConfig field) over the world chosen above; "
                             "VALUE is TOML or a bare string (repeat)")
    parser.add_argument("--paired-with", type=Path, metavar="FOLDER",
                        help="pair each policy with itself in an earlier comparison's --out folder (the same "
                             "policies and seeds, another world): a paired table in compare.md")
    parser.add_argument("--out", type=Path, default=Path("compare"),
                        help="folder for compare.md, compare.csv, compare-episodes.csv, compare.png (default compare/)")
    args = parser.parse_args(argv)
    if args.world_from is not None and args.protocol is not None:
        raise UsageError("--world-from and --protocol both name the world; allowed: one of them")
    check_output_dir(args.out, (*COMPARE_FILES, LOCK_FILE))
    if args.own_layout and args.world_from is None:
        raise UsageError("--own-layout: keeps the layout of --world-from's champion; allowed: with --world-from")
    if args.world_from is not None:
        world = champion_world(make_policy(f"champion:{args.world_from}"), args.world_from, args.own_layout)
        where = f", the world of {args.world_from}{' on its own layout' if args.own_layout else ''}"
    else:
        world = protocol_values(args.protocol or "paper")["environment"]
        where = ", original protocol" if args.protocol == "original" else ""
    for name, key, default in (("environment", "environment", 2), ("steps", "max_cycles", 10_000),
                               ("robots", "num_robots", 20)):
        if getattr(args, name) is None:
            setattr(args, name, world.get(key, default))
    env_config = {**world, "environment": args.environment, "max_cycles": args.steps, "num_robots": args.robots}
    WorldConfig.from_kwargs(**env_config)
    env_config = with_world_settings(env_config, args.world, ("environment", "max_cycles", "num_robots"))
    if args.world:
        where += ", with " + ", ".join(f"{k} = {v!r}" for k, v in args.world)
    policies = [make_policy(p) for p in args.policy]
    seeds = list(range(args.seed, args.seed + args.episodes))
    earlier = None
    if args.paired_with is not None:
        if args.episodes < 2:
            raise UsageError(f"--paired-with needs at least 2 episodes; allowed: --episodes {args.episodes} -> 2 or more")
        if args.paired_with.resolve() == args.out.resolve():
            raise UsageError(f"--paired-with {args.paired_with}: the same folder as --out (it would be replaced); "
                             "allowed: another --out")
        earlier = earlier_episodes(args.paired_with, row_names(policies), seeds)
    for line in world_notes(policies, env_config):
        print(line)
    title = (f"environment {args.environment}{where}, "
             f"{args.robots} robots, {args.steps} steps, "
             f"{args.episodes} episodes (seeds {args.seed}..{args.seed + args.episodes - 1})")
    # one writer per --out: a second copy stops here, before any episode
    with RunLock(args.out, what="output folder", by="another gathering-compare"):
        rows = compare(policies, env_config, seeds)
        extra = paired_with_lines(rows, earlier, args.paired_with) if earlier is not None else []
        md, csv_path, png = write_outputs(rows, args.out, title, extra)
    print(md.read_text())
    episodes = args.out / "compare-episodes.csv"
    written = [md, csv_path, *([episodes] if episodes.exists() else []), png]
    print("wrote " + ", ".join(map(str, written)))
    return 0


def run_compare() -> None:
    sys.exit(compare_main())
