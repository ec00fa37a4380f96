"""What the compiled kernels cost before they run: compilation and cache loading.

    python benchmarks/bench_jit.py

Each measurement is a fresh Python process that imports ``gathering_env``, builds the
default world and takes one step (so every kernel is compiled or loaded):

* cold cache: numba compiles every kernel (``NUMBA_CACHE_DIR`` points to an empty folder);
* warm cache: the same folder again, now holding the machine code;
* numpy kernel: the same with ``kernel="numpy"`` (no numba at all), for reference.

It then starts a process pool (the trainer's ``fork``, and ``spawn``) whose workers step a
world, and reports numba's own cache counters in each worker: hits > 0 and misses = 0 mean
the worker loaded the kernels from disk instead of compiling them.
"""

from __future__ import annotations

import multiprocessing
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor

SNIPPET = """
import time
t0 = time.perf_counter()
import numpy as np
from gathering_env import parallel_env
t1 = time.perf_counter()
env = parallel_env(kernel={kernel!r})
env.reset(seed=0)
env.step_batch(np.zeros((20, 2)))
t2 = time.perf_counter()
print(f"{{t1 - t0:.3f}} {{t2 - t1:.3f}}")
"""


def timed(kernel: str, cache_dir: str) -> tuple[float, float, float]:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    start = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", SNIPPET.format(kernel=kernel)], env=env, check=True,
                         capture_output=True, text=True).stdout.split()
    return time.perf_counter() - start, float(out[0]), float(out[1])


def worker_stats(_: int) -> tuple[int, dict[str, tuple[int, int]]]:
    import numpy as np

    from gathering_env import parallel_env
    from gathering_env.compiled import kernels

    env = parallel_env()
    env.reset(seed=0)
    env.step_batch(np.zeros((20, 2)))
    stats = {}
    for name in ("drive", "settle", "sense"):
        dispatcher = getattr(kernels, name)
        stats[name] = (sum(dispatcher.stats.cache_hits.values()), sum(dispatcher.stats.cache_misses.values()))
    return os.getpid(), stats


def main() -> None:
    with tempfile.TemporaryDirectory() as cache:
        rows = [("cold cache (compiles every kernel)", timed("compiled", cache)),
                ("warm cache (loads machine code)", timed("compiled", cache)),
                ("numpy kernel (no numba)", timed("numpy", cache))]
        print(f"{'fresh process':<38}{'total s':>9}{'import s':>10}{'first step s':>14}")
        for name, (total, imp, first) in rows:
            print(f"{name:<38}{total:>9.2f}{imp:>10.2f}{first:>14.2f}")
        os.environ["NUMBA_CACHE_DIR"] = cache
        for method in ("fork", "spawn"):
            ctx = multiprocessing.get_context(method)
            with ProcessPoolExecutor(2, mp_context=ctx) as pool:
                for pid, stats in pool.map(worker_stats, range(2)):
                    text = ", ".join(f"{k} {h} hit/{m} miss" for k, (h, m) in stats.items())
                    print(f"{method} worker {pid}: {text}")


if __name__ == "__main__":
    main()
