"""Held-out re-evaluation of a run's final genomes, for unbiased figures in the analysis.

Both samples of Table 4 are maxima over noisy evaluations: an SO champion is the best
training score a run ever saw, and an MO front holds the genomes whose training scores
happened to be non-dominated. Their training scores are therefore biased upward.
``reevaluate_run`` runs the champion (``champion.json``) and every front genome
(``front/*.json``) of a run again, ``trials`` times, on **held-out seeds**, through the
evaluation backends (``evolution.run.backends``), and caches the results in the run directory.

Held-out seeds. Training trial seeds are ``trial_seed(run seed, generation, trial)``, i.e.
``SeedSequence([run seed, generation, trial])`` with generation < the run's generations.
Re-evaluation calls ``evaluate`` with ``generation = HELDOUT_GENERATION`` (2**32 - 1, a tag
no run reaches), so its seeds are ``SeedSequence([run seed, 2**32 - 1, t])`` for t < K: a
separate domain, the same K worlds for every genome of a run. The K seeds are also checked
against every training seed of the run; on a (32-bit) collision the next tag down is used.

Cache: ``RUN_DIR/reevaluation.json`` (written atomically; an existing file of another
format is never overwritten). Each entry is keyed by a hash of the genome's genes, the
method, environment and substrate, and the list of held-out seeds (so the run seed and K),
and holds the objectives and per-trial ft. The file carries a version and a SHA-256 checksum
of its entries, and every entry is checked (finite numbers, one ft per seed) before it is
used, as checkpoints are: a damaged, edited or other-version cache is set aside
(``reevaluation.json.set-aside-N``) with a warning and its genomes are evaluated again.
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from pathlib import Path
from typing import Any

from evolution.run.backends import EvalContext, make_evaluator
from evolution.run.champion import ChampionError, genome_from_dict
from evolution.run.checkpoint import atomic_write_bytes
from evolution.run.evaluate import trial_seed

REEVALUATE_TRIALS = 20
"""Default K of ``gathering-analyze --reevaluate``."""
HELDOUT_GENERATION = 2**32 - 1
CACHE_FILE = "reevaluation.json"
CACHE_FORMAT = "gathering-evolution/reevaluation"
CACHE_VERSION = 2
"""Version 2 added the checksum (a version-1 cache is set aside and recomputed)."""


def training_seeds(run_seed: int, generations: int, trials: int) -> set[int]:
    """Every trial seed a run of ``generations`` generations used in training."""
    return {trial_seed(run_seed, g, t) for g in range(generations) for t in range(trials)}


def heldout_generation(run_seed: int, generations: int, trials: int, k: int) -> int:
    """The ``generation`` tag whose K trial seeds avoid every training seed of the run."""
    used = training_seeds(run_seed, generations, trials)
    tag = HELDOUT_GENERATION
    while any(trial_seed(run_seed, tag, t) in used for t in range(k)):
        tag -= 1
    return tag


def heldout_seeds(run_seed: int, generations: int, trials: int, k: int) -> list[int]:
    """The K held-out episode seeds of a run (see the module docstring)."""
    tag = heldout_generation(run_seed, generations, trials, k)
    return [trial_seed(run_seed, tag, t) for t in range(k)]


def _run_setup(run_dir: Path) -> tuple[Any, Any, Any]:
    """(experiment, neat config, substrate) of a run directory, from its own copies."""
    from evolution.run.champion import read_json
    from evolution.run.experiment import ExperimentError, experiment_from_run
    from evolution.run.neat_setup import make_neat_config, substrate_for

    path = run_dir / "experiment.json"
    try:
        experiment = experiment_from_run(read_json(path, "experiment file", ExperimentError), str(path),
                                         neat_config=run_dir / "neat.cfg")
        config = make_neat_config(experiment)
    except (TypeError, ExperimentError) as err:
        raise ValueError(f"{run_dir}: cannot rebuild the run's configuration for re-evaluation ({err}); "
                         "use --reevaluate 0 for its training scores") from None
    return experiment, config, substrate_for(experiment)


def _checksum(entries: dict[str, Any]) -> str:
    return hashlib.sha256(json.dumps(entries, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def _finite(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _entry_problem(key: Any, entry: Any) -> str | None:
    """What is wrong with one cache entry (None: a well-formed entry)."""
    if not isinstance(key, str) or not isinstance(entry, dict):
        return f"entry {key!r} is not an object"
    for name in ("task", "morphology", "controller"):
        if not _finite(entry.get(name)):
            return f"entry {key}: {name} = {entry.get(name)!r}; allowed: a finite number"
    trial_ft, seeds = entry.get("trial_ft"), entry.get("seeds")
    if not isinstance(seeds, list) or not seeds or not all(type(s) is int and s >= 0 for s in seeds):
        return f"entry {key}: seeds = {seeds!r}; allowed: a list of seeds (integers >= 0)"
    if not isinstance(trial_ft, list) or len(trial_ft) != len(seeds) or not all(map(_finite, trial_ft)):
        return f"entry {key}: trial_ft; allowed: one finite number per seed"
    return None


def _cache_problem(doc: dict[str, Any]) -> str | None:
    """What is wrong with a document in the cache format (None: a cache to trust)."""
    if doc.get("version") != CACHE_VERSION:
        return f"cache version {doc.get('version')!r}; this package reads version {CACHE_VERSION}"
    entries = doc.get("entries")
    if not isinstance(entries, dict):
        return "'entries' is not an object"
    for key, entry in entries.items():
        problem = _entry_problem(key, entry)
        if problem:
            return problem
    if doc.get("checksum") != _checksum(entries):
        return "checksum mismatch (the file was edited or damaged)"
    return None


def _set_aside(path: Path) -> Path:
    """Rename ``path`` to a free name beside it (``reevaluation.json.set-aside-N``); never overwrite."""
    for n in range(1, 10_000):
        target = path.with_name(f"{path.name}.set-aside-{n}")
        if not target.exists() and not target.is_symlink():
            path.rename(target)
            return target
    raise ValueError(f"{path}: cannot set it aside (too many set-aside copies beside it); move them away")


def _load_cache(path: Path) -> dict[str, Any]:
    """The trusted entries of a run's cache ({} if there is none).

    A file that is not a cache at all is refused (it is not ours to move). A cache that is
    damaged, edited (checksum), malformed (types, NaN) or of another version is reported in
    one warning and set aside under a new name; nothing from it is used.
    """
    if not path.exists():
        return {}
    if not path.is_file():
        raise ValueError(f"{path}: is a folder, not a re-evaluation cache; move it away (it is not overwritten)")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError, RecursionError):
        doc = None
    if not isinstance(doc, dict) or doc.get("format") != CACHE_FORMAT:
        raise ValueError(f"{path}: exists and is not a re-evaluation cache; move it away (it is not overwritten)")
    problem = _cache_problem(doc)
    if problem is None:
        return dict(doc["entries"])
    aside = _set_aside(path)
    warnings.warn(f"{path}: {problem}; not used: set aside as {aside.name}, the genomes are re-evaluated",
                  stacklevel=3)
    return {}


def _entry_key(genome: dict[str, Any], experiment: Any, seeds: list[int]) -> str:
    entry = {"genome": genome, "method": experiment.method, "environment": experiment.environment,
             "substrate": experiment.substrate, "seeds": seeds}
    if experiment.complexity != "paper":  # (keys of earlier caches stay valid)
        entry["complexity"] = experiment.complexity
    blob = json.dumps(entry, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:24]


def reevaluate_run(run_dir: Path, trials: int, workers: int | None = None, backend: str = "process",
                   generations: int | None = None) -> dict[str, dict[str, Any]]:
    """Held-out objectives of the champion and front genomes of one run.

    Args:
        run_dir: a run directory. trials: K held-out trials per genome (>= 1).
        workers, backend: as for ``evolution.run.backends.make_evaluator``.
        generations: generations the run trained (default: from its experiment).

    Returns:
        file name relative to ``run_dir`` (``champion.json``, ``front/genome-N.json``) ->
        ``{"task", "morphology", "controller", "trial_ft", "seeds"}``.
    """
    if trials < 1:
        raise ValueError(f"trials={trials}; allowed: >= 1")
    run_dir = Path(run_dir)
    files = [p for p in [run_dir / "champion.json"] if p.exists()] + sorted((run_dir / "front").glob("*.json"))
    if not files:
        return {}
    experiment, config, substrate = _run_setup(run_dir)
    gens = max(generations or 0, experiment.generations)
    tag = heldout_generation(experiment.seed, gens, experiment.trials, trials)
    seeds = [trial_seed(experiment.seed, tag, t) for t in range(trials)]
    cache_path = run_dir / CACHE_FILE
    cache = _load_cache(cache_path)

    results: dict[str, dict[str, Any]] = {}
    todo: list[tuple[str, str, Any]] = []
    for path in files:
        name = path.relative_to(run_dir).as_posix()
        try:
            data = json.loads(path.read_text(encoding="utf-8"))["genome"]
            genome = genome_from_dict(data, config)
        except (json.JSONDecodeError, KeyError, TypeError, ChampionError) as err:
            raise ValueError(f"{path}: cannot re-evaluate its genome: {err}") from None
        key = _entry_key(data, experiment, seeds)
        if key in cache:
            results[name] = cache[key]
        else:
            todo.append((name, key, genome))
    if todo:
        # fresh layouts whatever the run's layout; C by the run's own formula
        context = EvalContext(config, dict(experiment.environment), trials, experiment.seed, experiment.method,
                              substrate, complexity=experiment.complexity)
        evaluator = make_evaluator(context, workers, backend)
        try:
            evaluations = evaluator.map([g for _, _, g in todo], tag)
        finally:
            evaluator.close()
        if evaluator.failures:
            key, error = evaluator.failures[0]
            raise ValueError(f"{run_dir}: re-evaluating genome {key} failed: {error}")
        for (name, key, _), ev in zip(todo, evaluations):
            cache[key] = results[name] = {
                "task": ev.task, "morphology": ev.morphology, "controller": ev.controller,
                "trial_ft": list(ev.trial_ft), "seeds": seeds,
            }
        doc = {"format": CACHE_FORMAT, "version": CACHE_VERSION, "checksum": _checksum(cache), "entries": cache}
        atomic_write_bytes(cache_path, (json.dumps(doc, indent=1) + "\n").encode())
    return results
