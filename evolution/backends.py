"""Where genomes are evaluated: in this process (``serial``) or a local process pool.

Both return results in the order of the genomes they were given, and every result
depends only on (genome, run seed, generation), so serial and parallel runs of the same
seed give identical statistics. Each worker builds its environment once and reuses it.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any

from .evaluate import Evaluation, evaluate


@dataclass(frozen=True)
class EvalContext:
    """What every evaluation of a run shares (pickled once per worker)."""

    neat_config: Any
    env_config: dict[str, Any]
    trials: int
    seed: int
    method: str
    substrate: Any = None
    extra: dict[str, Any] = field(default_factory=dict)

    def evaluate(self, genome: Any, generation: int) -> Evaluation:
        return evaluate(genome, self.neat_config, self.env_config, trials=self.trials, seed=self.seed,
                        generation=generation, method=self.method, substrate=self.substrate)


class SerialEvaluator:
    """Evaluate genomes one after another in this process."""

    name = "serial"

    def __init__(self, context: EvalContext) -> None:
        self.context = context

    def map(self, genomes: list[Any], generation: int) -> list[Evaluation]:
        return [self.context.evaluate(g, generation) for g in genomes]

    def close(self) -> None:
        pass


_WORKER_CONTEXT: EvalContext | None = None


def _init_worker(context: EvalContext) -> None:
    global _WORKER_CONTEXT
    _WORKER_CONTEXT = context
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")


def _evaluate_in_worker(args: tuple[Any, int]) -> Evaluation:
    genome, generation = args
    assert _WORKER_CONTEXT is not None, "worker not initialised"
    return _WORKER_CONTEXT.evaluate(genome, generation)


class ProcessEvaluator:
    """Evaluate genomes on ``workers`` local processes (results in submission order)."""

    name = "process"

    def __init__(self, context: EvalContext, workers: int) -> None:
        if workers < 1:
            raise ValueError(f"workers={workers}; allowed: >= 1")
        self.context = context
        self.workers = workers
        ctx = multiprocessing.get_context("fork" if hasattr(os, "fork") else "spawn")
        self._pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx,
                                         initializer=_init_worker, initargs=(context,))

    def map(self, genomes: list[Any], generation: int) -> list[Evaluation]:
        return list(self._pool.map(_evaluate_in_worker, [(g, generation) for g in genomes], chunksize=1))

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


def make_evaluator(context: EvalContext, workers: int | None) -> SerialEvaluator | ProcessEvaluator:
    """``workers`` = 1 -> serial; None -> all local cores; N > 1 -> a pool of N processes."""
    if workers is None:
        workers = os.cpu_count() or 1
    if workers <= 1:
        return SerialEvaluator(context)
    return ProcessEvaluator(context, workers)
