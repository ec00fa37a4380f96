"""The generation loop: neat-python population, evaluation backend, statistics, checkpoints.

One call of ``Trainer.run()`` evolves an ``Experiment`` into a run directory::

    RUN_DIR/experiment.json        the resolved experiment (what was run)
    RUN_DIR/neat.cfg               a copy of the neat-python config used
    RUN_DIR/stats.jsonl, stats.csv one record per generation (evolution.run.stats)
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
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import neat

from evolution.guard import UsageError, check_output_dir, describe_os_error
from evolution.run.backends import EvalContext, make_evaluator
from evolution.run.champion import read_json, save_champion
from evolution.run.checkpoint import CheckpointError, load_checkpoint, save_checkpoint
from evolution.run.evaluate import Evaluation, decode_genome
from evolution.run.experiment import Experiment, ExperimentError, experiment_from_run
from evolution.run.stats import append_stats, generation_record, read_stats, write_stats
from gathering_env import morphological_complexity as morphology_simplicity

CHECKPOINT_DIR = "checkpoints"
KEEP_CHECKPOINTS = 3
#: What a resumed run must share with the run it continues (``generations`` may grow).
RUN_IDENTITY = ("method", "objectives", "seed", "population", "trials", "environment", "substrate")


def genome_class(method: str) -> type:
    """The neat-python genome class of a method."""
    if method == "hyperneat-m":
        from evolution.encodings.genome import CPPNGenome

        return CPPNGenome
    from evolution.encodings.direct import NEATMGenome

    return NEATMGenome


def make_neat_config(experiment: Experiment) -> neat.Config:
    """Load the experiment's neat-python config; the population size comes from the experiment.

    Single-objective runs use ``NEATReproduction`` (neat-python's ``DefaultReproduction``
    selection, its ``[NEATReproduction]`` section); multi-objective runs use
    ``MODSReproduction`` (its ``[MODSReproduction]`` section in the same file). Both breed
    with ``evolution.reproduction.breeding.breed``.
    """
    path = experiment.neat_config
    if experiment.multi_objective:
        from evolution.reproduction.mods import MODSReproduction

        reproduction: type = MODSReproduction
    else:
        from evolution.reproduction.breeding import NEATReproduction

        reproduction = NEATReproduction
    try:
        config = neat.Config(genome_class(experiment.method), reproduction,
                             neat.DefaultSpeciesSet, neat.DefaultStagnation, str(path))
    except Exception as err:  # neat raises several error types for broken files
        raise ExperimentError(f"{path}: invalid neat-python config: {err}") from None
    check_neat_config(config, path)
    config.pop_size = experiment.population
    config.no_fitness_termination = True  # the trainer decides when to stop
    return config


MAX_HIDDEN = 100
"""Upper bound of ``num_hidden`` (initial hidden nodes of every genome; the configs use 0)."""


def _cppn_genome() -> type:
    return genome_class("hyperneat-m")


def check_neat_config(config: neat.Config, path: Path) -> None:
    """Rates, bounds and sizes of a neat-python config that neat-python itself accepts blindly.

    Probabilities and rates must lie in [0, 1] (a negative rate silently switches a mutation
    off), powers, deviations and coefficients must be >= 0, every ``*_min_value`` <= its
    ``*_max_value``, ``num_hidden`` <= ``MAX_HIDDEN``. Raises ``ExperimentError`` naming the
    file, section and key.
    """
    def bad(section: str, key: str, value: Any, allowed: str) -> ExperimentError:
        return ExperimentError(f"{path}: [{section}] {key} = {value}; allowed: {allowed}")

    def number(value: Any) -> bool:
        return isinstance(value, (int, float)) and not isinstance(value, bool)

    genome, section = config.genome_config, config.genome_type.__name__
    for key, value in sorted(vars(genome).items()):
        if not number(value):
            continue
        if key.endswith("_add") and key.startswith("enabled_rate_to_"):
            total = genome.enabled_mutate_rate + value
            if not 0.0 <= total <= 1.0:
                raise bad(section, key, value, "enabled_mutate_rate + this in [0, 1]")
        elif key.endswith(("_rate", "_prob")):
            if not 0.0 <= value <= 1.0:
                raise bad(section, key, value, "a probability in [0, 1]")
        elif key.endswith(("_mutate_power", "_init_stdev", "_coefficient")):
            if not 0.0 <= value < float("inf"):
                raise bad(section, key, value, "a finite number >= 0")
        elif key.endswith(("_min_value", "_max_value", "_init_mean")) and value != value:
            raise bad(section, key, value, "a number")
        if key.endswith("_min_value"):
            high = getattr(genome, key[: -len("_min_value")] + "_max_value", None)
            if number(high) and value > high:
                raise bad(section, key, value, f"<= {key[: -len('_min_value')]}_max_value ({high})")
    for gene, defs in (("activation", genome.activation_defs), ("aggregation", genome.aggregation_function_defs)):
        options, default = getattr(genome, f"{gene}_options"), getattr(genome, f"{gene}_default")
        if not options:
            raise bad(section, f"{gene}_options", "(empty)", "one or more function names")
        unknown = [name for name in options if not defs.is_valid(name)]
        if unknown:
            raise bad(section, f"{gene}_options", " ".join(options), f"names neat-python knows (not {unknown})")
        if default not in options and default not in ("random", "none"):
            raise bad(section, f"{gene}_default", default, f"random, none or one of {gene}_options")
    if config.genome_type is not _cppn_genome():  # NEAT-M networks run on the team controller
        from evolution.encodings.controller import ACTIVATIONS

        unknown = [name for name in genome.activation_options if name not in ACTIVATIONS]
        if unknown:
            raise bad(section, "activation_options", " ".join(genome.activation_options),
                      f"functions of the team controller ({sorted(ACTIVATIONS)})")
    for key, value in sorted(vars(genome).items()):
        if key.endswith("_init_type") and value not in ("gaussian", "normal", "uniform"):
            raise bad(section, key, value, "gaussian, normal or uniform")
    if not 0 <= genome.num_hidden <= MAX_HIDDEN:
        raise bad(section, "num_hidden", genome.num_hidden, f"0..{MAX_HIDDEN}")
    species = config.species_set_config
    if not 0.0 < species.compatibility_threshold < float("inf"):
        raise bad("DefaultSpeciesSet", "compatibility_threshold", species.compatibility_threshold, "a number > 0")
    stagnation = config.stagnation_config
    if stagnation.species_fitness_func not in ("max", "min", "mean", "median"):
        raise bad("DefaultStagnation", "species_fitness_func", stagnation.species_fitness_func,
                  "max, min, mean or median")
    if stagnation.max_stagnation < 1:
        raise bad("DefaultStagnation", "max_stagnation", stagnation.max_stagnation, "an integer >= 1")
    if stagnation.species_elitism < 0:
        raise bad("DefaultStagnation", "species_elitism", stagnation.species_elitism, "an integer >= 0")
    reproduction = config.reproduction_config
    if config.reproduction_type is neat.DefaultReproduction:
        if reproduction.elitism < 0:
            raise bad("DefaultReproduction", "elitism", reproduction.elitism, "an integer >= 0")
        if not 0.0 < reproduction.survival_threshold <= 1.0:
            raise bad("DefaultReproduction", "survival_threshold", reproduction.survival_threshold, "(0, 1]")
        if reproduction.min_species_size < 1:
            raise bad("DefaultReproduction", "min_species_size", reproduction.min_species_size, "an integer >= 1")


def substrate_for(experiment: Experiment) -> Any:
    if experiment.method != "hyperneat-m":
        return None
    from evolution.encodings.substrate import Substrate

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
    already_finished: bool = False


class RunFailed(UsageError):
    """The run cannot go on (every evaluation failed, the run directory became unwritable)."""


def run_dir_of(checkpoint: Path) -> Path | None:
    """The run directory a checkpoint file belongs to (``RUN/checkpoints/gen-NNNN.ckpt``), if any."""
    checkpoint = Path(checkpoint)
    return checkpoint.parent.parent if checkpoint.parent.name == CHECKPOINT_DIR else None


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

    Output folder: a new run writes only into a missing or empty ``run_dir``. A resumed run
    must verify (a readable checkpoint whose experiment matches ``experiment.json``, the
    experiment and the overrides); deleted ``experiment.json``, ``neat.cfg``, ``stats.jsonl``
    and ``champion.json`` are rebuilt from the checkpoint. ``resume_from`` a checkpoint of
    another run directory continues that run into a missing or empty ``run_dir``. Anything
    else raises ``UsageError`` before a file is written.

    SIGINT/SIGTERM: the first signal lets the current generation finish (its statistics and
    checkpoint are written) and then stops; a second one abandons the generation at once. Either
    way the run resumes from its last checkpoint.
    """

    def __init__(self, experiment: Experiment | None, run_dir: Path, workers: int | None = None,
                 resume: bool = False, resume_from: Path | None = None, progress: bool = True,
                 backend: str = "process", ray_address: str | None = None, max_retries: int = 2,
                 overrides: dict[str, Any] | None = None) -> None:
        if experiment is None and not (resume or resume_from is not None):
            raise ValueError("experiment=None needs resume=True (the run's own experiment)")
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
        self.stop_requested = False
        self.stats_path = self.run_dir / "stats.jsonl"
        self.champion_path = self.run_dir / "champion.json"
        self.best: tuple[float, int] | None = None  # (task, genome key)
        self.champion_state: dict[str, Any] | None = None  # what champion.json is written from
        self.records: list[dict[str, Any]] = []
        self.neat_cfg_text: str | None = None
        self.finished = False  # set when a resumed run turns out to be complete already
        self._unwritten = False
        self._current: dict[int, Evaluation] = {}

    # ------------------------------------------------------------------ setup
    def _prepare(self) -> neat.Population:
        if self.resume:
            return self._restore()
        exp = self.experiment
        holds_run = (self.run_dir / CHECKPOINT_DIR).is_dir()
        check_output_dir(self.run_dir, what="run directory",
                         hint=f"it holds a run: continue it with gathering-evolve --resume {self.run_dir}"
                         if holds_run else "choose another --out")
        self.config = make_neat_config(exp)
        self.substrate = substrate_for(exp)
        self.neat_cfg_text = Path(exp.neat_config).read_text(encoding="utf-8")
        population = neat.Population(self.config, seed=exp.seed)
        self._unwritten = True  # written by _write_new_run once the backend has started
        return population

    def _write_new_run(self, population: neat.Population) -> None:
        self.run_dir.mkdir(parents=True, exist_ok=True)
        (self.run_dir / "experiment.json").write_text(json.dumps(self.experiment.to_dict(), indent=1) + "\n")
        (self.run_dir / "neat.cfg").write_text(self.neat_cfg_text, encoding="utf-8")
        self._save_checkpoint(population)
        self._unwritten = False

    def _checkpoints(self) -> list[Path]:
        return sorted((self.run_dir / CHECKPOINT_DIR).glob("gen-*.ckpt"))

    def _find_checkpoint(self) -> tuple[Path, dict[str, Any]]:
        """The checkpoint to resume from, after checking the run directory (nothing written)."""
        run_dir = self.run_dir
        if self.resume_from is not None:
            home = run_dir_of(self.resume_from)
            if home is None or home.resolve() != run_dir.resolve():
                # continuing another run's checkpoint: into a fresh folder only
                check_output_dir(run_dir, what="run directory",
                                 hint=f"--resume-from continues {self.resume_from} into a new folder, or into "
                                      "the run directory it belongs to")
            return self.resume_from, load_checkpoint(self.resume_from)
        if not run_dir.exists():
            raise UsageError(f"{run_dir}: does not exist; nothing to resume; allowed: an existing run directory "
                             "(start a new run without --resume)")
        if not run_dir.is_dir():
            raise UsageError(f"{run_dir}: is a file; allowed: a run directory written by gathering-evolve")
        candidates = list(reversed(self._checkpoints()))
        if not candidates:
            raise CheckpointError(f"{run_dir / CHECKPOINT_DIR}: no checkpoint to resume from; allowed: a run "
                                  "directory with checkpoints/gen-NNNN.ckpt (this folder is left unchanged)")
        errors = []
        for path in candidates:
            try:
                state = load_checkpoint(path)
            except CheckpointError as err:
                errors.append(str(err))  # fall back to the previous checkpoint
                continue
            if errors:
                warnings.warn(f"{'; '.join(errors)}; resuming from the previous readable checkpoint {path.name} "
                              f"(generation {state['population'].generation})", stacklevel=2)
            return path, state
        raise CheckpointError("no readable checkpoint: " + "; ".join(errors))

    def _restore(self) -> neat.Population:
        path, state = self._find_checkpoint()
        saved = state.get("experiment")
        population = state.get("population")
        if not isinstance(saved, dict) or not isinstance(population, neat.Population) or "random_state" not in state:
            raise CheckpointError(f"{path}: not a checkpoint of a gathering-evolve run")
        recorded_path = self.run_dir / "experiment.json"
        recorded = read_json(recorded_path, "experiment file", ExperimentError) if recorded_path.exists() else None
        if recorded is not None:
            for key in RUN_IDENTITY:
                if not isinstance(recorded, dict) or recorded.get(key) != saved.get(key):
                    raise ExperimentError(
                        f"{recorded_path}: {key!r} differs from checkpoint {path} ({saved.get(key)!r}); the folder "
                        "holds pieces of different runs; allowed: the run's own files (delete experiment.json to "
                        "have it rebuilt from the checkpoint)")
        if self.experiment is None:
            own = dict(saved)
            if recorded is not None and "generations" in recorded:
                own["generations"] = recorded["generations"]  # a run extended after this checkpoint
            own_cfg = self.run_dir / "neat.cfg"
            self.experiment = experiment_from_run(own, str(recorded_path if recorded is not None else path),
                                                  self.overrides, neat_config=own_cfg if own_cfg.is_file() else None)
        mine = self.experiment.to_dict()
        for key in RUN_IDENTITY:
            if saved.get(key) != mine.get(key):
                raise ExperimentError(
                    f"{path}: resuming needs the same {key!r} as the run ({saved.get(key)!r}), got {mine.get(key)!r}"
                )
        records = state.get("records")
        if records is None:  # checkpoint of an older version: statistics only in stats.jsonl
            records = [r for r in read_stats(self.stats_path) if r.get("generation", -1) < population.generation]
            if len(records) != population.generation:
                raise CheckpointError(
                    f"{self.stats_path}: holds {len(records)} of the {population.generation} generations before "
                    f"{path.name}, and this (older) checkpoint cannot rebuild them; allowed: the run's stats.jsonl")
        self.best = state.get("best")
        self.champion_state = state.get("champion")
        if self.best is not None and not self.champion_path.exists() and self.champion_state is None:
            raise CheckpointError(f"{self.champion_path}: missing, and this (older) checkpoint {path.name} cannot "
                                  "rebuild it; allowed: the run's champion.json")
        self.config = population.config  # the exact config the lineage was evolved with
        self.substrate = substrate_for(self.experiment)
        self.neat_cfg_text = state.get("neat_cfg")
        population.config.pop_size = self.experiment.population
        random.setstate(state["random_state"])
        self.records = list(records)
        # Verified. A finished run only gets its missing files back; a continued one is reset
        # to the checkpoint (later generations will be recomputed identically).
        self.finished = self._is_finished(population)
        self.run_dir.mkdir(parents=True, exist_ok=True)
        if recorded is None or (not self.finished and recorded.get("generations") != self.experiment.generations):
            recorded_path.write_text(json.dumps(self.experiment.to_dict(), indent=1) + "\n")
        if not (self.run_dir / "neat.cfg").exists():
            if self.neat_cfg_text is not None:
                (self.run_dir / "neat.cfg").write_text(self.neat_cfg_text, encoding="utf-8")
            else:
                warnings.warn(f"{self.run_dir / 'neat.cfg'}: missing and this (older) checkpoint cannot rebuild it; "
                              "the run goes on with the config stored in the checkpoint", stacklevel=2)
        if not self.finished or not self.stats_path.exists():
            write_stats(self.stats_path, self.records)
        if self.champion_state is not None and (not self.champion_path.exists() or not self.finished):
            self._write_champion(**self.champion_state)
        home = run_dir_of(path)
        if home is None or home.resolve() != self.run_dir.resolve():
            self._save_checkpoint(population)  # a run continued in a new folder resumes from there
        return population

    def _is_finished(self, population: neat.Population) -> bool:
        exp = self.experiment
        return population.generation >= exp.generations or self._converged()

    def _converged(self) -> bool:
        exp = self.experiment
        target = 100.0 + exp.world_config().time_bonus / 2.0
        return bool(exp.convergence_stop and not exp.multi_objective and self.records
                    and self.records[-1].get("task_best", 0.0) >= target)

    def _save_checkpoint(self, population: neat.Population) -> None:
        reporters = population.reporters
        population.reporters = neat.reporting.ReporterSet()
        population.species.reporters = population.reporters
        state = {
            "population": population,
            "random_state": random.getstate(),
            "experiment": self.experiment.to_dict(),
            "best": self.best,
            # enough to rebuild stats.jsonl, champion.json and neat.cfg if they are deleted
            "records": self.records,
            "champion": self.champion_state,
            "neat_cfg": self.neat_cfg_text,
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
        population = self._prepare()
        exp = self.experiment
        target = 100.0 + exp.world_config().time_bonus / 2.0
        if self.finished:
            # Nothing left to evolve: only rebuild what is missing.
            if exp.multi_objective and not any((self.run_dir / "front").glob("genome-*.json")):
                self._write_front(population)
            if not (self.run_dir / "stats.png").exists():
                self._plot()
            return self._result(self._converged(), already_finished=True)
        converged = False
        context = EvalContext(self.config, dict(exp.environment), exp.trials, exp.seed, exp.method, self.substrate)
        # Starting a backend (Ray in particular) may draw from Python's global random generator,
        # which is neat-python's: keep the lineage independent of the backend.
        random_state = random.getstate()
        evaluator = self._evaluator = make_evaluator(context, self.workers, self.backend, self.ray_address,
                                                     self.max_retries)
        random.setstate(random_state)
        if self._unwritten:  # a new run: nothing is written before the backend is up
            try:
                self._write_new_run(population)
            except BaseException:
                evaluator.close()
                raise
        previous_handlers = self._install_signal_handlers()
        bar = None
        if self.progress:
            from tqdm import tqdm

            bar = tqdm(total=exp.generations, initial=population.generation, desc=exp.name, unit="gen")
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
                self.records.append(record)
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
        except OSError as err:
            raise RunFailed(f"{describe_os_error(err)}; the run stopped at generation {population.generation}: "
                            f"fix it and continue with gathering-evolve --resume {self.run_dir}") from None
        finally:
            self._restore_signal_handlers(previous_handlers)
            evaluator.close()
            if bar is not None:
                bar.close()
        if exp.multi_objective:
            self._write_front(population)
        self._plot()
        return self._result(converged, interrupted=self.stop_requested)

    def _result(self, converged: bool, interrupted: bool = False, already_finished: bool = False) -> RunResult:
        best = self.best[0] if self.best is not None else max((r["task_best"] for r in self.records), default=0.0)
        return RunResult(self.run_dir, len(self.records), best,
                         self.champion_path if self.champion_path.exists() else None, converged,
                         interrupted=interrupted, already_finished=already_finished)

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
        if genomes and self._failures == len(genomes):
            first = self._evaluator.failures[0][1]
            raise RunFailed(f"{self.run_dir}: every evaluation of generation {self._generation} failed (first: "
                            f"{first}; all in {self.run_dir / 'errors.log'}); the run stopped: fix the cause and "
                            f"continue with gathering-evolve --resume {self.run_dir}")
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
            self.champion_state = {"generation": generation, "genome": self._current_genomes[best_key],
                                   "evaluation": self._current[best_key]}
            self._write_champion(**self.champion_state)
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
        from evolution.run.plots import plot_run

        if self.records:
            plot_run(self.records, self.run_dir / "stats.png", title=self.experiment.name)
