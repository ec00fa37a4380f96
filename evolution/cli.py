"""Command-line entry points: ``gathering-evolve``, ``gathering-replay``, ``gathering-analyze``.

Errors in input files (experiment TOML, neat config, checkpoint, champion) end with a
one-line message naming the file and field and exit status 2; nothing already written is
touched.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from .checkpoint import CheckpointError
from .experiment import (
    METHODS,
    ExperimentError,
    is_preset_name,
    load_experiment,
    neat_config_names,
    preset_description,
    preset_names,
    preset_path,
)


def _fail(message: str) -> int:
    print(f"error: {message}", file=sys.stderr)
    return 2


def _list_presets() -> int:
    for name in preset_names() + neat_config_names():
        print(f"{name:22s} {preset_description(name)}")
    return 0


def _dump_preset(name: str) -> int:
    try:
        path = preset_path(name, neat_configs=True)
    except ExperimentError as err:
        return _fail(f"--dump {err}")
    sys.stdout.write(path.read_text(encoding="utf-8"))
    return 0


def evolve_main(argv: list[str] | None = None) -> int:
    """``gathering-evolve [PRESET | EXPERIMENT.toml] [overrides] --out RUN_DIR``."""
    from gathering_env import __version__

    parser = argparse.ArgumentParser(
        prog="gathering-evolve",
        description="Co-evolve controllers and sensor morphologies of a robot team (HyperNEAT-M / NEAT-M).",
    )
    parser.add_argument("experiment", nargs="?",
                        help="a preset name (S1, quick, ...: see --list) or a TOML experiment file "
                             "(default: built-in paper defaults)")
    parser.add_argument("--list", action="store_true", help="list the shipped presets and exit")
    parser.add_argument("--dump", metavar="PRESET",
                        help="print a preset's file (e.g. --dump S1 > my.toml) and exit")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("--out", type=Path, help="run directory (default: runs/<name>-seed<seed>)")
    parser.add_argument("--workers", type=int, default=None, help="evaluation processes (default: all cores; 1 = serial)")
    parser.add_argument("--resume", action="store_true", help="continue the run in --out from its newest checkpoint")
    parser.add_argument("--resume-from", type=Path, help="continue from this checkpoint file")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--backend", choices=("serial", "process", "ray"), default="process",
                        help="where genomes are evaluated (default: process pool)")
    parser.add_argument("--ray-address", help="join this Ray cluster (e.g. 'auto' or 'head:6379') instead of a local Ray")
    parser.add_argument("--max-retries", type=int, default=2, help="retries of a failing evaluation (default 2)")
    group = parser.add_argument_group("overrides of the experiment file")
    group.add_argument("--name")
    group.add_argument("--method", choices=METHODS)
    group.add_argument("--objectives", help="comma-separated: task,morphology,controller")
    group.add_argument("--seed", type=int)
    group.add_argument("--generations", type=int)
    group.add_argument("--population", type=int)
    group.add_argument("--trials", type=int)
    group.add_argument("--environment", type=int, help="environment preset 1, 2 or 3")
    group.add_argument("--steps", type=int, help="steps per trial (max_cycles)")
    group.add_argument("--robots", type=int, help="team size (num_robots)")
    args = parser.parse_args(argv)
    if args.list:
        return _list_presets()
    if args.dump is not None:
        return _dump_preset(args.dump)

    overrides = {
        "name": args.name, "method": args.method, "seed": args.seed, "generations": args.generations,
        "population": args.population, "trials": args.trials,
        "objectives": args.objectives.split(",") if args.objectives else None,
        "environment.environment": args.environment, "environment.max_cycles": args.steps,
        "environment.num_robots": args.robots,
    }
    if args.workers is not None and args.workers < 1:
        return _fail(f"--workers={args.workers}; allowed: >= 1")
    if args.max_retries < 0:
        return _fail(f"--max-retries={args.max_retries}; allowed: >= 0")
    try:
        experiment_file = args.experiment
        if experiment_file is not None and is_preset_name(experiment_file):
            experiment_file = preset_path(experiment_file)
        experiment = load_experiment(experiment_file, overrides)
        out = args.out or Path("runs") / f"{experiment.name}-seed{experiment.seed}"
        from .trainer import Trainer

        trainer = Trainer(experiment, out, workers=args.workers, resume=args.resume,
                          resume_from=args.resume_from, progress=not args.no_progress,
                          backend=args.backend, ray_address=args.ray_address, max_retries=args.max_retries)
        result = trainer.run()
    except (ExperimentError, CheckpointError) as err:
        return _fail(str(err))
    except ValueError as err:  # e.g. the ray backend without Ray installed
        return _fail(str(err))
    except KeyboardInterrupt:
        print("\ninterrupted: resume with --resume", file=sys.stderr)
        return 130
    if result.interrupted:
        print(f"stopped after {result.generations} generations; resume with: gathering-evolve ... --out {out} --resume")
        return 130
    status = "converged" if result.converged else "finished"
    print(f"{status}: {result.generations} generations, best ft {result.best_task:.2f}")
    print(f"run directory: {result.run_dir}  (stats.jsonl, stats.csv, stats.png, champion.json, checkpoints/)")
    return 0


def replay_main(argv: list[str] | None = None) -> int:
    """``gathering-replay CHAMPION.json [--environment N] [--out team.gif]``."""
    parser = argparse.ArgumentParser(prog="gathering-replay",
                                     description="Replay an evolved team and save the episode as GIF/MP4.")
    parser.add_argument("champion", type=Path, help="champion JSON written by gathering-evolve")
    parser.add_argument("--environment", type=int, choices=(1, 2, 3), help="preset (default: the one it evolved in)")
    parser.add_argument("--steps", type=int, help="episode length (default: the evolved max_cycles)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("team.gif"), help=".gif or .mp4")
    parser.add_argument("--frame-every", type=int, default=10, help="record every k-th step")
    parser.add_argument("--fps", type=int, default=15)
    parser.add_argument("--png", type=Path, help="also save the last frame as a PNG picture")
    args = parser.parse_args(argv)
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    from .champion import ChampionError, load_champion
    from .replay import replay

    try:
        champion = load_champion(args.champion)
        env_config = dict(champion.environment)
        if args.environment is not None:
            env_config["environment"] = args.environment
        if args.steps is not None:
            env_config["max_cycles"] = args.steps
        info, path, frames = replay(champion, env_config, args.seed, args.out, args.frame_every, args.fps,
                                    png=args.png)
    except ChampionError as err:
        return _fail(str(err))
    except ValueError as err:
        return _fail(str(err))
    print(f"{champion.experiment or 'champion'} ({champion.method}, {len(champion.morphology)} sensors) in "
          f"environment {env_config.get('environment')}: ft = {info['task_performance']:.2f}, gathered "
          f"{info['gathered_value']:.0f}/{info['total_value']:.0f} in {info['steps']} steps")
    print(f"wrote {path} ({frames} frames)")
    return 0


def analyze_main(argv: list[str] | None = None) -> int:
    """``gathering-analyze RUN_DIR... --out report/``."""
    parser = argparse.ArgumentParser(
        prog="gathering-analyze",
        description="Merge MO fronts, compute selection points and SO-vs-MO tests; write Table 4, "
                    "Figures 4-6 and report.md.",
    )
    parser.add_argument("runs", nargs="+", type=Path, help="run directories written by gathering-evolve")
    parser.add_argument("--out", type=Path, default=Path("report"), help="output directory (default: report/)")
    from .reevaluate import REEVALUATE_TRIALS

    parser.add_argument("--reevaluate", type=int, default=REEVALUATE_TRIALS, metavar="K",
                        help="re-run every SO champion and MO front genome K times on held-out seeds and report "
                             f"those scores (default {REEVALUATE_TRIALS}; cached in each run directory); "
                             "0 = use the training scores")
    parser.add_argument("--workers", type=int, default=None,
                        help="evaluation processes for --reevaluate (default: all cores; 1 = serial)")
    parser.add_argument("--backend", default="process", help="serial, process or ray (default: process)")
    args = parser.parse_args(argv)
    from .analysis import analyse
    from .backends import BACKENDS
    from .report import write_report

    if args.reevaluate < 0:
        return _fail(f"--reevaluate={args.reevaluate}; allowed: an integer >= 0 (0 = training scores)")
    if args.workers is not None and args.workers < 1:
        return _fail(f"--workers={args.workers}; allowed: >= 1")
    if args.backend not in BACKENDS:
        return _fail(f"--backend={args.backend!r}; allowed: {', '.join(BACKENDS)}")
    try:
        analysis = analyse(args.runs, reevaluate=args.reevaluate, workers=args.workers, backend=args.backend)
    except ValueError as err:
        return _fail(str(err))
    path = write_report(analysis, args.out)
    print(f"{len(analysis.runs)} runs, {len(analysis.comparisons)} comparisons -> {path}")
    print(f"ft used: {analysis.scores}")
    return 0


def run_evolve() -> None:
    sys.exit(evolve_main())


def run_replay() -> None:
    sys.exit(replay_main())


def run_analyze() -> None:
    sys.exit(analyze_main())
