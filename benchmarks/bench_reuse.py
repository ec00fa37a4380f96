"""What reusing identical teams saves: the same run with and without ``evolution.run.reuse``.

    python benchmarks/bench_reuse.py [--preset S1-original] [--genomes 150] [--generations 8]
                                     [--steps 1000] [--workers 2]

Runs the preset twice on the same seed, cut to ``--steps`` per episode (the share of genomes
that decode to an already scored team does not depend on the episode length), once simulating
every genome and once reusing, and prints per generation the distinct teams, the steps
simulated and the seconds, then the totals. Both runs must give the same statistics (``steps``
and timings aside); the script checks that and says so.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

from evolution.guard import ArgumentParser, command, int_arg  # noqa: E402
from evolution.run.experiment import load_experiment  # noqa: E402
from evolution.run.presets import resolve_preset  # noqa: E402
from evolution.run.stats import read_stats, without_work  # noqa: E402
from evolution.run.trainer import Trainer  # noqa: E402


def run(args: argparse.Namespace, out: Path, reuse: bool) -> list[dict]:
    path, overrides = resolve_preset(args.preset)
    exp = load_experiment(path, {**overrides, "population": args.genomes, "generations": args.generations,
                                 "environment.max_cycles": args.steps})
    Trainer(exp, out, workers=args.workers, progress=False, reuse=reuse).run()
    return read_stats(out / "stats.jsonl")


@command
def main(argv: list[str] | None = None) -> int:
    parser = ArgumentParser(prog="bench_reuse.py", description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="S1-original")
    parser.add_argument("--genomes", type=int_arg(2, 10_000), default=150)
    parser.add_argument("--generations", type=int_arg(1, 10_000), default=8)
    parser.add_argument("--steps", type=int_arg(1, 10**7), default=1000)
    parser.add_argument("--workers", type=int_arg(1, 256), default=2)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        warm = argparse.Namespace(**{**vars(args), "genomes": 2, "generations": 1, "steps": 10})
        run(warm, Path(tmp) / "warm-up", reuse=False)  # compiled kernels and worker start-up, timed in neither
        every = run(args, Path(tmp) / "every", reuse=False)
        reused = run(args, Path(tmp) / "reuse", reuse=True)
    same = without_work(every) == without_work(reused)
    print(f"{args.preset}: {args.genomes} genomes x {args.steps} steps, {args.generations} generations, "
          f"{args.workers} workers")
    print(f"{'gen':>4} {'steps, every genome':>20} {'steps, reused':>14} {'s, every':>9} {'s, reused':>10}")
    for a, b in zip(every, reused):
        print(f"{a['generation']:>4} {a['steps']:>20} {b['steps']:>14} {a['seconds']:>9.1f} {b['seconds']:>10.1f}")
    sa, sb = sum(r["steps"] for r in every), sum(r["steps"] for r in reused)
    ta, tb = sum(r["seconds"] for r in every), sum(r["seconds"] for r in reused)
    print(f"total: steps {sa} -> {sb} ({sb / sa:.0%}), seconds {ta:.1f} -> {tb:.1f} ({ta / tb:.2f}x faster)")
    print("statistics of the two runs (steps and timings aside): " + ("identical" if same else "DIFFERENT"))
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
