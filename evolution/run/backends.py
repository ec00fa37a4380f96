"""Where genomes are evaluated: ``serial``, a local ``process`` pool, or a ``ray`` cluster.

Every backend returns results in the order of the genomes it was given, and every result
depends only on (genome, run seed, generation), so all backends give identical statistics
for the same seed. Each worker builds its environment once and reuses it
(``evolution.run.evaluate`` keeps one env per process).

Faults: an evaluation that raises, or a worker process that dies, is retried up to
``max_retries`` times; a genome that keeps failing gets the worst objectives
(``Evaluation.failure``) and its error is reported with the genome id, and the run goes on.
"""

from __future__ import annotations

import multiprocessing
import os
import re
import signal
import socket
import tempfile
import threading
import time
import traceback
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any, Protocol

from evolution.run.evaluate import Evaluation, evaluate
from evolution.run.lock import drop_inherited_locks
from evolution.run.reaper import start_reaper, stop_reaper

BACKENDS = ("serial", "process", "ray")


@dataclass(frozen=True)
class EvalContext:
    """What every evaluation of a run shares (sent once per worker)."""

    neat_config: Any
    env_config: dict[str, Any]
    trials: int
    seed: int
    method: str
    substrate: Any = None
    extra: dict[str, Any] = field(default_factory=dict)
    layout: str = "per_trial"
    complexity: str = "paper"

    def evaluate(self, genome: Any, generation: int) -> Evaluation:
        return evaluate(genome, self.neat_config, self.env_config, trials=self.trials, seed=self.seed,
                        generation=generation, method=self.method, substrate=self.substrate,
                        layout=self.layout, complexity=self.complexity)


class Evaluator(Protocol):
    name: str
    failures: list[tuple[int, str]]

    def map(self, genomes: list[Any], generation: int) -> list[Evaluation]: ...

    def close(self) -> None: ...


def _describe(err: BaseException) -> str:
    return "".join(traceback.format_exception_only(type(err), err)).strip()


class SerialEvaluator:
    """Evaluate genomes one after another in this process."""

    name = "serial"

    def __init__(self, context: EvalContext, max_retries: int = 2) -> None:
        self.context = context
        self.max_retries = max_retries
        self.failures: list[tuple[int, str]] = []

    def map(self, genomes: list[Any], generation: int) -> list[Evaluation]:
        results = []
        for g in genomes:
            for attempt in range(self.max_retries + 1):
                try:
                    results.append(self.context.evaluate(g, generation))
                    break
                except Exception as err:  # noqa: BLE001 - any evaluation error is retried, then recorded
                    if attempt == self.max_retries:
                        self.failures.append((g.key, _describe(err)))
                        results.append(Evaluation.failure(_describe(err)))
        return results

    def close(self) -> None:
        pass


_WORKER_CONTEXT: EvalContext | None = None
ORPHAN_POLL_SECONDS = 0.5
"""How often a pool worker checks that the process that started it is still alive."""


def _exit_when_orphaned(parent: int) -> None:
    """Watchdog of a pool worker: exit as soon as ``parent`` is gone (e.g. SIGKILLed)."""
    while True:
        if os.getppid() != parent:
            os._exit(1)
        time.sleep(ORPHAN_POLL_SECONDS)


def _init_worker(context: EvalContext, parent: int) -> None:
    global _WORKER_CONTEXT
    _WORKER_CONTEXT = context
    drop_inherited_locks()  # the run directory's lock stays the trainer's alone
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    # Forked workers inherit the trainer's Python signal handlers: drop them. Ctrl-C reaches
    # the whole process group and the trainer decides what to do, so workers ignore SIGINT;
    # SIGTERM ends a worker at once.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    # A trainer killed with SIGKILL cannot shut its pool down: the workers notice on their own.
    threading.Thread(target=_exit_when_orphaned, args=(parent,), name="orphan-watchdog", daemon=True).start()


def _evaluate_in_worker(genome: Any, generation: int, attempt: int) -> Evaluation:
    assert _WORKER_CONTEXT is not None, "worker not initialised"
    os.environ["GATHERING_EVAL_ATTEMPT"] = str(attempt)  # visible to fault-injection tests
    return _WORKER_CONTEXT.evaluate(genome, generation)


class ProcessEvaluator:
    """Evaluate genomes on ``workers`` local processes.

    A worker that dies breaks the pool: the pool is rebuilt, and the genomes that were in it
    are retried one at a time, so that a death counts as an attempt of the genome that caused
    it and of no other.
    """

    name = "process"

    def __init__(self, context: EvalContext, workers: int, max_retries: int = 2) -> None:
        if workers < 1:
            raise ValueError(f"workers={workers}; allowed: >= 1")
        self.context = context
        self.workers = workers
        self.max_retries = max_retries
        self.failures: list[tuple[int, str]] = []
        self._ctx = multiprocessing.get_context("fork" if hasattr(os, "fork") else "spawn")
        self._pool = self._new_pool()

    def _new_pool(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(max_workers=self.workers, mp_context=self._ctx,
                                   initializer=_init_worker, initargs=(self.context, os.getpid()))

    def map(self, genomes: list[Any], generation: int) -> list[Evaluation]:
        results: list[Evaluation | None] = [None] * len(genomes)
        attempts = [0] * len(genomes)
        isolated: set[int] = set()   # caught in a broken pool: retried one at a time
        pending = list(range(len(genomes)))

        def charge(i: int, error: str, retry: list[int]) -> None:
            attempts[i] += 1
            if attempts[i] > self.max_retries:
                self.failures.append((genomes[i].key, error))
                results[i] = Evaluation.failure(error)
            else:
                retry.append(i)

        while pending:
            retry: list[int] = []
            together = [i for i in pending if i not in isolated]
            futures = {i: self._pool.submit(_evaluate_in_worker, genomes[i], generation, attempts[i])
                       for i in together}
            broken = False
            for i, fut in futures.items():
                try:
                    results[i] = fut.result()
                except BrokenProcessPool:
                    # which genome killed the worker is unknown: charge nobody, isolate them all
                    broken = True
                    isolated.add(i)
                    retry.append(i)
                except Exception as err:  # noqa: BLE001 - evaluation errors come back from the worker
                    charge(i, _describe(err), retry)
            if broken:
                self._renew_pool()
            for i in (i for i in pending if i in isolated and i not in futures):
                try:
                    results[i] = self._pool.submit(_evaluate_in_worker, genomes[i], generation, attempts[i]).result()
                except BrokenProcessPool as err:
                    self._renew_pool()
                    charge(i, f"worker process died: {_describe(err)}", retry)
                except Exception as err:  # noqa: BLE001
                    charge(i, _describe(err), retry)
            pending = retry
        return results  # type: ignore[return-value]

    def _renew_pool(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)
        self._pool = self._new_pool()

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)


class RayEvaluator:
    """Evaluate genomes as Ray tasks (a local Ray, or a cluster at ``address``).

    The context is put into Ray's object store once; each task resolves it and evaluates one
    genome; Ray retries tasks whose worker died and, with ``retry_exceptions``, tasks that
    raised, up to ``max_retries`` times. Results are collected in submission order.
    """

    name = "ray"

    def __init__(self, context: EvalContext, address: str | None = None, num_cpus: int | None = None,
                 max_retries: int = 2) -> None:
        try:
            import ray
        except ImportError:
            raise ValueError("the ray backend needs Ray: pip install 'gathering-evolution[ray]' "
                             "(or pip install ray)") from None
        self._ray = ray
        self.failures: list[tuple[int, str]] = []
        self._own = not ray.is_initialized()
        self._reaper = None
        if self._own:
            kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                                      "configure_logging": False}
            if address:
                _check_reachable(address)
                kwargs["address"] = address
            else:
                if num_cpus:
                    kwargs["num_cpus"] = num_cpus
                # a local Ray's processes must not outlive this trainer, even a SIGKILLed one
                self._reaper = start_reaper()
            started = time.time()
            try:
                ray.init(**kwargs)
            except Exception as err:  # noqa: BLE001 - Ray raises many types when it cannot start
                self.close()
                where = f"--ray-address {address}" if address else "--backend ray"
                reason = (str(err).strip().splitlines() or [type(err).__name__])[-1]
                cause = None if address else ray_log_cause(started)
                raise ValueError(f"{where}: Ray did not start ({reason}{'; ' + cause if cause else ''}); "
                                 "allowed: a reachable Ray cluster address, or --backend process") from None
            except BaseException:
                self.close()
                raise
        try:
            self._context_ref = ray.put(context)
            self._task = ray.remote(_ray_evaluate).options(max_retries=max_retries, retry_exceptions=True)
        except BaseException:
            self.close()
            raise

    def map(self, genomes: list[Any], generation: int) -> list[Evaluation]:
        refs = [self._task.remote(self._context_ref, g, generation) for g in genomes]
        results = []
        for g, ref in zip(genomes, refs):
            try:
                results.append(self._ray.get(ref))
            except Exception as err:  # noqa: BLE001 - RayTaskError / WorkerCrashedError after retries
                error = _describe(err).splitlines()[-1]
                self.failures.append((g.key, error))
                results.append(Evaluation.failure(error))
        return results

    def close(self) -> None:
        """Shut a Ray this evaluator started down, then its reaper (safe to call twice)."""
        try:
            if self._own and self._ray.is_initialized():
                self._ray.shutdown()
        finally:
            stop_reaper(self._reaper)
            self._reaper = None


_RAY_LOG_LINE = re.compile(r"^\[(\S+ \S+) ([EC]) \d+ \d+\] \((\w+)\) [^:\s]+:\d+:\s*(.+)$")


def ray_log_cause(since: float) -> str | None:
    """The first error a local Ray started by this process logged (raylet, GCS server), if any.

    Ray reports a failed start only as "node timed out during startup"; the reason (an mmap
    refused, a port taken) is in its session logs: ``<ray temp dir>/session_*_<driver pid>/logs``.
    """
    root = Path(os.environ.get("RAY_TMPDIR") or tempfile.gettempdir()) / "ray"
    found: list[tuple[str, str, Path]] = []
    for session in root.glob(f"session_*_{os.getpid()}"):
        try:  # session_<local date and time>_<driver pid>: only a session of this start
            if datetime.strptime(session.name[8:34], "%Y-%m-%d_%H-%M-%S_%f").timestamp() < since - 2:
                continue
        except ValueError:
            continue
        for log in sorted((session / "logs").glob("*.[eo][ru][rt]")):  # *.err, *.out
            try:
                lines = log.read_text(encoding="utf-8", errors="replace").splitlines()
            except OSError:
                continue
            for line in lines:
                match = _RAY_LOG_LINE.match(line)
                if match:
                    found.append((match[1], f"{match[3]}: {match[4].strip()[:200]}", log))
                    break
    if not found:
        return None
    _, message, log = min(found)
    return f"{message} (Ray's log {log})"


def _check_reachable(address: str, timeout: float = 5.0) -> None:
    """Fail fast for a ``host:port`` Ray address nobody listens on (Ray itself retries for minutes)."""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not port.isdigit():
        return  # 'auto', 'local', ...: Ray resolves these itself
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except (OSError, ValueError) as err:
        raise ValueError(f"--ray-address {address}: cannot connect ({getattr(err, 'strerror', None) or err}); "
                         "allowed: the address of a running Ray head node (ray start --head), or "
                         "--backend process") from None


def _ray_evaluate(context: EvalContext, genome: Any, generation: int) -> Evaluation:
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    return context.evaluate(genome, generation)


def make_evaluator(context: EvalContext, workers: int | None, backend: str = "process",
                   ray_address: str | None = None, max_retries: int = 2) -> Evaluator:
    """An evaluator for ``backend`` ('serial', 'process' or 'ray').

    ``workers``: processes for 'process' (None = all local cores; 1 falls back to serial),
    CPUs of a locally started Ray for 'ray'.
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend={backend!r}; allowed: {list(BACKENDS)}")
    if workers is None:
        workers = os.cpu_count() or 1
    if backend == "ray":
        return RayEvaluator(context, address=ray_address, num_cpus=workers, max_retries=max_retries)
    if backend == "serial" or workers <= 1:
        return SerialEvaluator(context, max_retries=max_retries)
    return ProcessEvaluator(context, workers, max_retries=max_retries)
