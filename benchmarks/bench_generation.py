"""Seconds per generation of the trainer, serial and parallel, and where the time goes.

    python benchmarks/bench_generation.py [--genomes 20] [--trials 2] [--steps 1000] [--generations 2]

Runs the HyperNEAT-M trainer (environment 2, 20 robots) for a few generations with 1 and 2
workers on the same seed, and prints: wall-clock seconds per generation, the parallel
speed-up, the split of evaluation time between the environment step and the overhead
outside it (decoding, the team controller, bookkeeping), and the projected time of one
paper generation (150 genomes x 5 trials x 10 000 steps) on this machine.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

from evolution.experiment import load_experiment  # noqa: E402
from evolution.stats import read_stats  # noqa: E402
from evolution.trainer import Trainer  # noqa: E402


def run(workers: int, args: argparse.Namespace, root: Path) -> list[dict]:
    exp = load_experiment(None, {
        "name": f"bench-w{workers}", "generations": args.generations, "population": args.genomes,
        "trials": args.trials, "seed": 3, "environment.environment": 2,
        "environment.max_cycles": args.steps, "environment.num_robots": 20,
    })
    Trainer(exp, root / f"w{workers}", workers=workers, progress=False).run()
    return read_stats(root / f"w{workers}" / "stats.jsonl")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--genomes", type=int, default=20)
    parser.add_argument("--trials", type=int, default=2)
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--generations", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        serial = run(1, args, Path(tmp))
        parallel = run(2, args, Path(tmp))
    s_gen = sum(r["seconds"] for r in serial) / len(serial)
    p_gen = sum(r["seconds"] for r in parallel) / len(parallel)
    steps = sum(r["steps"] for r in serial) / len(serial)
    env = sum(r["seconds_env"] for r in serial)
    ctrl = sum(r["seconds_controller"] for r in serial)
    decode = sum(r["seconds_decode"] for r in serial)
    total = sum(r["seconds"] for r in serial)
    other = total - env - ctrl - decode
    print(f"reduced setting: {args.genomes} genomes x {args.trials} trials x {args.steps} steps, "
          f"environment 2, 20 robots, {args.generations} generations (mean per generation)")
    print(f"  1 worker : {s_gen:8.2f} s/generation  ({steps / s_gen:,.0f} env steps/s)")
    print(f"  2 workers: {p_gen:8.2f} s/generation  speed-up {s_gen / p_gen:.2f}x")
    print("  split of the serial run's time:")
    for name, value in (("environment step (sensing, physics, scoring)", env), ("team controller", ctrl),
                        ("decoding genomes", decode), ("bookkeeping (neat-python, stats, checkpoints)", other)):
        print(f"    {name:<48}{value:8.2f} s  {100 * value / total:5.1f} %")
    print(f"  overhead outside the env step: {100 * (total - env) / total:.1f} % of evaluation time")
    per_step = s_gen / steps
    paper_steps = 150 * 5 * 10_000
    print(f"projected paper generation (150 x 5 x 10 000 steps): {paper_steps * per_step / 60:.1f} min serial, "
          f"{paper_steps * per_step / 60 / (s_gen / p_gen):.1f} min on 2 workers "
          f"(x 250 generations = {250 * paper_steps * per_step / 3600 / (s_gen / p_gen):.0f} h)")


if __name__ == "__main__":
    main()
