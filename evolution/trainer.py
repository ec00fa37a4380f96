"""The generation loop: neat-python population, evaluation backend, statistics, checkpoints.

One call of ``Trainer.run()`` evolves an ``Experiment`` into a run directory::

    RUN_DIR/experiment.json        the resolved experiment (what was run)
    RUN_DIR/neat.cfg               a copy of the neat-python config used
    RUN_DIR/stats.jsonl, stats.csv one record per generation (evolution.stats)
    RUN_DIR/checkpoints/gen-NNNN.ckpt  state before generation NNNN is evaluated
    RUN_DIR/champion.json          best genome so far by task performance (JSON, no pickle)
    RUN_DIR/stats.png              fitness and simplicity over generations (at the end)

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

import json
import random
import shutil
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import neat

from gathering_env import morphological_complexity as morphology_simplicity

from .backends import EvalContext, make_evaluator
from .champion import save_champion
from .checkpoint import CheckpointError, load_checkpoint, save_checkpoint
from .evaluate import Evaluation, decode_genome
from .experiment import Experiment, ExperimentError
from .stats import append_stats, generation_record, read_stats, write_stats

CHECKPOINT_DIR = "checkpoints"
KEEP_CHECKPOINTS = 3


def genome_class(method: str) -> type:
    """The neat-python genome class of a method."""
    if method == "hyperneat-m":
        from .genome import CPPNGenome

        return CPPNGenome
    from .direct import NEATMGenome

    return NEATMGenome


def make_neat_config(experiment: Experiment) -> neat.Config:
    """Load the experiment's neat-python config; the population size comes from the experiment.

    Single-objective runs use ``NEATReproduction`` (neat-python's ``DefaultReproduction``
    selection, its ``[NEATReproduction]`` section); multi-objective runs use
    ``MODSReproduction`` (its ``[MODSReproduction]`` section in the same file). Both breed
    with ``evolution.breeding.breed``.
    """
    path = experiment.neat_config
    if experiment.multi_objective:
        from .mods import MODSReproduction

        reproduction: type = MODSReproduction
    else:
        from .breeding import NEATReproduction

        reproduction = NEATReproduction
    try:
        config = neat.Config(genome_class(experiment.method), reproduction,
                             neat.DefaultSpeciesSet, neat.DefaultStagnation, str(path))
    except Exception as err:  # neat raises several error types for broken files
        raise ExperimentError(f"{path}: invalid neat-python config: {err}") from None
    config.pop_size = experiment.population
    config.no_fitness_termination = True  # the trainer decides when to stop
    return config


def substrate_for(experiment: Experiment) -> Any:
    if experiment.method != "hyperneat-m":
        return None
    from .substrate import Substrate

    try:
        return Substrate(**experiment.substrate)
    except TypeError as err:
        raise ExperimentError(f"{experiment.source}: [substrate] {err}") from None


@dataclass
class RunResult:
    run_dir: Path
    generations: int
    best_task: float
    champion: Path | None
    converged: bool
    interrupted: bool = False


class Trainer:
    """Evolve one experiment into ``run_dir``.

    Args:
        experiment: the validated experiment. run_dir: output directory.
        workers: evaluation processes (None = all local cores, 1 = serial).
        resume: continue from the newest checkpoint in ``run_dir`` (or ``resume_from``).
        progress: show a progress bar with ETA (tqdm).
        backend: 'serial', 'process' or 'ray' (``evolution.backends``); ray_address: join this
            Ray cluster instead of starting a local one. max_retries: per failing evaluation.

    SIGINT/SIGTERM: the first signal lets the current generation finish (its statistics and
    checkpoint are written) and then stops; a second one abandons the generation at once. Either
    way the run resumes from its last checkpoint.
    """

    def __init__(self, experiment: Experiment, run_dir: Path, workers: int | None = None,
                 resume: bool = False, resume_from: Path | None = None, progress: bool = True,
                 backend: str = "process", ray_address: str | None = None, max_retries: int = 2) -> None:
        self.experiment = experiment
        self.run_dir = Path(run_dir)
        self.workers = workers
        self.resume = resume or resume_from is not None
        self.resume_from = resume_from
        self.progress = progress
        self.backend = backend
        self.ray_address = ray_address
        self.max_retries = max_retries
        self.stop_requested = False
        self.stats_path = self.run_dir / "stats.jsonl"
        self.champion_path = self.run_dir / "champion.json"
        self.best: tuple[float, int] | None = None  # (task, genome key)
        self._current: dict[int, Evaluation] = {}

    # ------------------------------------------------------------------ setup
    def _prepare(self) -> neat.Population:
        exp = self.experiment
        self.config = make_neat_config(exp)
        self.substrate = substrate_for(exp)
        if self.resume:
            return self._restore()
        if self.stats_path.exists() or (self.run_dir / CHECKPOINT_DIR).exists():
            raise ExperimentError(
                f"{self.run_dir}: already holds a run; pass --resume to continue it or choose another --out"
            )
        self.run_dir.mkdir(parents=True, exist_ok=True)
        (self.run_dir / "experiment.json").write_text(json.dumps(exp.to_dict(), indent=1) + "\n")
        shutil.copyfile(exp.neat_config, self.run_dir / "neat.cfg")
        population = neat.Population(self.config, seed=exp.seed)
        self._save_checkpoint(population)
        return population

    def _checkpoints(self) -> list[Path]:
        return sorted((self.run_dir / CHECKPOINT_DIR).glob("gen-*.ckpt"))

    def _restore(self) -> neat.Population:
        candidates = [self.resume_from] if self.resume_from else list(reversed(self._checkpoints()))
        if not candidates:
            raise CheckpointError(f"{self.run_dir / CHECKPOINT_DIR}: no checkpoint to resume from")
        errors = []
        for path in candidates:
            try:
                state = load_checkpoint(path)
                break
            except CheckpointError as err:
                if self.resume_from:
                    raise
                errors.append(str(err))  # fall back to the previous checkpoint
        else:
            raise CheckpointError("no readable checkpoint: " + "; ".join(errors))
        saved = state["experiment"]
        mine = self.experiment.to_dict()
        for key in ("method", "objectives", "seed", "population", "trials", "environment", "substrate"):
            if saved.get(key) != mine.get(key):
                raise ExperimentError(
                    f"{path}: resuming needs the same {key!r} as the run ({saved.get(key)!r}), got {mine.get(key)!r}"
                )
        population: neat.Population = state["population"]
        population.config.pop_size = self.experiment.population
        random.setstate(state["random_state"])
        self.best = state["best"]
        # Statistics of generations after the checkpoint will be recomputed identically.
        records = [r for r in read_stats(self.stats_path) if r["generation"] < population.generation]
        write_stats(self.stats_path, records)
        return population

    def _save_checkpoint(self, population: neat.Population) -> None:
        reporters = population.reporters
        population.reporters = neat.reporting.ReporterSet()
        population.species.reporters = population.reporters
        state = {
            "population": population,
            "random_state": random.getstate(),
            "experiment": self.experiment.to_dict(),
            "best": self.best,
        }
        path = self.run_dir / CHECKPOINT_DIR / f"gen-{population.generation:04d}.ckpt"
        try:
            save_checkpoint(path, state)
        finally:
            population.reporters = reporters
            population.species.reporters = reporters
        for old in self._checkpoints()[:-KEEP_CHECKPOINTS]:
            old.unlink(missing_ok=True)

    # ------------------------------------------------------------------ loop
    def run(self) -> RunResult:
        exp = self.experiment
        population = self._prepare()
        context = EvalContext(self.config, dict(exp.environment), exp.trials, exp.seed, exp.method, self.substrate)
        # Starting a backend (Ray in particular) may draw from Python's global random generator,
        # which is neat-python's: keep the lineage independent of the backend.
        random_state = random.getstate()
        evaluator = self._evaluator = make_evaluator(context, self.workers, self.backend, self.ray_address,
                                                     self.max_retries)
        random.setstate(random_state)
        previous_handlers = self._install_signal_handlers()
        bar = None
        if self.progress:
            from tqdm import tqdm

            bar = tqdm(total=exp.generations, initial=population.generation, desc=exp.name, unit="gen")
        converged = False
        target = 100.0 + exp.world_config().time_bonus / 2.0
        try:
            while population.generation < exp.generations:
                generation = population.generation
                start = time.perf_counter()
                species_count = len(population.species.species)

                self._generation = generation
                population.run(self._fitness, 1)
                record = self._record(generation, species_count, time.perf_counter() - start)
                if exp.multi_objective:
                    front = population.reproduction.front
                    record["front"] = {"genomes": [k for k, _ in front], "objectives": [list(o) for _, o in front],
                                       "names": list(exp.objectives)}
                append_stats(self.stats_path, record)
                self._save_checkpoint(population)
                if bar is not None:
                    bar.set_postfix(best_ft=f"{record['task_best']:.1f}", mean_ft=f"{record['task_mean']:.1f}")
                    bar.update(1)
                if (exp.convergence_stop and not exp.multi_objective and record["task_best"] >= target):
                    converged = True
                    break
                if self.stop_requested:
                    break
        finally:
            self._restore_signal_handlers(previous_handlers)
            evaluator.close()
            if bar is not None:
                bar.close()
        if exp.multi_objective:
            self._write_front(population)
        self._plot()
        records = read_stats(self.stats_path)
        return RunResult(self.run_dir, len(records), max((r["task_best"] for r in records), default=0.0),
                         self.champion_path if self.champion_path.exists() else None, converged,
                         interrupted=self.stop_requested)

    def _install_signal_handlers(self) -> dict[int, Any]:
        import signal
        import threading

        if threading.current_thread() is not threading.main_thread():
            return {}

        def request_stop(signum: int, frame: Any) -> None:
            if self.stop_requested:
                raise KeyboardInterrupt  # second signal: abandon the generation in flight
            self.stop_requested = True
            print(f"\nsignal {signum}: finishing generation {getattr(self, '_generation', 0)}, then stopping "
                  "(again to abandon it); resume with --resume", flush=True)

        previous = {}
        for sig in (signal.SIGINT, signal.SIGTERM):
            previous[sig] = signal.signal(sig, request_stop)
        return previous

    @staticmethod
    def _restore_signal_handlers(previous: dict[int, Any]) -> None:
        import signal

        for sig, handler in previous.items():
            signal.signal(sig, handler)

    def _fitness(self, genomes: list[tuple[int, Any]], config: neat.Config) -> None:
        """neat-python fitness function: evaluate on the backend, set fitness and objectives."""
        evaluations = self._evaluator.map([g for _, g in genomes], self._generation)
        self._current = {}
        for key, error in self._evaluator.failures:
            with open(self.run_dir / "errors.log", "a", encoding="utf-8") as log:
                log.write(f"generation {self._generation} genome {key}: {error}\n")
        self._failures = len(self._evaluator.failures)
        self._evaluator.failures.clear()
        for (key, g), ev in zip(genomes, evaluations):
            g.fitness = ev.task
            g.objectives = ev.objectives(self.experiment.objectives)
            self._current[key] = ev
        self._current_genomes = dict(genomes)

    def _record(self, generation: int, species_count: int, seconds: float) -> dict[str, Any]:
        evaluations = list(self._current.values())
        best_key = max(self._current, key=lambda k: (self._current[k].task, -k))
        record = generation_record(generation, evaluations, species_count, seconds, best_key)
        record["failures"] = int(getattr(self, "_failures", 0))
        best_task = self._current[best_key].task
        if self.best is None or best_task > self.best[0]:
            self.best = (best_task, best_key)
            self._write_champion(generation, self._current_genomes[best_key], self._current[best_key])
        return record

    def _write_champion(self, generation: int, genome: Any, evaluation: Evaluation) -> None:
        exp = self.experiment
        controller, morphology = decode_genome(exp.method, genome, self.config, self.substrate)
        save_champion(self.champion_path, method=exp.method, experiment=exp.name, generation=generation,
                      genome=genome, morphology=morphology, controller=controller,
                      objectives={"task": evaluation.task, "morphology": evaluation.morphology,
                                  "controller": evaluation.controller},
                      environment=exp.environment)

    def _write_front(self, population: neat.Population) -> None:
        """Write every genome of the final first front as a JSON champion in ``front/``."""
        exp = self.experiment
        reproduction = population.reproduction
        front_dir = self.run_dir / "front"
        front_dir.mkdir(exist_ok=True)
        for old in front_dir.glob("genome-*.json"):
            old.unlink()
        generation = population.generation - 1
        for key, objectives in reproduction.front:
            genome = reproduction.parents.get(key) or reproduction.front_genomes[key]
            controller, morphology = decode_genome(exp.method, genome, self.config, self.substrate)
            values = dict(zip(exp.objectives, objectives))
            values.setdefault("morphology", morphology_simplicity(morphology))
            values.setdefault("controller", 100.0 - float(controller.num_links))
            save_champion(front_dir / f"genome-{key}.json", method=exp.method, experiment=exp.name,
                          generation=generation, genome=genome, morphology=morphology,
                          controller=controller, objectives=values, environment=exp.environment)

    def _plot(self) -> None:
        from .plots import plot_run

        records = read_stats(self.stats_path)
        if records:
            plot_run(records, self.run_dir / "stats.png", title=self.experiment.name)
