"""Seconds per generation of the trainer, serial and parallel, and where the time goes.

    python benchmarks/bench_generation.py [--genomes 20] [--trials 5] [--steps 1000] [--generations 2]
                                          [--kernels compiled,numpy]

Runs the HyperNEAT-M trainer (environment 2, 20 robots) for a few generations with 1 and 2
workers on the same seed, once per simulation kernel, and prints: wall-clock seconds per
generation, the parallel speed-up, the split of evaluation time between the simulation
and the overhead outside it (decoding, the team controller, bookkeeping), and the
projected time of one paper generation (150 genomes x 5 trials x 10 000 steps) on this
machine. A genome's trials run as one batch of worlds, so ``--trials 5`` (the paper's)
measures the batch width a paper generation uses.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

from evolution.run.experiment import load_experiment  # noqa: E402
from evolution.run.stats import read_stats  # noqa: E402
from evolution.run.trainer import Trainer  # noqa: E402


def run(workers: int, kernel: str, args: argparse.Namespace, root: Path) -> list[dict]:
    exp = load_experiment(None, {
        "name": f"bench-w{workers}", "generations": args.generations, "population": args.genomes,
        "trials": args.trials, "seed": 3, "environment.environment": 2,
        "environment.max_cycles": args.steps, "environment.num_robots": 20, "environment.kernel": kernel,
    })
    out = root / f"{kernel}-w{workers}"
    Trainer(exp, out, workers=workers, progress=False).run()
    return read_stats(out / "stats.jsonl")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--genomes", type=int, default=20)
    parser.add_argument("--trials", type=int, default=5)
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--generations", type=int, default=2)
    parser.add_argument("--kernels", default="compiled,numpy", help="comma-separated simulation kernels")
    args = parser.parse_args()
    for kernel in [k.strip() for k in args.kernels.split(",") if k.strip()]:
        report(kernel, args)


def report(kernel: str, args: argparse.Namespace) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        serial = run(1, kernel, args, Path(tmp))
        parallel = run(2, kernel, args, Path(tmp))
    s_gen = sum(r["seconds"] for r in serial) / len(serial)
    p_gen = sum(r["seconds"] for r in parallel) / len(parallel)
    steps = sum(r["steps"] for r in serial) / len(serial)
    env = sum(r["seconds_env"] for r in serial)
    ctrl = sum(r["seconds_controller"] for r in serial)
    decode = sum(r["seconds_decode"] for r in serial)
    total = sum(r["seconds"] for r in serial)
    other = total - env - ctrl - decode
    print(f"kernel {kernel!r}: {args.genomes} genomes x {args.trials} trials x {args.steps} steps, "
          f"environment 2, 20 robots, {args.generations} generations (mean per generation)")
    print(f"  1 worker : {s_gen:8.2f} s/generation  ({steps / s_gen:,.0f} env steps/s)")
    print(f"  2 workers: {p_gen:8.2f} s/generation  speed-up {s_gen / p_gen:.2f}x")
    print("  split of the serial run's time:")
    for name, value in (("simulation (physics, sensing, heuristics, scoring)", env), ("team controller", ctrl),
                        ("decoding genomes", decode), ("bookkeeping (neat-python, stats, checkpoints)", other)):
        print(f"    {name:<52}{value:8.2f} s  {100 * value / total:5.1f} %")
    print(f"  overhead outside the simulation: {100 * (total - env) / total:.1f} % of evaluation time")
    per_step = s_gen / steps
    paper_steps = 150 * 5 * 10_000
    print(f"  projected paper generation (150 x 5 x 10 000 steps): {paper_steps * per_step / 60:.1f} min serial, "
          f"{paper_steps * per_step / 60 / (s_gen / p_gen):.1f} min on 2 workers "
          f"(x 250 generations = {250 * paper_steps * per_step / 3600 / (s_gen / p_gen):.0f} h)")


if __name__ == "__main__":
    main()
