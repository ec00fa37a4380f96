"""Per-generation statistics: one flat record per generation, in JSONL and CSV.

``stats.jsonl`` is the record of truth (one JSON object per line, appended and fsync'ed
each generation); ``stats.csv`` is rewritten from it atomically for spreadsheet users.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from evolution.guard import writing
from evolution.run.checkpoint import atomic_write_bytes
from evolution.run.evaluate import Evaluation
from gathering_env import SENSOR_TYPES

OBJECTIVE_NAMES = ("task", "morphology", "controller")
TIMING_KEYS = ("seconds", "seconds_env", "seconds_controller", "seconds_decode")
WORK_KEYS = (*TIMING_KEYS, "steps")
"""What measures a run's work rather than its result: equal runs may differ here (a resumed or
rebuilt run, reuse of identical teams)."""


def generation_record(generation: int, evaluations: Sequence[Evaluation], species: int,
                      seconds: float, best_key: int) -> dict[str, Any]:
    """Flat statistics of one evaluated generation.

    Keys: ``generation``, ``genomes``, ``species``, ``best_genome``; for each objective
    ``<obj>_best``, ``<obj>_mean``, ``<obj>_std``; ``num_sensors_mean``; per sensor type
    ``count_<type>_mean`` and, for configurable types, ``range_<type>_mean`` and
    ``fov_<type>_mean`` (over the genomes that have such a sensor; null if none);
    ``steps`` simulated (a genome that took the evaluation of an identical team adds none:
    ``evolution.run.reuse``); and the timing keys ``seconds`` (wall clock of the generation),
    ``seconds_env``, ``seconds_controller``, ``seconds_decode`` (summed over genomes).
    """
    rec: dict[str, Any] = {"generation": int(generation), "genomes": len(evaluations),
                           "species": int(species), "best_genome": int(best_key)}
    for name in OBJECTIVE_NAMES:
        values = np.array([getattr(e, name) for e in evaluations], dtype=float)
        rec[f"{name}_best"] = float(values.max())
        rec[f"{name}_mean"] = float(values.mean())
        rec[f"{name}_std"] = float(values.std())
    rec["num_sensors_mean"] = float(np.mean([e.sensors["num_sensors"] for e in evaluations]))
    for kind, spec in SENSOR_TYPES.items():
        rec[f"count_{kind}_mean"] = float(np.mean([e.sensors[f"count_{kind}"] for e in evaluations]))
        if spec.configurable:
            for param in ("range", "fov"):
                vals = [e.sensors[f"{param}_{kind}"] for e in evaluations]
                vals = [v for v in vals if not math.isnan(v)]
                rec[f"{param}_{kind}_mean"] = float(np.mean(vals)) if vals else None
    rec["steps"] = int(sum(e.steps for e in evaluations))
    rec["seconds"] = float(seconds)
    rec["seconds_env"] = float(sum(e.seconds_env for e in evaluations))
    rec["seconds_controller"] = float(sum(e.seconds_controller for e in evaluations))
    rec["seconds_decode"] = float(sum(e.seconds_decode for e in evaluations))
    return rec


def read_stats(path: Path) -> list[dict[str, Any]]:
    """Records of a ``stats.jsonl`` file (empty list if it does not exist).

    A final line cut short by a crash is ignored with a warning naming the file; any other
    unreadable line, or a line that is not a JSON object, raises ``ValueError`` naming the
    file and line.
    """
    path = Path(path)
    if not path.exists():
        return []
    if path.is_dir():
        raise ValueError(f"{path}: is a folder; allowed: a stats.jsonl file")
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a text file; allowed: one JSON object per line") from None
    records = []
    for i, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except (json.JSONDecodeError, RecursionError):
            if i == len(lines):  # torn last line of a killed run
                warnings.warn(f"{path}: last line ({i}) is cut short (a killed run?); ignored it", stacklevel=2)
                break
            raise ValueError(f"{path}: line {i} is not valid JSON") from None
        if not isinstance(record, dict):
            raise ValueError(f"{path}: line {i} is not a JSON object; allowed: one record per line")
        records.append(record)
    return records


def check_generations(path: Path, records: Sequence[dict[str, Any]]) -> None:
    """Raise ``ValueError`` unless the records are generations 0, 1, 2, ... in order (one run).

    Two writers in one run directory, or a resume of a run that was still running, leave
    repeated or interleaved generations; such statistics are not one run's record.
    """
    generations = [r.get("generation") for r in records]
    for i, g in enumerate(generations):
        if type(g) is not int or g != i:
            shown = ",".join(str(x) for x in generations[:12]) + (",..." if len(generations) > 12 else "")
            raise ValueError(f"{path}: record {i + 1} is generation {g!r}, expected {i}; the generations "
                             f"({shown}) are not one run's record (two writers in one run directory?); allowed: "
                             "one record per generation, 0, 1, 2, ... in order")


def write_stats(path: Path, records: Sequence[dict[str, Any]]) -> None:
    """Rewrite ``stats.jsonl`` and its ``stats.csv`` sibling atomically."""
    path = Path(path)
    body = "".join(json.dumps(r, allow_nan=False) + "\n" for r in records)
    atomic_write_bytes(path, body.encode())
    write_csv(path.with_suffix(".csv"), records)


def append_stats(path: Path, record: dict[str, Any]) -> None:
    """Append one record to ``stats.jsonl`` (fsync'ed) and refresh ``stats.csv``."""
    path = Path(path)
    with writing(path), open(path, "a", encoding="utf-8") as f:
        f.write(json.dumps(record, allow_nan=False) + "\n")
        f.flush()
        os.fsync(f.fileno())
    write_csv(path.with_suffix(".csv"), read_stats(path))


def write_csv(path: Path, records: Sequence[dict[str, Any]]) -> None:
    columns: list[str] = []
    for r in records:
        for k, v in r.items():
            if k not in columns and not isinstance(v, (list, dict)):
                columns.append(k)
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, extrasaction="ignore")
    writer.writeheader()
    for r in records:
        writer.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in columns})
    atomic_write_bytes(Path(path), buf.getvalue().encode())


def without_timing(records: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Records with the wall-clock keys removed (for comparing runs)."""
    return [{k: v for k, v in r.items() if k not in TIMING_KEYS} for r in records]


def without_work(records: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Records with the ``WORK_KEYS`` removed: the results of a run alone."""
    return [{k: v for k, v in r.items() if k not in WORK_KEYS} for r in records]
