"""Command-line entry points: ``gathering-evolve``, ``gathering-replay``, ``gathering-analyze``.

Errors in options and input files (experiment TOML, neat config, checkpoint, champion) end
with a one-line message naming the option, file or field and exit status 2 (``evolution.guard``);
nothing already written is touched. See docs/guarantees.md.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from .experiment import LIMITS, METHODS, load_experiment
from .guard import ArgumentParser, UsageError, check_output_file, command, int_arg

MAX_WORKERS = max(4, 4 * (os.cpu_count() or 1))
"""Most evaluation processes ``--workers`` may ask for: four per core (each worker holds its own
environment, so more processes than cores only add memory)."""


@command
def evolve_main(argv: list[str] | None = None) -> int:
    """``gathering-evolve [EXPERIMENT.toml] [overrides] --out RUN_DIR``."""
    parser = ArgumentParser(
        prog="gathering-evolve",
        description="Co-evolve controllers and sensor morphologies of a robot team (HyperNEAT-M / NEAT-M).",
    )
    parser.add_argument("experiment", nargs="?", type=Path,
                        help="TOML experiment file (default: built-in paper defaults; see configs/)")
    parser.add_argument("--out", type=Path, help="run directory (default: runs/<name>-seed<seed>)")
    parser.add_argument("--workers", type=int_arg(1, MAX_WORKERS), default=None,
                        help="evaluation processes (default: all cores; 1 = serial)")
    parser.add_argument("--resume", nargs="?", const=True, type=Path, metavar="RUN_DIR",
                        help="continue a run from its newest readable checkpoint: RUN_DIR (or --out); without "
                             "an experiment file the run's own experiment is used")
    parser.add_argument("--resume-from", type=Path, metavar="CHECKPOINT",
                        help="continue from this checkpoint, in its run directory or into a new --out")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--backend", choices=("serial", "process", "ray"), default="process",
                        help="where genomes are evaluated (default: process pool)")
    parser.add_argument("--ray-address", help="join this Ray cluster (e.g. 'auto' or 'head:6379') instead of a local Ray")
    parser.add_argument("--max-retries", type=int_arg(0, 100), default=2,
                        help="retries of a failing evaluation (default 2)")
    group = parser.add_argument_group("overrides of the experiment file")
    group.add_argument("--name")
    group.add_argument("--method", choices=METHODS)
    group.add_argument("--objectives", help="comma-separated: task,morphology,controller")
    group.add_argument("--seed", type=int_arg(*LIMITS["seed"]))
    group.add_argument("--generations", type=int_arg(*LIMITS["generations"]))
    group.add_argument("--population", type=int_arg(*LIMITS["population"]))
    group.add_argument("--trials", type=int_arg(*LIMITS["trials"]))
    group.add_argument("--environment", type=int, help="environment preset 1, 2 or 3")
    group.add_argument("--steps", type=int, help="steps per trial (max_cycles)")
    group.add_argument("--robots", type=int, help="team size (num_robots)")
    args = parser.parse_args(argv)

    overrides = {
        "name": args.name, "method": args.method, "seed": args.seed, "generations": args.generations,
        "population": args.population, "trials": args.trials,
        "objectives": [o.strip() for o in args.objectives.split(",")] if args.objectives is not None else None,
        "environment.environment": args.environment, "environment.max_cycles": args.steps,
        "environment.num_robots": args.robots,
    }
    resume = args.resume is not None or args.resume_from is not None
    out = args.out
    if args.resume is True and out is None and args.experiment is not None and args.experiment.is_dir():
        out, args.experiment = args.experiment, None  # gathering-evolve RUN_DIR --resume
    if isinstance(args.resume, Path):
        if out is not None and out.resolve() != args.resume.resolve():
            raise UsageError(f"--resume {args.resume}: differs from --out {out}; allowed: one run directory "
                             "(--resume RUN_DIR alone)")
        out = args.resume
    if args.resume_from is not None and args.resume_from.is_dir():
        raise UsageError(f"--resume-from {args.resume_from}: is a folder; allowed: a checkpoint file "
                         "(RUN_DIR/checkpoints/gen-NNNN.ckpt), or --resume RUN_DIR")
    if out is None and args.resume_from is not None:
        from .trainer import run_dir_of

        out = run_dir_of(args.resume_from)
        if out is None:
            raise UsageError(f"--resume-from {args.resume_from}: not in a run's checkpoints/ folder; allowed: "
                             "add --out NEW_DIR to continue it there")
    if resume and out is None:
        raise UsageError("--resume: which run? allowed: --resume RUN_DIR")
    if resume and args.experiment is None:
        experiment = None  # the run's own experiment, from its checkpoint
    else:
        experiment = load_experiment(args.experiment, overrides)
        out = out or Path("runs") / f"{experiment.name}-seed{experiment.seed}"
    from .trainer import Trainer

    trainer = Trainer(experiment, out, workers=args.workers, resume=resume,
                      resume_from=args.resume_from, progress=not args.no_progress,
                      backend=args.backend, ray_address=args.ray_address, max_retries=args.max_retries,
                      overrides=overrides)
    try:
        result = trainer.run()
    except KeyboardInterrupt:
        print(f"\ninterrupted: resume with gathering-evolve --resume {out}", file=sys.stderr)
        return 130
    if result.interrupted:
        print(f"stopped after {result.generations} generations; resume with: gathering-evolve --resume {out}")
        return 130
    if result.already_finished:
        why = "converged" if result.converged else f"reached its {trainer.experiment.generations} generations"
        print(f"{out}: already finished ({why}: {result.generations} generations, best ft {result.best_task:.2f}); "
              "nothing to evolve (raise --generations to continue it)")
        return 0
    status = "converged" if result.converged else "finished"
    print(f"{status}: {result.generations} generations, best ft {result.best_task:.2f}")
    print(f"run directory: {result.run_dir}  (stats.jsonl, stats.csv, stats.png, champion.json, checkpoints/)")
    return 0


@command
def replay_main(argv: list[str] | None = None) -> int:
    """``gathering-replay CHAMPION.json [--environment N] [--out team.gif]``."""
    parser = ArgumentParser(prog="gathering-replay",
                            description="Replay an evolved team and save the episode as GIF/MP4.")
    parser.add_argument("champion", type=Path, help="champion JSON written by gathering-evolve")
    parser.add_argument("--environment", type=int, choices=(1, 2, 3), help="preset (default: the one it evolved in)")
    parser.add_argument("--steps", type=int_arg(1, 10**9), help="episode length (default: the evolved max_cycles)")
    parser.add_argument("--seed", type=int_arg(*LIMITS["seed"]), default=0)
    parser.add_argument("--out", type=Path, default=Path("team.gif"), help=".gif or .mp4")
    parser.add_argument("--frame-every", type=int_arg(1, 10**9), default=10, help="record every k-th step")
    parser.add_argument("--fps", type=int_arg(1, 1000), default=15)
    parser.add_argument("--png", type=Path, help="also save the last frame as a PNG picture")
    args = parser.parse_args(argv)
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    from .champion import load_champion
    from .replay import replay

    check_output_file(args.out, (".gif", ".mp4"), "--out")
    if args.png is not None:
        check_output_file(args.png, (".png",), "--png")
    champion = load_champion(args.champion)
    env_config = dict(champion.environment)
    if args.environment is not None:
        env_config["environment"] = args.environment
    if args.steps is not None:
        env_config["max_cycles"] = args.steps
    info, path, frames = replay(champion, env_config, args.seed, args.out, args.frame_every, args.fps,
                                png=args.png)
    print(f"{champion.experiment or 'champion'} ({champion.method}, {len(champion.morphology)} sensors) in "
          f"environment {env_config.get('environment')}: ft = {info['task_performance']:.2f}, gathered "
          f"{info['gathered_value']:.0f}/{info['total_value']:.0f} in {info['steps']} steps")
    print(f"wrote {path} ({frames} frames)")
    return 0


@command
def analyze_main(argv: list[str] | None = None) -> int:
    """``gathering-analyze RUN_DIR... --out report/``."""
    parser = ArgumentParser(
        prog="gathering-analyze",
        description="Merge MO fronts, compute selection points and SO-vs-MO tests; write Table 4, "
                    "Figures 4-6 and report.md.",
    )
    parser.add_argument("runs", nargs="+", type=Path, help="run directories written by gathering-evolve")
    parser.add_argument("--out", type=Path, default=Path("report"), help="output directory (default: report/)")
    args = parser.parse_args(argv)
    from .analysis import analyse
    from .guard import check_output_dir
    from .report import REPORT_FILES, write_report

    check_output_dir(args.out, REPORT_FILES)
    analysis = analyse(args.runs)
    path = write_report(analysis, args.out)
    print(f"{len(analysis.runs)} runs, {len(analysis.comparisons)} comparisons -> {path}")
    return 0


def run_evolve() -> None:
    sys.exit(evolve_main())


def run_replay() -> None:
    sys.exit(replay_main())


def run_analyze() -> None:
    sys.exit(analyze_main())
