"""Generation time on each evaluation backend: serial, process pool (2 workers), local Ray (2 CPUs).

    python benchmarks/bench_backends.py [--genomes 16] [--trials 1] [--steps 4000] [--generations 2]

Same seed and reduced setting on every backend (environment 2, 20 robots); prints seconds per
generation, the speed-up over serial, and Ray's overhead per task (its generation time minus
the process pool's, per genome). Evaluations of >= 1 s each are the regime the 1.7x target on
2 cores refers to: the default, 4 000 steps, takes about 1 s per genome here (the script prints it).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

from evolution.run.experiment import load_experiment  # noqa: E402
from evolution.run.stats import read_stats, without_timing  # noqa: E402
from evolution.run.trainer import Trainer  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--genomes", type=int, default=16)
    parser.add_argument("--trials", type=int, default=1)
    parser.add_argument("--steps", type=int, default=4000)
    parser.add_argument("--generations", type=int, default=2)
    args = parser.parse_args()
    exp = load_experiment(None, {
        "generations": args.generations, "population": args.genomes, "trials": args.trials, "seed": 2,
        "environment.environment": 2, "environment.max_cycles": args.steps, "environment.num_robots": 20,
    })
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for backend, workers in (("serial", 1), ("process", 2), ("ray", 2)):
            try:
                trainer = Trainer(exp, Path(tmp) / backend, workers=workers, backend=backend, progress=False)
                start = time.perf_counter()
                trainer.run()
            except ValueError as err:
                print(f"{backend}: skipped ({err})")
                continue
            records = read_stats(Path(tmp) / backend / "stats.jsonl")
            results[backend] = (sum(r["seconds"] for r in records) / len(records), without_timing(records),
                                time.perf_counter() - start)
    serial = results["serial"][0]
    print(f"{args.genomes} genomes x {args.trials} trial(s) x {args.steps} steps, environment 2, 20 robots")
    print(f"{'backend':<22}{'s/generation':>14}{'speed-up':>10}{'same statistics':>18}")
    for name, (sec, stats, _) in results.items():
        label = {"serial": "serial", "process": "process (2 workers)", "ray": "ray (2 CPUs)"}[name]
        print(f"{label:<22}{sec:>14.2f}{serial / sec:>9.2f}x{str(stats == results['serial'][1]):>18}")
    per_eval = serial / args.genomes
    print(f"one evaluation takes {per_eval:.2f} s serially")
    if "ray" in results and "process" in results:
        overhead = (results["ray"][0] - results["process"][0]) / args.genomes
        print(f"ray overhead vs the process pool: {overhead * 1000:+.0f} ms per task "
              f"(Ray start-up, excluded above: {results['ray'][2] - sum([results['ray'][0]] * args.generations):.1f} s)")


if __name__ == "__main__":
    main()
