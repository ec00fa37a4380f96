"""Rebuild a run from its record instead of simulating it again, then go on evolving.

A run's ``stats.jsonl`` holds, for every generation, the ft of each trial of each genome
scored in it (``trial_ft``; ``evolution.run.recorder.trial_scores``). Everything else about an
evaluation follows from the genome (its decoded morphology and controller), and the lineage
follows from the scores and the run seed (neat-python's only randomness is Python's
``random``, seeded by the run). So a new run of the same experiment can take the recorded
scores for the recorded generations and simulate only the generations after them: a run
whose checkpoints are gone (another machine, a lost disk) continues where its record ends.

Checked, so that a rebuilt run is the recorded run or nothing:

- the record's ``experiment.json`` (beside its ``stats.jsonl``) equals the new run's experiment
  in everything but ``name``, ``generations`` and ``source``, the neat config's SHA-256 included;
- each rebuilt generation asks for exactly the genomes the record scored;
- each rebuilt generation's statistics equal the recorded ones (every field but the timings
  and ``steps``, which are the recorded run's and are copied from it).

A difference stops the run naming the generation and the field: the code or a library
changed what a genome decodes to, how it breeds, or how species form.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from evolution.guard import UsageError
from evolution.run.evaluate import Evaluation, decode_genome, scored
from evolution.run.stats import WORK_KEYS, check_generations, read_stats

RECORD_ONLY = WORK_KEYS
"""Statistics of a rebuilt generation taken from the record (they measure the recorded run's work)."""
NOT_IDENTITY = ("name", "generations", "source")
"""Experiment keys a rebuilt run may change."""


class RebuildError(UsageError):
    """A record that cannot be rebuilt, or a rebuilt generation that differs from it."""


def _record_paths(source: Path) -> tuple[Path, Path]:
    """(stats.jsonl, experiment.json) of a record; ``RebuildError`` if there is no stats.jsonl."""
    source = Path(source)
    stats = source / "stats.jsonl" if source.is_dir() else source
    if not stats.is_file():
        raise RebuildError(f"--rebuild-from {source}: no stats.jsonl there; allowed: a run or evidence folder "
                           "(or its stats.jsonl) written by gathering-evolve")
    return stats, stats.parent / "experiment.json"


def experiment_of_record(source: Path, overrides: dict[str, Any] | None = None) -> Any:
    """The experiment a record was run with (its ``experiment.json``), with ``overrides``."""
    from evolution.run.experiment import experiment_from_run

    _, exp_path = _record_paths(source)
    return experiment_from_run(_read_experiment(exp_path), str(exp_path), overrides)


def _read_experiment(exp_path: Path) -> dict[str, Any]:
    if not exp_path.is_file():
        raise RebuildError(f"{exp_path}: missing; a record is rebuilt only beside the experiment it was run with")
    try:
        recorded = json.loads(exp_path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise RebuildError(f"{exp_path}: not valid JSON; allowed: the experiment.json gathering-evolve wrote") from None
    if not isinstance(recorded, dict):
        raise RebuildError(f"{exp_path}: not a JSON object; allowed: the experiment.json gathering-evolve wrote")
    return recorded


def load_record(source: Path, experiment: dict[str, Any]) -> list[dict[str, Any]]:
    """The recorded generations of ``source`` (a run or evidence folder, or its ``stats.jsonl``)
    to rebuild a run of ``experiment`` (``Experiment.to_dict()``) from; ``RebuildError`` naming
    the file if they cannot be."""
    from evolution.run.experiment import with_protocol_version

    stats_path, exp_path = _record_paths(source)
    recorded = with_protocol_version(_read_experiment(exp_path))  # a record from before protocol versions
    for key in sorted(set(recorded) | set(experiment)):
        if key not in NOT_IDENTITY and recorded.get(key) != experiment.get(key):
            raise RebuildError(f"{exp_path}: {key!r} is {recorded.get(key)!r}, the new run's is {experiment.get(key)!r}; "
                               f"allowed: the same experiment (only {', '.join(NOT_IDENTITY)} may differ)")
    try:
        records = read_stats(stats_path)
        check_generations(stats_path, records)
    except ValueError as err:
        raise RebuildError(str(err)) from None
    if not records:
        raise RebuildError(f"{stats_path}: records no generation; allowed: the stats.jsonl of a run that finished "
                           "at least one generation")
    for record in records:
        scores = record.get("trial_ft")
        if not isinstance(scores, dict):
            raise RebuildError(f"{stats_path}: generation {record['generation']} has no per-genome scores (trial_ft, "
                               "which older runs did not record); allowed: a record that has them")
        for key, fts in scores.items():
            if not key.isdigit() or not (fts is None or (isinstance(fts, list) and fts and all(
                    isinstance(f, (int, float)) and math.isfinite(f) for f in fts))):
                raise RebuildError(f"{stats_path}: generation {record['generation']}, trial_ft[{key!r}] = {fts!r}; "
                                   "allowed: a genome id with a list of finite scores, or null (failed)")
    if len(records) > int(experiment["generations"]):
        raise RebuildError(f"{stats_path}: records {len(records)} generations, more than the new run's "
                           f"{experiment['generations']}; allowed: --generations {len(records)} or more")
    return records


class RebuildingEvaluator:
    """An evaluator that answers the recorded generations from the record and passes the
    later ones to ``inner`` (any backend of ``evolution.run.backends``)."""

    def __init__(self, inner: Any, records: list[dict[str, Any]], context: Any, source: Path) -> None:
        self.inner = inner
        self.records = records
        self.context = context
        self.source = source
        self.name = inner.name
        self.failures = inner.failures

    def rebuilds(self, generation: int) -> bool:
        return generation < len(self.records)

    def map(self, genomes: list[Any], generation: int) -> list[Evaluation]:
        if not self.rebuilds(generation):
            return self.inner.map(genomes, generation)
        scores = self.records[generation]["trial_ft"]
        wanted = sorted(int(k) for k in scores)
        asked = sorted(int(g.key) for g in genomes)
        if asked != wanted:
            extra = sorted(set(asked) - set(wanted))[:5]
            missing = sorted(set(wanted) - set(asked))[:5]
            raise RebuildError(f"{self.source}: generation {generation} scored other genomes than this run breeds "
                               f"(not recorded: {extra}, recorded but not bred: {missing}); the code or a library "
                               "changed how genomes breed; the run stopped")
        ctx = self.context
        results = []
        for g in genomes:
            fts = scores[str(g.key)]
            if fts is None:
                error = "failed in the recorded run"
                self.failures.append((g.key, error))
                results.append(Evaluation.failure(error))
                continue
            controller, morphology = decode_genome(ctx.method, g, ctx.neat_config, ctx.substrate)
            results.append(scored(controller, morphology, [float(f) for f in fts], ctx.complexity))
        return results

    def check(self, record: dict[str, Any]) -> dict[str, Any]:
        """``record`` of a rebuilt generation, checked against the recorded one, with the recorded
        run's timings and steps; ``RebuildError`` names the first field that differs."""
        generation = record["generation"]
        recorded = self.records[generation]
        for key in sorted(set(record) | set(recorded)):
            if key in RECORD_ONLY:
                continue
            if not _same(record.get(key), recorded.get(key)):
                raise RebuildError(f"{self.source}: generation {generation}: {key} is {record.get(key)!r} rebuilt, "
                                   f"{recorded.get(key)!r} recorded; the code or a library changed the run; "
                                   "the run stopped")
        return {**record, **{k: recorded[k] for k in RECORD_ONLY if k in recorded}}

    def close(self) -> None:
        self.inner.close()


def _same(a: Any, b: Any) -> bool:
    """Equal as JSON values (a float in one and an int in the other compare by value)."""
    return json.loads(json.dumps(a)) == json.loads(json.dumps(b))


__all__ = ["RebuildError", "RebuildingEvaluator", "experiment_of_record", "load_record"]
