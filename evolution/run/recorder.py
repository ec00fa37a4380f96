"""What a run writes about itself: statistics lines, checkpoints, the champion, the final front, the figure.

``RunRecorder`` owns the run's record (the per-generation statistics, the best task score so
far and what ``champion.json`` is written from) and every file written from it, so the
generation loop (``evolution.run.trainer``) only evaluates and asks for records to be kept.
Files (in ``run_dir``): ``stats.jsonl`` / ``stats.csv`` (``evolution.run.stats``),
``checkpoints/gen-NNNN.ckpt`` (the last ``KEEP_CHECKPOINTS``), ``champion.json``,
``front/genome-KEY.json`` (multi-objective runs), ``stats.png``.
"""

from __future__ import annotations

import json
import random
from collections.abc import Callable
from pathlib import Path
from typing import Any

import neat

from evolution.run.champion import save_champion
from evolution.run.checkpoint import atomic_write_bytes, save_checkpoint
from evolution.run.evaluate import Evaluation, decode_genome, episode_seeds, training_environment
from evolution.run.experiment import Experiment
from evolution.run.stats import append_stats, generation_record, write_stats
from gathering_env import morphological_complexity as morphology_simplicity

CHECKPOINT_DIR = "checkpoints"
KEEP_CHECKPOINTS = 3


def checkpoints_in(run_dir: Path) -> list[Path]:
    """The run's checkpoint files, oldest first."""
    return sorted((Path(run_dir) / CHECKPOINT_DIR).glob("gen-*.ckpt"))


class RunRecorder:
    """The record of one run and the files written from it.

    Args:
        run_dir: the run directory. experiment: the run's experiment. config: its neat-python
            config; substrate: the HyperNEAT-M substrate (None for NEAT-M) — both to decode
            champions. neat_cfg_text: the config file's text (kept in checkpoints).
        records, best, champion_state: the record so far (a resumed run's, from its checkpoint).
    """

    def __init__(self, run_dir: Path, experiment: Experiment, config: neat.Config, substrate: Any,
                 neat_cfg_text: str | None, records: list[dict[str, Any]] | None = None,
                 best: tuple[float, int] | None = None, champion_state: dict[str, Any] | None = None) -> None:
        self.run_dir = Path(run_dir)
        self.experiment = experiment
        self.config = config
        self.substrate = substrate
        self.neat_cfg_text = neat_cfg_text
        self.records: list[dict[str, Any]] = list(records or [])
        self.best = best  # (task, genome key)
        self.champion_state = champion_state
        self.stats_path = self.run_dir / "stats.jsonl"
        self.champion_path = self.run_dir / "champion.json"

    # ------------------------------------------------------------------ run files
    def write_new_run(self, population: neat.Population) -> None:
        """The files of a new run: experiment.json, neat.cfg and the first checkpoint."""
        self.run_dir.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(self.run_dir / "experiment.json",
                           (json.dumps(self.experiment.to_dict(), indent=1) + "\n").encode())
        atomic_write_bytes(self.run_dir / "neat.cfg", self.neat_cfg_text.encode())
        self.save_checkpoint(population)

    def rewrite_stats(self) -> None:
        write_stats(self.stats_path, self.records)

    def save_checkpoint(self, population: neat.Population) -> None:
        """The state before ``population.generation`` is evaluated, with the record so far."""
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
        for old in checkpoints_in(self.run_dir)[:-KEEP_CHECKPOINTS]:
            old.unlink(missing_ok=True)

    # ------------------------------------------------------------------ generations
    def record(self, population: neat.Population, generation: int, species_count: int, seconds: float,
               evaluations: dict[int, Evaluation], genomes: dict[int, Any], failures: int,
               threshold: float | None = None, carried: frozenset[int] = frozenset(),
               amend: Callable[[dict[str, Any]], dict[str, Any]] | None = None) -> dict[str, Any]:
        """Keep and append the statistics of a finished generation (``species`` and the
        compatibility ``threshold`` that formed them); a better genome becomes the champion.
        ``carried``: genomes entered with their stored evaluation (not scored this generation).
        ``amend``: checks and completes the record before it is kept (a rebuilt generation,
        ``evolution.run.rebuild``)."""
        best_key = max(evaluations, key=lambda k: (evaluations[k].task, -k))
        record = generation_record(generation, list(evaluations.values()), species_count, seconds, best_key)
        record["threshold"] = None if threshold is None else float(threshold)
        record["failures"] = int(failures)
        record["trial_ft"] = trial_scores(evaluations, carried)
        exp = self.experiment
        if exp.multi_objective:
            front = population.reproduction.front
            record["front"] = {"genomes": [k for k, _ in front], "objectives": [list(o) for _, o in front],
                               "names": list(exp.objectives)}
        if amend is not None:
            record = amend(record)
        best_task = evaluations[best_key].task
        if self.best is None or best_task > self.best[0]:
            self.best = (best_task, best_key)
            self.champion_state = {"generation": generation, "genome": genomes[best_key],
                                   "evaluation": evaluations[best_key]}
            self.write_champion(**self.champion_state)
        self.records.append(record)
        append_stats(self.stats_path, record)
        return record

    def converged(self) -> bool:
        """The single-objective convergence stop: the last generation's best reached 100 + half the bonus."""
        exp = self.experiment
        return bool(exp.convergence_stop and not exp.multi_objective and self.records
                    and self.records[-1].get("task_best", 0.0) >= convergence_target(exp))

    def write_champion(self, generation: int, genome: Any, evaluation: Evaluation) -> None:
        exp = self.experiment
        controller, morphology = decode_genome(exp.method, genome, self.config, self.substrate)
        save_champion(self.champion_path, method=exp.method, experiment=exp.name, generation=generation,
                      genome=genome, morphology=morphology, controller=controller,
                      objectives={"task": evaluation.task, "morphology": evaluation.morphology,
                                  "controller": evaluation.controller},
                      environment=training_environment(exp.environment, exp.seed, exp.layout),
                      trial_seeds=episode_seeds(exp.seed, generation, exp.trials, exp.layout, exp.environment),
                      trial_ft=evaluation.trial_ft)

    def write_front(self, population: neat.Population) -> None:
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
            values.setdefault("morphology", morphology_simplicity(morphology, exp.complexity))
            values.setdefault("controller", 100.0 - float(controller.num_links))
            save_champion(front_dir / f"genome-{key}.json", method=exp.method, experiment=exp.name,
                          generation=generation, genome=genome, morphology=morphology,
                          controller=controller, objectives=values,
                          environment=training_environment(exp.environment, exp.seed, exp.layout))

    def plot(self) -> None:
        from evolution.run.plots import plot_run

        if self.records:
            plot_run(self.records, self.run_dir / "stats.png", title=self.experiment.name)


def trial_scores(evaluations: dict[int, Evaluation], carried: frozenset[int] = frozenset()
                 ) -> dict[str, list[float] | None]:
    """The record's ``trial_ft``: each genome scored this generation (id as a string) with its
    trials' ft, or None for a failed evaluation; ``carried`` genomes are left out. Everything
    else about an evaluation follows from the genome (``evolution.run.rebuild``)."""
    return {str(key): None if ev.failed else [float(f) for f in ev.trial_ft]
            for key, ev in sorted(evaluations.items()) if key not in carried}


def convergence_target(experiment: Experiment) -> float:
    """ft of a team that gathers every block within half the allowed steps: 100 + bonus / 2."""
    return 100.0 + experiment.world_config().time_bonus / 2.0


__all__ = ["CHECKPOINT_DIR", "KEEP_CHECKPOINTS", "RunRecorder", "checkpoints_in", "convergence_target", "trial_scores"]
