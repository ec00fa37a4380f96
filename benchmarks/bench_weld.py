"""What the weld's seat is worth: the scripted wander team with the weld seating the robot
(the default, as in the original) and welding it where it stands, on the same worlds.

    python benchmarks/bench_weld.py [--worlds 16] [--steps 10000] [--environments 1 2 3]

Prints, per environment, the mean ft +- standard error of ``wander`` (evolution.policies)
over the same ``--worlds`` layouts (seeds 0..worlds-1) with ``weld_seat`` on and off, and the
paired difference. The figures in docs/environment.md come from this script.
"""

from __future__ import annotations

import argparse
import os

import numpy as np

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

from evolution.compare import run_episode  # noqa: E402
from evolution.policies import make_policy  # noqa: E402
from gathering_env import parallel_env  # noqa: E402


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--worlds", type=int, default=16)
    p.add_argument("--steps", type=int, default=10_000)
    p.add_argument("--environments", type=int, nargs="+", default=[1, 2, 3])
    args = p.parse_args()
    print(f"wander on {args.worlds} paired layouts x {args.steps} steps; ft mean +- SE")
    for environment in args.environments:
        ft = {}
        for seat in (True, False):
            env = parallel_env(environment=environment, max_cycles=args.steps, weld_seat=seat)
            policy = make_policy("wander")
            ft[seat] = np.array([run_episode(env, policy, s)["ft"] for s in range(args.worlds)])
        diff = ft[True] - ft[False]
        se = lambda v: v.std(ddof=1) / np.sqrt(len(v))  # noqa: E731
        print(f"environment {environment}: seated {ft[True].mean():6.2f} +- {se(ft[True]):4.2f}   "
              f"in place {ft[False].mean():6.2f} +- {se(ft[False]):4.2f}   "
              f"difference {diff.mean():+6.2f} +- {se(diff):4.2f}", flush=True)


if __name__ == "__main__":
    main()
