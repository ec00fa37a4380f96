"""The run directory's rules: what a new run may write into, and what a resumed run must verify.

A new run writes only into a missing or empty folder. A resumed run needs a readable
checkpoint whose experiment matches ``experiment.json``, the experiment and the overrides;
deleted ``experiment.json``, ``neat.cfg``, ``stats.jsonl`` and ``champion.json`` are rebuilt
from the checkpoint. ``resume_from`` a checkpoint of another run directory continues that run
into a missing or empty folder. Anything else raises ``UsageError`` before a file is written.

One writer per run directory: ``evolution.run.lock.RunLock`` is taken before the first file
is written and held until the run ends; a second writer is refused naming the holder's PID.
"""

from __future__ import annotations

import json
import random
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import neat

from evolution.guard import UsageError, check_output_dir
from evolution.run.champion import read_json
from evolution.run.checkpoint import CheckpointError, atomic_write_bytes, load_checkpoint
from evolution.run.experiment import Experiment, ExperimentError, experiment_from_run
from evolution.run.lock import LOCK_FILE
from evolution.run.neat_setup import make_neat_config, substrate_for
from evolution.run.recorder import CHECKPOINT_DIR, RunRecorder, checkpoints_in
from evolution.run.stats import check_generations, read_stats

#: What a resumed run must share with the run it continues (``generations`` may grow).
RUN_IDENTITY = ("method", "objectives", "seed", "population", "trials", "environment", "substrate")


def run_dir_of(checkpoint: Path) -> Path | None:
    """The run directory a checkpoint file belongs to (``RUN/checkpoints/gen-NNNN.ckpt``), if any."""
    checkpoint = Path(checkpoint)
    return checkpoint.parent.parent if checkpoint.parent.name == CHECKPOINT_DIR else None


def check_new_run_dir(run_dir: Path) -> None:
    """``run_dir`` may receive a new run: missing, empty, or holding only a lock file."""
    holds_run = (run_dir / CHECKPOINT_DIR).is_dir()
    check_output_dir(run_dir, owned=(LOCK_FILE,), what="run directory",
                     hint=f"it holds a run: continue it with gathering-evolve --resume {run_dir}"
                     if holds_run else "choose another --out")


def new_run(experiment: Experiment, run_dir: Path) -> tuple[neat.Population, RunRecorder]:
    """A new population and its recorder, after checking that ``run_dir`` may receive a run
    (nothing is written: ``RunRecorder.write_new_run`` does that once the backend is up and
    the run directory is locked; check the folder again then)."""
    check_new_run_dir(run_dir)
    config = make_neat_config(experiment)
    neat_cfg_text = Path(experiment.neat_config).read_text(encoding="utf-8")
    population = neat.Population(config, seed=experiment.seed)
    return population, RunRecorder(run_dir, experiment, config, substrate_for(experiment), neat_cfg_text)


def find_checkpoint(run_dir: Path, resume_from: Path | None) -> tuple[Path, dict[str, Any]]:
    """The checkpoint to resume from, after checking the run directory (nothing written)."""
    if resume_from is not None:
        home = run_dir_of(resume_from)
        if home is None or home.resolve() != run_dir.resolve():
            # continuing another run's checkpoint: into a fresh folder only
            check_output_dir(run_dir, owned=(LOCK_FILE,), what="run directory",
                             hint=f"--resume-from continues {resume_from} into a new folder, or into "
                                  "the run directory it belongs to")
        return resume_from, load_checkpoint(resume_from)
    if not run_dir.exists():
        raise UsageError(f"{run_dir}: does not exist; nothing to resume; allowed: an existing run directory "
                         "(start a new run without --resume)")
    if not run_dir.is_dir():
        raise UsageError(f"{run_dir}: is a file; allowed: a run directory written by gathering-evolve")
    candidates = list(reversed(checkpoints_in(run_dir)))
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


def _check_identity(path: Path, saved: dict[str, Any], other: Any, what: Path | None) -> None:
    for key in RUN_IDENTITY:
        if not isinstance(other, dict) or other.get(key) != saved.get(key):
            if what is not None:
                raise ExperimentError(
                    f"{what}: {key!r} differs from checkpoint {path} ({saved.get(key)!r}); the folder "
                    "holds pieces of different runs; allowed: the run's own files (delete experiment.json to "
                    "have it rebuilt from the checkpoint)")
            raise ExperimentError(f"{path}: resuming needs the same {key!r} as the run ({saved.get(key)!r}), "
                                  f"got {other.get(key)!r}")


def restore_run(run_dir: Path, experiment: Experiment | None, resume_from: Path | None,
                overrides: dict[str, Any] | None
                ) -> tuple[neat.Population, RunRecorder, bool, Callable[[], None]]:
    """(population, recorder, finished, write) of a verified run to resume (nothing written).

    ``write()`` writes back the missing files (call it holding the run's lock, once the
    backend is up). ``experiment`` None: the run's own experiment (from its files) with
    ``overrides``. A finished run only gets its missing files back; a continued one is reset
    to the checkpoint (later generations will be recomputed identically).
    """
    path, state = find_checkpoint(run_dir, resume_from)
    saved = state.get("experiment")
    population = state.get("population")
    if not isinstance(saved, dict) or not isinstance(population, neat.Population) or "random_state" not in state:
        raise CheckpointError(f"{path}: not a checkpoint of a gathering-evolve run")
    recorded_path = run_dir / "experiment.json"
    recorded = read_json(recorded_path, "experiment file", ExperimentError) if recorded_path.exists() else None
    if recorded is not None:
        _check_identity(path, saved, recorded, recorded_path)
    if experiment is None:
        own = dict(saved)
        if recorded is not None and "generations" in recorded:
            own["generations"] = recorded["generations"]  # a run extended after this checkpoint
        own_cfg = run_dir / "neat.cfg"
        experiment = experiment_from_run(own, str(recorded_path if recorded is not None else path),
                                         overrides, neat_config=own_cfg if own_cfg.is_file() else None)
    _check_identity(path, saved, experiment.to_dict(), None)
    stats_path, champion_path = run_dir / "stats.jsonl", run_dir / "champion.json"
    on_disk = _check_stats_file(stats_path)
    records = state.get("records")
    if records is None:  # checkpoint of an older version: statistics only in stats.jsonl
        records = [r for r in on_disk if r.get("generation", -1) < population.generation]
        if len(records) != population.generation:
            raise CheckpointError(
                f"{stats_path}: holds {len(records)} of the {population.generation} generations before "
                f"{path.name}, and this (older) checkpoint cannot rebuild them; allowed: the run's stats.jsonl")
    best, champion_state = state.get("best"), state.get("champion")
    if best is not None and not champion_path.exists() and champion_state is None:
        raise CheckpointError(f"{champion_path}: missing, and this (older) checkpoint {path.name} cannot "
                              "rebuild it; allowed: the run's champion.json")
    config = population.config  # the exact config the lineage was evolved with
    population.config.pop_size = experiment.population
    random.setstate(state["random_state"])
    recorder = RunRecorder(run_dir, experiment, config, substrate_for(experiment), state.get("neat_cfg"),
                           records, best, champion_state)
    finished = population.generation >= experiment.generations or recorder.converged()
    home = run_dir_of(path)
    elsewhere = home is None or home.resolve() != run_dir.resolve()

    def write() -> None:
        _rebuild_files(recorder, recorded, finished)
        if elsewhere:
            recorder.save_checkpoint(population)  # a run continued in a new folder resumes from there

    return population, recorder, finished, write


def _check_stats_file(path: Path) -> list[dict[str, Any]]:
    """The records of a run's ``stats.jsonl`` if it is readable and one sequence of generations."""
    hint = " (delete it to have it rebuilt from the checkpoint)"
    try:
        records = read_stats(path)
        check_generations(path, records)
    except ValueError as err:
        raise ValueError(f"{err}{hint}") from None
    return records


def _rebuild_files(recorder: RunRecorder, recorded: Any, finished: bool) -> None:
    """Verified: write back what is missing (and, for a continued run, reset stats and champion)."""
    run_dir, experiment = recorder.run_dir, recorder.experiment
    run_dir.mkdir(parents=True, exist_ok=True)
    if recorded is None or (not finished and recorded.get("generations") != experiment.generations):
        atomic_write_bytes(run_dir / "experiment.json", (json.dumps(experiment.to_dict(), indent=1) + "\n").encode())
    if not (run_dir / "neat.cfg").exists():
        if recorder.neat_cfg_text is not None:
            atomic_write_bytes(run_dir / "neat.cfg", recorder.neat_cfg_text.encode())
        else:
            warnings.warn(f"{run_dir / 'neat.cfg'}: missing and this (older) checkpoint cannot rebuild it; "
                          "the run goes on with the config stored in the checkpoint", stacklevel=3)
    if not finished or not recorder.stats_path.exists():
        recorder.rewrite_stats()
    if recorder.champion_state is not None and (not recorder.champion_path.exists() or not finished):
        recorder.write_champion(**recorder.champion_state)


__all__ = ["RUN_IDENTITY", "check_new_run_dir", "find_checkpoint", "new_run", "restore_run",
           "run_dir_of"]
