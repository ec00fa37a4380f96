"""Regenerate every picture of docs/ from the commands that make them, so none goes stale.

    make docs-images                                    # the pictures this repository can make alone
    python examples/docs_images.py [--only gallery,random-episode] [--champion out/quick/champion.json]
    python examples/docs_images.py --evidence out/evidence-fidelity     # + the evidence pictures
    python examples/docs_images.py --rl out/rl                          # + the RL pictures

``STEPS`` lists every picture of docs/ with the step that makes it (tests/test_docs_images.py
checks that the list and the pictures in docs/ are the same). The steps:

* ``gallery`` (docs/img/render-*.png): ``examples/render_gallery.py`` on a champion, by default
  the one of ``make demo``'s run (out/quick/champion.json; evolved first if missing);
* ``random-episode`` (docs/random_episode.png): the last frame of ``examples/random_episode.py``;
* ``evolved-team`` (docs/evolved_team.png): ``gathering-replay --png`` of the S2-seed1 champion
  of the reduced evidence run; needs ``--evidence DIR`` (the run directories of
  docs/evidence/README.md);
* ``evidence`` (docs/evidence/figure*.png, with the report they belong to): ``gathering-analyze``
  of those runs; needs ``--evidence DIR``;
* ``original-m1-analysis`` (docs/evidence/original-M1/analysis-*/): ``gathering-analyze`` of the
  original-protocol S1 and M1 runs of version 2, both ways (``--reevaluate 0`` and ``20``); needs
  ``--original-runs DIR`` holding ``S1-original-continued`` and ``M1-original`` rebuilt from their
  records (docs/evidence/original-M1/README.md); ``original-m1-five-analysis`` the same for
  version 3 (``S1-original-five`` and ``M1-original-five``, docs/evidence/original-M1-five/);
* ``original-s1-continued``, ``original-s1-five``, ``original-s1-five-seed2``, ``original-s1-v4``, ``original-m1-five``
  and the other steps of ``RECORD_CURVES`` (docs/evidence/<folder>/stats.png): the curve of a run
  kept going across sessions, drawn from its committed record (stats.jsonl);
* ``original-s1-v4-cells`` (docs/evidence/original-S1-v4/cells.png): best-ever ft of version 4's
  2 x 2 (Encog's truncation, Encog's weights, both, neither), of versions 5-11 and of version 10's
  world bred as version 3 was, from the committed records;
* ``rl`` (docs/rl/*.png): ``examples/rl_figures.py`` and the learning curves of the PPO runs of
  docs/rl/README.md; needs ``--rl DIR`` (the runs) and the demo champion.

Steps whose inputs are not given are skipped with a line saying what they need: the evidence and
RL runs take hours. Everything is drawn by the current renderer and plotting code.
"""

from __future__ import annotations

import argparse
import itertools
import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
PICTURE_SUFFIXES = (".png", ".gif", ".jpg", ".jpeg", ".svg", ".mp4")
GALLERY = ("default", "cameras-auto", "cameras-all", "cones-robots", "zone", "follow", "trail", "small",
           "strip", "sensors", "human")
EVIDENCE_RUNS = ("S2-seed1", "S2-seed2", "M2-seed1", "M2-seed2")
EVIDENCE_FIGURES = ("figure4_fronts.png", "figure5_simplicity.png", "figure6_points.png")
# learning curves of single PPO runs shown in docs/rl/README.md: picture -> run directory
RL_CURVES = {
    "curve-oldbonus-shaped-team-env1.png": "ppo-oldbonus-shaped-team-env1",
    "curve-oldbonus-shaped-local-env1.png": "ppo-oldbonus-shaped-local-env1",
    "curve-ent0-oldbonus-shaped-team-env1.png": "ppo-ent0-oldbonus-shaped-team-env1",
}
RL_FIGURES = tuple(f"compare-env{e}-{s}.png" for e in (1, 2) for s in (2000, 10000)) + \
    ("curves-env1.png", "curves-env2.png")


@dataclass(frozen=True)
class Step:
    outputs: tuple[str, ...]        # pictures, relative to docs/
    needs: str | None               # None or the option naming its input folder
    make: Callable[[argparse.Namespace], None]


def run(*command: str | Path) -> None:
    """Run a command from the repository root with this interpreter's tools; stop on failure."""
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy",
           "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    print("+", " ".join(str(c) for c in command), flush=True)
    subprocess.run([str(c) for c in command], cwd=ROOT, env=env, check=True)


def cli(name: str) -> list[str]:
    """A console script of this checkout, run through this interpreter."""
    module, function = {"gathering-evolve": ("evolution.cli", "run_evolve"),
                        "gathering-replay": ("evolution.cli", "run_replay"),
                        "gathering-analyze": ("evolution.cli", "run_analyze")}[name]
    return [sys.executable, "-c", f"import sys; from {module} import {function} as f; sys.argv[0] = {name!r}; f()"]


def demo_champion(args: argparse.Namespace) -> Path:
    if args.champion is not None:
        return args.champion
    champion = ROOT / "out" / "quick" / "champion.json"
    if not champion.is_file():  # make demo's run
        run(*cli("gathering-evolve"), "configs/quick.toml", "--out", "out/quick", "--no-progress")
    return champion


def make_gallery(args: argparse.Namespace) -> None:
    run(sys.executable, "examples/render_gallery.py", demo_champion(args), "--out", DOCS / "img", "--force")


def make_random_episode(args: argparse.Namespace) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        run(sys.executable, "examples/random_episode.py", "--environment", "2", "--steps", "600", "--seed", "0",
            "--out", Path(tmp) / "random_episode.gif", "--png", DOCS / "random_episode.png")


def make_evolved_team(args: argparse.Namespace) -> None:
    run(*cli("gathering-replay"), args.evidence / "S2-seed1" / "champion.json", "--seed", "3", "--steps", "2000",
        "--png", DOCS / "evolved_team.png", "--out", Path(tempfile.mkdtemp()) / "team.gif")


def make_evidence(args: argparse.Namespace) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        report = Path(tmp) / "report"
        run(*cli("gathering-analyze"), *(args.evidence / r for r in EVIDENCE_RUNS), "--reevaluate", "20",
            "--out", report)
        for produced in sorted(report.iterdir()):  # the figures with the report they belong to
            shutil.copy2(produced, DOCS / "evidence" / produced.name)


def make_marl(args: argparse.Namespace) -> None:
    """The IPPO / MAPPO comparison of docs/rl/README.md from BenchMARL runs (``--marl DIR`` of
    ``examples/benchmarl_run.py`` outputs; training them takes hours)."""
    run(sys.executable, "examples/marl_figures.py", "--runs", args.marl, "--out", DOCS / "rl")


ORIGINAL_S1_FILES = ("stats.png", "stats.jsonl", "stats.csv", "experiment.json", "champion.json")


def make_original_s1(args: argparse.Namespace) -> None:
    """The original-protocol S1 run's figure and small files (``--original-s1 DIR``: its run
    directory, ``gathering-evolve S1-original``; hours of CPU). A run still going has no
    ``stats.png`` yet: it is drawn from its statistics."""
    for name in ORIGINAL_S1_FILES:
        if (args.original_s1 / name).exists():
            shutil.copy2(args.original_s1 / name, DOCS / "evidence" / "original-S1" / name)
        elif name == "stats.png":
            from evolution.run.plots import plot_run
            from evolution.run.stats import read_stats

            plot_run(read_stats(args.original_s1 / "stats.jsonl"), DOCS / "evidence" / "original-S1" / name,
                     title="S1-original")


# step -> (docs/evidence folder, title): runs kept going across sessions, whose curve is drawn
# from their committed record (stats.jsonl) rather than from a run directory
RECORD_CURVES = {
    "original-s1-continued": ("original-S1-continued", "S1-original, continued"),
    "original-s1-shuffled": ("original-S1-shuffled", "S1-original, force drive, shuffled schedule"),
    "original-s1-five": ("original-S1-five", "S1-original (version 3), five schedules a genome"),
    "original-s1-five-seed2": ("original-S1-five-seed2", "S1-original (version 3), five schedules, seed 2"),
    "original-m1-five": ("original-M1-five", "M1-original (version 3), five schedules a genome"),
    "original-s1-v4": ("original-S1-v4", "S1-original (version 4: Encog's truncation and weights)"),
    "original-s1-v11": ("original-S1-v11", "S1-original (version 11: the original's welded robot), converged"),
}


def record_curve(step: str) -> Callable[[argparse.Namespace], None]:
    """``stats.png`` of a run kept going across sessions, drawn from its committed record
    (``docs/evidence/<folder>/stats.jsonl``)."""
    folder_name, title = RECORD_CURVES[step]

    def make(args: argparse.Namespace) -> None:
        from evolution.run.plots import plot_run
        from evolution.run.stats import read_stats

        folder = DOCS / "evidence" / folder_name
        plot_run(read_stats(folder / "stats.jsonl"), folder / "stats.png", title=title)

    return make


# docs/evidence folder -> (label, colour, line style): version 4's 2 x 2 of Encog's truncation and
# weights (seed 1), version 4 with the original's bearings, versions 6-11, version 10's world bred as
# version 3 was, and version 3's second seed for scale; drawn from the committed records
V4_CELLS = {
    "original-S1-five": ("version 3 (neither), seed 1", "C0", "-"),
    "original-S1-five-seed2": ("version 3 (neither), seed 2", "C0", "--"),
    "original-S1-v4-neat-weights": ("Encog's truncation only", "C2", "-"),
    "original-S1-v4-neat-truncation": ("Encog's weights only", "C1", "-"),
    "original-S1-v4": ("version 4 (both), seed 1", "C3", "-"),
    "original-S1-v4-atan-bearings": ("version 5 (version 4 + the original's bearings)", "C4", "-"),
    "original-S1-v6": ("version 6 (version 5 + the original's colour reading)", "C5", "-"),
    "original-S1-v7": ("version 7 (version 6 + the original's block sighting)", "C6", "-"),
    "original-S1-v8": ("version 8 (version 7 + the original's Khepera curve)", "C7", "-"),
    "original-S1-v9": ("version 9 (version 8 + the original's wall distances)", "C8", "-"),
    "original-S1-v10": ("version 10 (version 9 + Encog's species bookkeeping)", "C9", "-"),
    "original-S1-v10-neat-breeding": ("version 10's world, version 3's breeding", "C9", "--"),
    "original-S1-v11": ("version 11 (version 10 + the original's welded robot)", "k", "-"),
}


def make_v4_cells(args: argparse.Namespace) -> None:
    """Best-ever ft by generation of version 4's 2 x 2 (``docs/evidence/original-S1-v4/cells.png``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from evolution.run.stats import read_stats

    fig, ax = plt.subplots(figsize=(8, 4.5))
    for folder, (label, colour, style) in V4_CELLS.items():
        path = DOCS / "evidence" / folder / "stats.jsonl"
        if not path.exists():
            continue
        rows = read_stats(path)
        best = list(itertools.accumulate((r["task_best"] for r in rows), max))  # version 10 does not carry gen 0's
        ax.plot([r["generation"] for r in rows], best, style, color=colour, label=label)
    ax.axhline(110, color="grey", lw=0.8, ls=":", label="convergence (110)")
    ax.set_xlabel("generation")
    ax.set_ylabel("best-ever ft (mean of 5 schedules)")
    ax.set_title("S1-original: version 4's options one at a time, versions 5-11 (seed 1)")
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(DOCS / "evidence" / "original-S1-v4" / "cells.png", dpi=110)
    plt.close(fig)


ORIGINAL_M1_ANALYSES = {"analysis-training": "0", "analysis-heldout": "20"}  # folder -> --reevaluate
# step -> (S1 run, M1 run, docs/evidence folder): the M1 run beside the S1 run of its protocol version
ORIGINAL_M1_PAIRS = {
    "original-m1-analysis": ("S1-original-continued", "M1-original", "original-M1"),      # version 2
    "original-m1-five-analysis": ("S1-original-five", "M1-original-five", "original-M1-five"),  # version 3
}


def original_m1_analysis(step: str) -> Callable[[argparse.Namespace], None]:
    """Table 4 and Figures 4-6 of an original-protocol M1 run beside the S1 run of its version,
    scored on the training layout and held out (``--original-runs DIR`` holds both runs)."""
    s1, m1, target = ORIGINAL_M1_PAIRS[step]

    def make(args: argparse.Namespace) -> None:
        runs = (args.original_runs / s1, args.original_runs / m1)
        for folder, episodes in ORIGINAL_M1_ANALYSES.items():
            with tempfile.TemporaryDirectory() as tmp:
                report = Path(tmp) / "report"
                run(*cli("gathering-analyze"), *runs, "--reevaluate", episodes, "--out", report)
                (DOCS / "evidence" / target / folder).mkdir(parents=True, exist_ok=True)
                for produced in sorted(report.iterdir()):
                    shutil.copy2(produced, DOCS / "evidence" / target / folder / produced.name)

    return make


LEARNING_FILES = ("learning.png", "learning.json", "learning.md")
LEARNING_RUN_FILES = ("stats.png", "stats.jsonl", "stats.csv", "experiment.json", "champion.json")


def make_learning(args: argparse.Namespace) -> None:
    """The learning benchmark's figure and small files, from ``make bench-learning``'s folder
    (``--learning DIR``; the benchmark itself takes about an hour)."""
    target = DOCS / "evidence" / "learning"
    for name in LEARNING_FILES:
        shutil.copy2(args.learning / name, target / name)
    for run_name in ("S1", "M1"):
        for name in LEARNING_RUN_FILES:
            shutil.copy2(args.learning / run_name / name, target / run_name / name)


def make_rl(args: argparse.Namespace) -> None:
    champion = demo_champion(args)
    made = ROOT / "out" / "rl-figures"  # rl_figures.py writes only into its own folder, never docs/rl
    run(sys.executable, "examples/rl_figures.py", "--runs", args.rl, "--champion", champion.parent, "--out", made)
    for picture in RL_FIGURES:
        shutil.copy2(made / picture, DOCS / "rl" / picture)
    for picture, run_dir in RL_CURVES.items():
        shutil.copy2(args.rl / run_dir / "curve.png", DOCS / "rl" / picture)


STEPS: dict[str, Step] = {
    "gallery": Step(tuple(f"img/render-{name}.png" for name in GALLERY), None, make_gallery),
    "random-episode": Step(("random_episode.png",), None, make_random_episode),
    "evolved-team": Step(("evolved_team.png",), "evidence", make_evolved_team),
    "evidence": Step(tuple(f"evidence/{f}" for f in EVIDENCE_FIGURES), "evidence", make_evidence),
    "rl": Step(tuple(f"rl/{f}" for f in (*RL_FIGURES, *RL_CURVES)), "rl", make_rl),
    "marl": Step(("rl/curves-marl-env1.png",), "marl", make_marl),
    "original-s1": Step(("evidence/original-S1/stats.png",), "original_s1", make_original_s1),
    "original-s1-v4-cells": Step(("evidence/original-S1-v4/cells.png",), None, make_v4_cells),
    **{step: Step((f"evidence/{folder}/stats.png",), None, record_curve(step))
       for step, (folder, _) in RECORD_CURVES.items()},
    **{step: Step(tuple(f"evidence/{target}/{folder}/{f}" for folder in ORIGINAL_M1_ANALYSES
                        for f in EVIDENCE_FIGURES), "original_runs", original_m1_analysis(step))
       for step, (_, _, target) in ORIGINAL_M1_PAIRS.items()},
    "learning": Step(("evidence/learning/learning.png", "evidence/learning/S1/stats.png",
                      "evidence/learning/M1/stats.png"), "learning", make_learning),
}


def outputs() -> set[str]:
    """Every picture the steps make, relative to docs/."""
    return {path for step in STEPS.values() for path in step.outputs}


def pictures_in_docs(docs: Path = DOCS) -> set[str]:
    """Every picture file under ``docs``, relative to it."""
    return {p.relative_to(docs).as_posix() for p in docs.rglob("*") if p.suffix.lower() in PICTURE_SUFFIXES}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", default=None,
                        help=f"comma-separated steps to run (default: all whose inputs are given): {', '.join(STEPS)}")
    parser.add_argument("--champion", type=Path, default=None,
                        help="champion.json for the gallery (default: make demo's, out/quick/champion.json)")
    parser.add_argument("--original-s1", type=Path, default=None,
                        help="run directory of gathering-evolve S1-original: the original protocol's evidence")
    parser.add_argument("--marl", type=Path, default=None,
                        help="folder of the BenchMARL runs (examples/benchmarl_run.py): the IPPO/MAPPO figures")
    parser.add_argument("--original-runs", type=Path, default=None,
                        help="folder holding the original-protocol S1 and M1 runs rebuilt from their records "
                             "(S1-original-continued and M1-original; S1-original-five and M1-original-five): "
                             "the original-protocol M1 analyses")
    parser.add_argument("--learning", type=Path, default=None,
                        help="folder of make bench-learning (runs/bench-learning): the learning benchmark's figures")
    parser.add_argument("--evidence", type=Path, default=None,
                        help="folder of the evidence runs (S2-seed1 ... M2-seed2; docs/evidence/README.md)")
    parser.add_argument("--rl", type=Path, default=None, help="folder of the PPO runs of docs/rl/README.md")
    args = parser.parse_args(argv)
    chosen = list(STEPS) if args.only is None else [s.strip() for s in args.only.split(",") if s.strip()]
    unknown = [s for s in chosen if s not in STEPS]
    if unknown:
        parser.error(f"--only {args.only}: unknown step {unknown[0]!r}; allowed: {', '.join(STEPS)}")
    if not chosen:
        parser.error(f"--only {args.only!r}: names no step; allowed: a comma-separated list of {', '.join(STEPS)}")
    if args.champion is not None and not args.champion.is_file():
        parser.error(f"--champion {args.champion}: no such file; allowed: a champion.json of gathering-evolve")
    for key in ("original_s1", "original_runs", "marl", "learning", "evidence", "rl"):
        folder = getattr(args, key)
        if folder is not None and not folder.is_dir():
            print(f"error: --{key.replace('_', '-')} {folder}: no such folder; allowed: an existing folder of runs",
                  file=sys.stderr)
            return 2
    if args.original_s1 is not None and not (args.original_s1 / "stats.jsonl").is_file():
        print(f"error: --original-s1 {args.original_s1}: no stats.jsonl; allowed: a run directory of "
              "gathering-evolve S1-original", file=sys.stderr)
        return 2
    if args.original_runs is not None:
        for step in (step for step in chosen if step in ORIGINAL_M1_PAIRS):
            s1, m1, _ = ORIGINAL_M1_PAIRS[step]
            for run_name in (s1, m1):
                if not (args.original_runs / run_name / "stats.jsonl").is_file():
                    print(f"error: --original-runs {args.original_runs}: no {run_name}/stats.jsonl; allowed: a folder "
                          f"holding {s1} and {m1} rebuilt from their records (step {step})", file=sys.stderr)
                    return 2
    for name in chosen:
        step = STEPS[name]
        if step.needs and getattr(args, step.needs) is None:
            print(f"skipped {name} ({len(step.outputs)} pictures): needs --{step.needs.replace('_', '-')} DIR")
            continue
        step.make(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
