"""The generation loop: neat-python population, evaluation backend, statistics, checkpoints.

One call of ``Trainer.run()`` evolves an ``Experiment`` into a run directory::

    RUN_DIR/experiment.json        the resolved experiment (what was run)
    RUN_DIR/neat.cfg               a copy of the neat-python config used
    RUN_DIR/stats.jsonl, stats.csv one record per generation (evolution.run.stats)
    RUN_DIR/checkpoints/gen-NNNN.ckpt  state before generation NNNN is evaluated
    RUN_DIR/champion.json          best genome so far by task performance (JSON, no pickle)
    RUN_DIR/stats.png              fitness and simplicity over generations (at the end)
    RUN_DIR/.lock                  the writer's lock and PID (evolution.run.lock)

neat-python's ``Population.run(fitness, 1)`` is called once per generation: it evaluates the
population through our fitness function (which hands the genomes to the backend), reports,
reproduces and speciates. After each generation the statistics line is appended and then the
checkpoint of the next generation is written atomically, so a killed run resumes
(``resume=True``) from the last checkpoint and reproduces the same lineage: the checkpoint
holds the population, species, reproduction state (genome ids, stagnation), the innovation
tracker and the state of Python's ``random`` (neat-python's only source of randomness);
trial seeds depend only on (run seed, generation, trial).
"""

from __future__ import annotations

import random
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import neat

from evolution.guard import UsageError, describe_os_error, writing
from evolution.reproduction.encog import ENCOG_PERTURB_SIGMAS, ENCOG_WEIGHT_RANGE
from evolution.run.backends import EvalContext, make_evaluator
from evolution.run.evaluate import Evaluation, training_environment, varied_episodes
from evolution.run.experiment import Experiment
from evolution.run.lock import RunLock
from evolution.run.rebuild import RebuildingEvaluator, load_record
from evolution.run.recorder import RunRecorder, convergence_target
from evolution.run.reuse import ReusingEvaluator
from evolution.run.rundir import check_new_run_dir, new_run, restore_run
from evolution.run.signals import StopSignals
from gathering_env.compiled.engine import announce_compile


@dataclass
class RunResult:
    run_dir: Path
    generations: int
    best_task: float
    champion: Path | None
    converged: bool
    interrupted: bool = False
    already_finished: bool = False
    reused: int = 0
    """Genomes of this invocation that took the evaluation of an identical team (``evolution.run.reuse``)."""
    asked: int = 0
    """Genomes this invocation had evaluated (the carried ones not counted)."""


#: World options of the original protocol that a run names at its start: (key, value) -> (what
#: of the original's it is, what it does and where).
WORLD_NOTES = {
    ("colour_response", "farther"): ("colour reading", "a block reads 0.5 + d/2R, a wall d/2R, rising with "
                                     "distance d (gathering_env.reference.sensing)"),
    ("block_sighting", "rays"): ("block sighting", "a sensor sees a block only along its axis and its two cone "
                                 "edges (gathering_env.reference.sensing)"),
    ("wall_distance", "original"): ("wall distances", "a wall is read at the distance the 2018 line formulas "
                                    "give, not its nearest point (gathering_env.reference.sensing)"),
    ("attached_steering", "original"): ("steering of a welded robot", "its inner wheel slows to a stop at 90 "
                                        "degrees off the zone centre, not 45 (gathering_env.reference.heuristics)"),
    ("weld_spin", "free"): ("welded pair", "a welded robot's friction torque lets go, so robot and block turn "
                            "together (gathering_env.attachments)"),
}


def protocol_notes(exp: Experiment) -> list[str]:
    """What a run does differently from the paper's defaults, one line each (printed at its start)."""
    notes = []
    if exp.protocol is not None:
        notes.append(f"{exp.name}: protocol {exp.protocol!r}, version {exp.protocol_version} (evolution.run.protocol)")
    if exp.layout == "per_run" and varied_episodes(exp.environment) and exp.trials == 1:
        notes.append(f"{exp.name}: one layout for the whole run (layout = per_run), one trial on it with one "
                     "shuffled schedule (schedule = shuffled), the same for every genome")
    elif exp.layout == "per_run" and varied_episodes(exp.environment):
        notes.append(f"{exp.name}: one layout for the whole run (layout = per_run): its {exp.trials} trials share it "
                     "and differ by their shuffled schedules (schedule = shuffled), as the original's did")
    elif exp.layout == "per_run":
        notes.append(f"{exp.name}: one layout for the whole run (layout = per_run): its {exp.trials} trials would be "
                     "the same episode in this deterministic simulator, so each genome runs it once")
    if exp.elitism == "ratchet" and not exp.multi_objective:
        carried = "the best-ever genome is carried over"
        if exp.speciation == "original":
            carried = ("the best-ever genome (and Encog's species elites, if [NEATReproduction] "
                       "original_elite_rate > 0; the 2018 code's is 0) is carried over")
        notes.append(f"{exp.name}: ratchet (elitism = ratchet): {carried}, with stored scores, and not "
                     "evaluated again; only offspring are scored")
    if exp.truncation == "encog":
        notes.append(f"{exp.name}: Encog's truncation (truncation = encog): the best max(floor(f n), 1) genomes of a "
                     "species of n breed (f = parent_fraction; at 0.3 a species of fewer than 7 breeds from its best alone)")
    if exp.weights == "encog":
        small, large = ENCOG_PERTURB_SIGMAS[exp.method]
        notes.append(f"{exp.name}: Encog's link weights (weights = encog): uniform in +-{ENCOG_WEIGHT_RANGE:g}, perturbed "
                     f"by a deviation of {small:g} or {large:g}, or reset (evolution.reproduction.encog)")
    if exp.method == "hyperneat-m" and exp.substrate.get("bearings") == "atan":
        notes.append(f"{exp.name}: the original's sensor bearings (bearings = atan): atan(y / x) of each input node, "
                     "so every sensor sits on the front half of the body (evolution.encodings.substrate)")
    for (key, value), (what, does) in WORLD_NOTES.items():
        if exp.environment.get(key) == value:
            notes.append(f"{exp.name}: the original's {what} ({key} = {value}): {does}")
    if exp.environment.get("ir_response") == "khepera" or exp.environment.get("bottom_response") == "khepera":
        which = [k for k in ("ir_response", "bottom_response") if exp.environment.get(k) == "khepera"]
        notes.append(f"{exp.name}: the original's Khepera curve ({', '.join(f'{k} = khepera' for k in which)}): "
                     "infrared near-contact, bottom on/off at the robot's front (gathering_env.khepera)")
    if exp.species_bookkeeping == "encog" and not exp.multi_objective:
        notes.append(f"{exp.name}: Encog's species books (species_bookkeeping = encog): the best genome's species "
                     "pointer names the best species, which outlives its leader; speciation after scoring; generation "
                     "0 speciated at 0.99, the ratchet starting from its first genome (evolution.reproduction.bookkeeping)")
    return notes


class RunFailed(UsageError):
    """The run cannot go on (every evaluation failed, the run directory became unwritable)."""


class Trainer:
    """Evolve one experiment into ``run_dir``.

    Args:
        experiment: the validated experiment; None when resuming: the run's own experiment
            (from its checkpoint) with ``overrides`` applied. run_dir: output directory.
        workers: evaluation processes (None = all local cores, 1 = serial).
        resume: continue from the newest readable checkpoint in ``run_dir`` (or ``resume_from``).
        progress: show a progress bar with ETA (tqdm).
        backend: 'serial', 'process' or 'ray' (``evolution.run.backends``); ray_address: join this
            Ray cluster instead of starting a local one. max_retries: per failing evaluation.
        overrides: as for ``load_experiment``, applied to the run's experiment when
            ``experiment`` is None (only ``generations`` and ``name`` may differ from the run).
        rebuild_from: a new run takes the scores of the generations recorded there (a run or
            evidence folder) instead of simulating them (``evolution.run.rebuild``).
        reuse: a genome that decodes to a team already scored on the same episodes takes its
            evaluation (``evolution.run.reuse``; the same statistics, fewer steps); False
            simulates every genome (to measure what reuse saves).

    Output folder: the rules of ``evolution.run.rundir`` (a new run into a missing or empty
    folder; a resumed run verified before anything is written; one writer at a time, by the
    run directory's lock, ``evolution.run.lock``). The record and every file
    written from it: ``evolution.run.recorder.RunRecorder`` (``self.recorder``).

    SIGINT/SIGTERM/SIGHUP: the first signal lets the current generation finish (its statistics and
    checkpoint are written) and then stops; a second one abandons the generation at once. Either
    way the run resumes from its last checkpoint (``evolution.run.signals``).
    """

    def __init__(self, experiment: Experiment | None, run_dir: Path, workers: int | None = None,
                 resume: bool = False, resume_from: Path | None = None, progress: bool = True,
                 backend: str = "process", ray_address: str | None = None, max_retries: int = 2,
                 overrides: dict[str, Any] | None = None, rebuild_from: Path | None = None,
                 reuse: bool = True) -> None:
        if experiment is None and not (resume or resume_from is not None):
            raise ValueError("experiment=None needs resume=True (the run's own experiment)")
        if rebuild_from is not None and (resume or resume_from is not None or experiment is None):
            raise UsageError(f"--rebuild-from {rebuild_from}: starts a new run from a record; allowed: an experiment "
                             "and a new --out, without --resume (a run with checkpoints resumes from them)")
        self.rebuild_from = Path(rebuild_from) if rebuild_from is not None else None
        self.reuse = reuse
        self.experiment = experiment
        self.run_dir = Path(run_dir)
        self.workers = workers
        self.resume = resume or resume_from is not None
        self.resume_from = Path(resume_from) if resume_from is not None else None
        self.progress = progress
        self.backend = backend
        self.ray_address = ray_address
        self.max_retries = max_retries
        self.overrides = overrides
        self.stop = StopSignals(lambda: getattr(self, "_generation", 0))
        self.recorder: RunRecorder | None = None
        self._current: dict[int, Evaluation] = {}
        self._current_genomes: dict[int, Any] = {}
        self._carried: frozenset[int] = frozenset()
        self._failures = 0

    @property
    def records(self) -> list[dict[str, Any]]:
        return self.recorder.records if self.recorder is not None else []

    def _prepare(self) -> tuple[neat.Population, bool, Any]:
        """(population, finished, write): a verified run, nothing written yet; ``write()``
        writes its files (a new run's first ones, a resumed run's missing ones)."""
        if self.resume:
            population, self.recorder, finished, write = restore_run(self.run_dir, self.experiment,
                                                                     self.resume_from, self.overrides)
            self.experiment = self.recorder.experiment
            return population, finished, write
        population, self.recorder = new_run(self.experiment, self.run_dir)

        def write() -> None:
            check_new_run_dir(self.run_dir)  # again, now that it is locked: no other run got in first
            self.recorder.write_new_run(population)

        return population, False, write

    # ------------------------------------------------------------------ loop
    def run(self) -> RunResult:
        """Evolve; the run directory is locked (``evolution.run.lock.RunLock``) throughout."""
        self._lock = RunLock(self.run_dir)
        try:
            self._lock.acquire(create=False)  # a run directory in use is refused before any work
            return self._run()
        finally:
            self._lock.release()

    def _run(self) -> RunResult:
        population, finished, write = self._prepare()
        exp, recorder, lock = self.experiment, self.recorder, self._lock
        if finished:
            # Nothing left to evolve: only rebuild what is missing.
            lock.acquire()
            write()
            if exp.multi_objective and not any((self.run_dir / "front").glob("genome-*.json")):
                recorder.write_front(population)
            if not (self.run_dir / "stats.png").exists():
                recorder.plot()
            return self._result(recorder.converged(), already_finished=True)
        recorded = load_record(self.rebuild_from, exp.to_dict()) if self.rebuild_from is not None else None
        context = EvalContext(recorder.config, training_environment(exp.environment, exp.seed, exp.layout),
                              exp.trials, exp.seed, exp.method,
                              recorder.substrate, layout=exp.layout, complexity=exp.complexity)
        for line in protocol_notes(exp):
            print(line, flush=True)
        # Starting a backend (Ray in particular) may draw from Python's global random generator,
        # which is neat-python's: keep the lineage independent of the backend.
        random_state = random.getstate()
        if dict(exp.environment).get("kernel", "compiled") == "compiled":
            announce_compile()  # here, once: not from every worker, nor across the progress bar
        evaluator = self._evaluator = make_evaluator(context, self.workers, self.backend, self.ray_address,
                                                     self.max_retries)
        random.setstate(random_state)
        if recorded is not None:
            evaluator = RebuildingEvaluator(evaluator, recorded, context, self.rebuild_from)
            print(f"{exp.name}: generations 0-{len(recorded) - 1} rebuilt from {self.rebuild_from} (its recorded "
                  "scores, each generation checked against its record), the rest simulated", flush=True)
        if self.reuse:
            evaluator = ReusingEvaluator(evaluator, context)
        self._evaluator = evaluator
        try:  # nothing is written before the backend is up and the run directory is locked
            lock.acquire()
            write()
        except BaseException:
            evaluator.close()
            raise
        bar = None
        if self.progress:
            from tqdm import tqdm

            bar = tqdm(total=exp.generations, initial=population.generation, desc=exp.name, unit="gen")
        try:
            with self.stop:
                converged = self._evolve(population, evaluator, recorded, bar)
        except OSError as err:
            raise RunFailed(f"{describe_os_error(err)}; the run stopped at generation {population.generation}: "
                            f"fix it and continue with gathering-evolve --resume {self.run_dir}") from None
        finally:
            evaluator.close()
            if bar is not None:
                bar.close()
        if exp.multi_objective:
            recorder.write_front(population)
        recorder.plot()
        self._check_run_dir(population.generation)
        return self._result(converged, interrupted=self.stop.requested)

    def _evolve(self, population: neat.Population, evaluator: Any, recorded: Any, bar: Any) -> bool:
        """Run generations until the limit, convergence (returns True) or a stop signal."""
        exp, recorder = self.experiment, self.recorder
        target = convergence_target(exp)
        while population.generation < exp.generations:
            generation = population.generation
            start = time.perf_counter()
            species_count = len(population.species.species)
            history = getattr(population.species, "history", None)
            threshold = history[-1][1] if history else population.species.species_set_config.compatibility_threshold

            self._generation = generation
            self._population = population
            rebuilt = recorded is not None and evaluator.rebuilds(generation)
            amend = evaluator.check if rebuilt else None
            population.run(self._fitness, 1)
            if getattr(population.species, "deferred", False):  # speciated once scored, in the run
                _, threshold, species_count = population.species.history[-1]
            self._check_run_dir(generation)
            record = recorder.record(population, generation, species_count, time.perf_counter() - start,
                                     self._current, self._current_genomes, self._failures, threshold,
                                     self._carried, amend)
            recorder.save_checkpoint(population)
            if bar is not None:
                bar.set_postfix(best_ft=f"{record['task_best']:.1f}", mean_ft=f"{record['task_mean']:.1f}")
                bar.update(1)
            if exp.convergence_stop and not exp.multi_objective and record["task_best"] >= target:
                self._check_run_dir(population.generation)
                return True
            if self.stop.requested:
                break
        self._check_run_dir(population.generation)
        return False

    def _check_run_dir(self, generation: int) -> None:
        """Stop (no success reported) if the run directory was deleted or replaced under the run."""
        try:
            self._lock.check()
        except FileNotFoundError:
            raise RunFailed(f"{self.run_dir}: the run directory was deleted or replaced while the run was writing "
                            f"it (at generation {generation}); the run stopped and its record is incomplete; "
                            "allowed: leave a run directory alone while it runs (start the run again)") from None

    def _result(self, converged: bool, interrupted: bool = False, already_finished: bool = False) -> RunResult:
        recorder = self.recorder
        best = recorder.best[0] if recorder.best is not None else max((r["task_best"] for r in recorder.records),
                                                                        default=0.0)
        champion = recorder.champion_path
        evaluator = getattr(self, "_evaluator", None)
        return RunResult(self.run_dir, len(recorder.records), best, champion if champion.exists() else None, converged,
                         interrupted=interrupted, already_finished=already_finished,
                         reused=getattr(evaluator, "reused", 0), asked=getattr(evaluator, "asked", 0))

    def _fitness(self, genomes: list[tuple[int, Any]], config: neat.Config) -> None:
        """neat-python fitness function: evaluate on the backend, set fitness and objectives.

        A genome the reproduction carried over unscored (``elitism = "ratchet"``) keeps its
        fitness and its stored evaluation (``genome.evaluation``), entered in this generation's
        statistics with no steps or time of its own.
        """
        carried = {key for key in getattr(self._population.reproduction, "carried", ())
                   if getattr(dict(genomes).get(key), "evaluation", None) is not None}
        kept = {key: dict(genomes)[key] for key in carried}
        genomes = [(key, g) for key, g in genomes if key not in carried]
        evaluations = self._evaluator.map([g for _, g in genomes], self._generation)
        self._current = {}
        for key, error in self._evaluator.failures:
            with writing(self.run_dir / "errors.log"), open(self.run_dir / "errors.log", "a", encoding="utf-8") as log:
                log.write(f"generation {self._generation} genome {key}: {error}\n")
        self._failures = len(self._evaluator.failures)
        if genomes and self._failures == len(genomes):
            first = self._evaluator.failures[0][1]
            raise RunFailed(f"{self.run_dir}: every evaluation of generation {self._generation} failed (first: "
                            f"{first}; all in {self.run_dir / 'errors.log'}); the run stopped: fix the cause and "
                            f"continue with gathering-evolve --resume {self.run_dir}")
        self._evaluator.failures.clear()
        ratchet = self.experiment.elitism == "ratchet"
        for (key, g), ev in zip(genomes, evaluations):
            g.fitness = ev.task
            g.objectives = ev.objectives(self.experiment.objectives)
            if ratchet:
                g.evaluation = ev
            self._current[key] = ev
        for key, g in kept.items():
            self._current[key] = replace(g.evaluation, steps=0, seconds_env=0.0, seconds_controller=0.0,
                                         seconds_decode=0.0)
        self._current_genomes = dict(genomes) | kept
        self._carried = frozenset(kept)
