"""Command-line entry points: ``gathering-evolve``, ``gathering-replay``, ``gathering-analyze``.

Errors in options and input files (experiment TOML, neat config, checkpoint, champion) end
with a one-line message naming the option, file or field and exit status 2 (``evolution.guard``);
nothing already written is touched. See docs/guarantees.md.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from evolution.guard import (
    ArgumentParser,
    UsageError,
    check_output_file,
    command,
    int_arg,
    with_world_settings,
    world_setting,
)
from evolution.run.experiment import LIMITS, METHODS, load_experiment
from evolution.run.presets import (
    is_preset_name,
    neat_config_names,
    preset_description,
    preset_names,
    preset_text,
    protocol_preset_description,
    protocol_preset_names,
    resolve_preset,
)
from evolution.run.protocol import DESCRIPTIONS, PROTOCOLS, newest_version
from gathering_env.config import ENVIRONMENT_PRESETS, INT_RANGES

MAX_WORKERS = max(4, 4 * (os.cpu_count() or 1))
"""Most evaluation processes ``--workers`` may ask for: four per core (each worker holds its own
environment, so more processes than cores only add memory)."""


def _list_presets() -> int:
    print(f"# protocol \"paper\": {DESCRIPTIONS['paper']}")
    for name in preset_names():
        print(f"{name:22s} {preset_description(name)}")
    for protocol in PROTOCOLS[1:]:
        print(f"# protocol \"{protocol}\" (version {newest_version(protocol)}; protocol_version picks another): "
              f"{DESCRIPTIONS[protocol]}")
        for name in protocol_preset_names():
            if name.endswith(f"-{protocol}"):
                print(f"{name:22s} {protocol_preset_description(name)}")
    print("# neat-python configs")
    for name in neat_config_names():
        print(f"{name:22s} {preset_description(name)}")
    return 0


def _dump_preset(name: str) -> int:
    sys.stdout.write(preset_text(name))
    return 0


@command
def evolve_main(argv: list[str] | None = None) -> int:
    """``gathering-evolve [PRESET | EXPERIMENT.toml] [overrides] --out RUN_DIR``."""
    args = _evolve_parser().parse_args(argv)
    if args.ray_address is not None and args.backend != "ray":
        raise UsageError(f"--ray-address {args.ray_address}: only used with --backend ray (the backend is "
                         f"{args.backend}); allowed: add --backend ray, or drop --ray-address")
    if args.list:
        return _list_presets()
    if args.dump is not None:
        try:
            return _dump_preset(args.dump)
        except ValueError as err:
            raise UsageError(f"--dump {err}") from None
    overrides = _evolve_overrides(args)
    resume = args.resume is not None or args.resume_from is not None
    out, experiment = _run_dir_and_experiment(args, overrides, resume)
    from evolution.run.trainer import Trainer

    trainer = Trainer(experiment, out, workers=args.workers, resume=resume,
                      resume_from=args.resume_from, progress=not args.no_progress,
                      backend=args.backend, ray_address=args.ray_address, max_retries=args.max_retries,
                      overrides=overrides, rebuild_from=args.rebuild_from)
    try:
        result = trainer.run()
    except KeyboardInterrupt:
        print(f"\ninterrupted: resume with gathering-evolve --resume {out}", file=sys.stderr)
        return 130
    if result.interrupted:
        print(f"stopped after {result.generations} generations; resume with: gathering-evolve --resume {out}")
        return 130
    return _report_run(result, out, trainer.experiment.generations)


def _evolve_parser() -> ArgumentParser:
    """The ``gathering-evolve`` command line."""
    from gathering_env import __version__

    parser = ArgumentParser(
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
    parser.add_argument("--workers", type=int_arg(1, MAX_WORKERS), default=None,
                        help="evaluation processes (default: all cores; 1 = serial)")
    parser.add_argument("--resume", nargs="?", const=True, type=Path, metavar="RUN_DIR",
                        help="continue a run from its newest readable checkpoint: RUN_DIR (or --out); without "
                             "an experiment file the run's own experiment is used")
    parser.add_argument("--resume-from", type=Path, metavar="CHECKPOINT",
                        help="continue from this checkpoint, in its run directory or into a new --out")
    parser.add_argument("--rebuild-from", type=Path, metavar="RECORD",
                        help="a new run of the same experiment that takes the scores of the generations recorded "
                             "in RECORD (a run or evidence folder) instead of simulating them, then goes on "
                             "(docs/evolution.md, 'Rebuilding a run')")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--backend", choices=("serial", "process", "ray"), default="process",
                        help="where genomes are evaluated (default: process pool)")
    parser.add_argument("--ray-address", help="join this Ray cluster (e.g. 'auto' or 'head:6379') instead of a local Ray")
    parser.add_argument("--max-retries", type=int_arg(0, 100), default=2,
                        help="retries of a failing evaluation (default 2)")
    group = parser.add_argument_group("overrides of the experiment file")
    group.add_argument("--name", help="the run's name ([experiment] name; default run folder runs/<name>-seed<seed>)")
    group.add_argument("--protocol", choices=PROTOCOLS,
                       help="a named bundle of world and method options (docs/fidelity.md); "
                            "'original' = the 2018 code behind the published figures")
    group.add_argument("--method", choices=METHODS, help="hyperneat-m (CPPN) or neat-m (direct encoding)")
    group.add_argument("--objectives", help="comma-separated, all maximised: task (ft), morphology (simplicity C), "
                                             "controller (100 - links); more than one = NEAT-MODS")
    group.add_argument("--seed", type=int_arg(*LIMITS["seed"]),
                       help="run seed: every random choice of the run flows from it")
    group.add_argument("--generations", type=int_arg(*LIMITS["generations"]), help="generations to evolve")
    group.add_argument("--population", type=int_arg(*LIMITS["population"]), help="genomes per generation")
    group.add_argument("--trials", type=int_arg(*LIMITS["trials"]),
                       help="episodes per genome; its fitness is their mean ft")
    group.add_argument("--environment", type=int, choices=tuple(ENVIRONMENT_PRESETS),
                       help="environment preset 1, 2 or 3 (paper Table 2)")
    group.add_argument("--steps", type=int_arg(*INT_RANGES["max_cycles"]), help="steps per trial (max_cycles)")
    group.add_argument("--robots", type=int_arg(*INT_RANGES["num_robots"]), help="team size (num_robots)")
    return parser


def _evolve_overrides(args) -> dict:
    """The command line's overrides of the experiment file (``None``: not given); resolves a preset name."""
    preset_overrides: dict = {}
    if args.experiment is not None:
        if is_preset_name(args.experiment):
            args.experiment, preset_overrides = resolve_preset(args.experiment)
        else:
            args.experiment = Path(args.experiment)
    return {
        **preset_overrides,
        "protocol": args.protocol if args.protocol is not None else preset_overrides.get("protocol"),
        "name": args.name if args.name is not None else preset_overrides.get("name"), "method": args.method,
        "seed": args.seed, "generations": args.generations,
        "population": args.population, "trials": args.trials,
        "objectives": [o.strip() for o in args.objectives.split(",")] if args.objectives is not None else None,
        "environment.environment": args.environment, "environment.max_cycles": args.steps,
        "environment.num_robots": args.robots,
    }


def _run_dir_and_experiment(args, overrides: dict, resume: bool):
    """The run directory and the experiment (``None``: the resumed run's own) the arguments name."""
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
        from evolution.run.rundir import run_dir_of

        out = run_dir_of(args.resume_from)
        if out is None:
            raise UsageError(f"--resume-from {args.resume_from}: not in a run's checkpoints/ folder; allowed: "
                             "add --out NEW_DIR to continue it there")
    if resume and out is None:
        raise UsageError("--resume: which run? allowed: --resume RUN_DIR")
    if resume and args.experiment is None:
        experiment = None  # the run's own experiment, from its checkpoint
    elif args.rebuild_from is not None and args.experiment is None:
        from evolution.run.rebuild import experiment_of_record

        experiment = experiment_of_record(args.rebuild_from, overrides)  # the record's own experiment
        out = out or Path("runs") / f"{experiment.name}-seed{experiment.seed}"
    else:
        experiment = load_experiment(args.experiment, overrides)
        out = out or Path("runs") / f"{experiment.name}-seed{experiment.seed}"
    return out, experiment


def _report_run(result, out: Path, generations: int) -> int:
    """Print how a run that was not interrupted ended."""
    if result.already_finished:
        why = "converged" if result.converged else f"reached its {generations} generations"
        print(f"{out}: already finished ({why}: {result.generations} generations, best ft {result.best_task:.2f}); "
              "nothing to evolve (raise --generations to continue it)")
        return 0
    status = "converged" if result.converged else "finished"
    print(f"{status}: {result.generations} generations, best ft {result.best_task:.2f}")
    if result.reused:
        print(f"{result.reused} of {result.asked} genomes decoded to a team already scored on the same episodes "
              "and took its scores (not simulated again)")
    print(f"run directory: {result.run_dir}  (stats.jsonl, stats.csv, stats.png, champion.json, checkpoints/)")
    return 0


_REPLAY_FLAGS = {"size_px": "--size", "cones": "--cones", "view": "--view", "trail": "--trail",
                 "panel": "--no-panel", "min_robot_px": "--min-robot-px", "strip": "--strip",
                 "png": "--png", "sensors_png": "--sensors-png"}
"""Render option (and replay argument) -> the ``gathering-replay`` flag that sets it."""


@command
def replay_main(argv: list[str] | None = None) -> int:
    """``gathering-replay CHAMPION.json|POLICY [--environment N] [--out team.gif] [render options]``."""
    from evolution.policies import POLICY_NAMES

    parser = ArgumentParser(prog="gathering-replay",
                            description="Replay an evolved team or any named policy and save the episode as GIF/MP4 "
                                        "(pictures: --png, --strip, --sensors-png; see docs/rendering.md).")
    parser.add_argument("team", help=f"champion JSON written by gathering-evolve, or a policy name: {POLICY_NAMES}")
    parser.add_argument("--environment", type=int, choices=tuple(ENVIRONMENT_PRESETS),
                        help="preset (default: the one it evolved or was trained in; else 2)")
    parser.add_argument("--steps", type=int_arg(*INT_RANGES["max_cycles"]),
                        help="episode length (default: the evolved or trained max_cycles; else 10 000)")
    parser.add_argument("--seed", type=int_arg(*LIMITS["seed"]), default=0,
                        help="the episode's seed (default 0): an episode the team was not trained on")
    parser.add_argument("--world", type=world_setting, action="append", default=[], metavar="KEY=VALUE",
                        help="set one world parameter (a WorldConfig field) over the team's own world; "
                             "VALUE is TOML or a bare string (repeat)")
    parser.add_argument("--out", type=Path, default=Path("team.gif"), help=".gif or .mp4")
    parser.add_argument("--frame-every", type=int_arg(1, 10**9), default=10, help="record every k-th step")
    parser.add_argument("--fps", type=int_arg(1, 1000), default=15, help="frames per second of the video (default 15)")
    parser.add_argument("--png", type=Path, help="also save the last frame (or with --strip a film strip) as PNG")
    look = parser.add_argument_group("what the frames show (docs/rendering.md)")
    look.add_argument("--cones", help="whose sensor cones: auto (default), all, none or robot indices like 0,3")
    look.add_argument("--view", help="full (default), zone, or follow:K to follow robot K")
    look.add_argument("--size", type=int, help="side of the arena view in pixels (default 640)")
    look.add_argument("--trail", type=int, help="draw each robot's path over its last K steps (default 0)")
    look.add_argument("--no-panel", action="store_true", help="no information panel beside the arena")
    look.add_argument("--min-robot-px", type=int, help="smallest robot radius in pixels (default 4)")
    look.add_argument("--strip", help="with --png: film strip of the frames at these steps, e.g. 0,600,1200")
    look.add_argument("--sensors-png", type=Path, help="also save the team's sensor layout (like the paper's Figure 3)")
    args = parser.parse_args(argv)
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    from evolution.policies import is_policy_name, make_policy
    from evolution.replay import replay, unseen_note
    from evolution.run.champion import load_champion
    from gathering_env.render import RenderOptionError

    render_options = {name: value for name, value in (
        ("cones", args.cones), ("view", args.view), ("size_px", args.size), ("trail", args.trail),
        ("min_robot_px", args.min_robot_px)) if value is not None}
    if args.no_panel:
        render_options["panel"] = False
    check_output_file(args.out, (".gif", ".mp4"), "--out")
    if args.png is not None and args.sensors_png is not None and args.png.resolve() == args.sensors_png.resolve():
        raise UsageError(f"--sensors-png {args.sensors_png}: the same file as --png (one would overwrite the "
                         "other); allowed: two different file names")
    for picture, flag in ((args.png, "--png"), (args.sensors_png, "--sensors-png")):
        if picture is not None:
            check_output_file(picture, (".png",), flag)
    if is_policy_name(args.team):
        team = make_policy(args.team)
        env_config, label = dict(team.environment or {}), f"{team.name} ({len(team.morphology)} sensors)"
    else:
        if not Path(args.team).exists():
            raise UsageError(f"{args.team}: neither a champion file nor a policy name; allowed: a champion JSON "
                             f"written by gathering-evolve, or {POLICY_NAMES}")
        team = load_champion(Path(args.team))
        env_config = dict(team.environment)
        label = f"{team.experiment or 'champion'} ({team.method}, {len(team.morphology)} sensors)"
    if args.environment is not None:
        env_config["environment"] = args.environment
    if args.steps is not None:
        env_config["max_cycles"] = args.steps
    env_config = with_world_settings(env_config, args.world, ("environment", "max_cycles"))
    try:
        info, path, frames = replay(team, env_config, args.seed, args.out, args.frame_every, args.fps,
                                    png=args.png, render_options=render_options, strip=args.strip,
                                    sensors_png=args.sensors_png)
    except RenderOptionError as err:
        raise UsageError(f"{_REPLAY_FLAGS.get(err.option, err.option)}: {err.problem}; allowed: {err.allowed}") from None
    print(f"{label} in environment {env_config.get('environment', 2)}: ft = {info['task_performance']:.2f}, gathered "
          f"{info['gathered_value']:.0f}/{info['total_value']:.0f} in {info['steps']} steps")
    if not is_policy_name(args.team):
        print(unseen_note(team, env_config, args.seed, info["task_performance"]))
    print(f"wrote {path} ({frames} frames)")
    for picture in (args.png, args.sensors_png):
        if picture is not None:
            print(f"wrote {picture}")
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
    from evolution.analysis.reevaluate import REEVALUATE_TRIALS
    from evolution.run.backends import BACKENDS

    parser.add_argument("--reevaluate", type=int_arg(0, 100_000), default=REEVALUATE_TRIALS, metavar="K",
                        help="re-run every SO champion and MO front genome K times on held-out seeds and report "
                             f"those scores (default {REEVALUATE_TRIALS}; cached in each run directory); "
                             "0 = use the training scores")
    parser.add_argument("--workers", type=int_arg(1, MAX_WORKERS), default=None,
                        help="evaluation processes for --reevaluate (default: all cores; 1 = serial)")
    parser.add_argument("--backend", choices=BACKENDS, default="process",
                        help="where --reevaluate runs (default: process pool)")
    args = parser.parse_args(argv)
    from evolution.analysis.fronts import analyse, nothing_to_compare
    from evolution.analysis.report import REPORT_FILES, write_report
    from evolution.guard import check_output_dir

    check_output_dir(args.out, REPORT_FILES)
    analysis = analyse(args.runs, reevaluate=args.reevaluate, workers=args.workers, backend=args.backend)
    path = write_report(analysis, args.out)
    print(f"{len(analysis.runs)} runs, {len(analysis.comparisons)} comparisons -> {path}")
    untested = sorted({c.untested for c in analysis.comparisons if c.untested})
    for line in filter(None, [nothing_to_compare(analysis), *untested]):
        print(line)
    print(f"ft used: {analysis.scores}")
    return 0


def run_evolve() -> None:
    sys.exit(evolve_main())


def run_replay() -> None:
    sys.exit(replay_main())


def run_analyze() -> None:
    sys.exit(analyze_main())
