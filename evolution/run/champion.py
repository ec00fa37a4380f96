"""Champion files: a genome's decoded team as plain JSON (no pickle needed to load).

A champion file holds the decoded morphology and controller weights (enough to replay the
team), the objectives it reached, the environment it was evolved in, and the genome's
genes as plain data::

    {"format": "gathering-evolution/run/champion", "version": 1,
     "method": "hyperneat-m", "experiment": "S2", "generation": 41, "genome_key": 6130,
     "objectives": {"task": 57.3, "morphology": 61.0, "controller": 82.0},
     "environment": {"environment": 2, "max_cycles": 10000},
     "morphology": {"sensors": [...]}, "controller": {...}, "genome": {...}}
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from evolution.run.checkpoint import atomic_write_bytes
from gathering_env import Morphology, WorldConfig

FORMAT = "gathering-evolution/run/champion"
VERSION = 1


class ChampionError(ValueError):
    """A champion file that is missing, truncated, malformed or of another version."""


def genome_to_dict(genome: Any) -> dict[str, Any]:
    """Plain-data view of a neat-python genome: nodes, connections and any extra genes."""
    def gene_data(gene: Any) -> dict[str, Any]:
        data = {}
        for attr in getattr(gene, "_gene_attributes", ()):
            value = getattr(gene, attr.name)
            data[attr.name] = _plain(value)
        return data

    out: dict[str, Any] = {
        "key": genome.key,
        "nodes": {str(k): gene_data(g) for k, g in sorted(genome.nodes.items())},
        "connections": [
            {"in": k[0], "out": k[1], **({"innovation": g.innovation} if hasattr(g, "innovation") else {}),
             **gene_data(g)} for k, g in sorted(genome.connections.items())
        ],
    }
    sensors = getattr(genome, "sensors", None)
    if sensors is not None:
        items = sensors.items() if isinstance(sensors, dict) else enumerate(sensors)
        out["sensors"] = {str(k): _plain(getattr(s, "to_dict", lambda s=s: vars(s))()) for k, s in items}
    return out


def genome_from_dict(data: dict[str, Any], config: Any) -> Any:
    """Rebuild a genome of ``config.genome_type`` from ``genome_to_dict`` data (for evaluation).

    Raises ``ChampionError`` if the data does not fit the genome class. Connection genes
    written without an innovation number get their index (innovation numbers only matter
    for crossover).
    """
    gcfg = config.genome_config
    try:
        genome = config.genome_type(int(data["key"]))
        for key, attrs in data["nodes"].items():
            gene = gcfg.node_gene_type(int(key))
            for name, value in attrs.items():
                setattr(gene, name, value)
            genome.nodes[int(key)] = gene
        for i, c in enumerate(data["connections"]):
            key = (int(c["in"]), int(c["out"]))
            gene = gcfg.connection_gene_type(key, innovation=int(c.get("innovation", i)))
            for attr in gene._gene_attributes:
                setattr(gene, attr.name, c[attr.name])
            genome.connections[key] = gene
        if "sensors" in data:
            from evolution.encodings.direct import SensorGene

            genome.sensors = {int(k): SensorGene(**v) for k, v in sorted(data["sensors"].items(), key=lambda kv: int(kv[0]))}
    except (KeyError, TypeError, ValueError, AttributeError) as err:
        raise ChampionError(f"genome data does not fit {config.genome_type.__name__}: {err!r}") from None
    return genome


def _plain(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item"):
        return value.item()
    return str(value)


@dataclass
class Champion:
    """A loaded champion: everything needed to replay the team."""

    method: str
    morphology: Morphology
    controller: Any
    objectives: dict[str, float]
    environment: dict[str, Any]
    experiment: str = ""
    generation: int = -1
    genome_key: int = -1
    genome: dict[str, Any] | None = None
    trial_seeds: tuple[int, ...] = ()
    """The episodes of ``objectives['task']`` (empty: not recorded, e.g. a file of an older run)."""
    trial_ft: tuple[float, ...] = ()
    """ft of each of ``trial_seeds``, in order (empty: not recorded, a file from before 2026-12)."""


def save_champion(path: Path, *, method: str, experiment: str, generation: int, genome: Any,
                  morphology: Morphology, controller: Any, objectives: dict[str, float],
                  environment: dict[str, Any], trial_seeds: list[int] | None = None,
                  trial_ft: list[float] | None = None) -> Path:
    """Write a champion JSON file atomically; returns its path. ``trial_seeds``: the episodes
    its ``task`` objective is the mean ft over (``evolution.run.evaluate.episode_seeds``);
    ``trial_ft``: the ft of each (so a replay can check each training episode)."""
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "method": method,
        "experiment": experiment,
        "generation": int(generation),
        "genome_key": int(genome.key),
        "objectives": {k: float(v) for k, v in objectives.items()},
        "environment": _plain(environment),
        "morphology": morphology.to_dict(),
        "controller": controller.to_dict(),
        "genome": genome_to_dict(genome),
    }
    if trial_seeds is not None:
        doc["trial_seeds"] = [int(s) for s in trial_seeds]
        if trial_ft is not None and len(trial_ft) == len(trial_seeds):
            doc["trial_ft"] = [float(f) for f in trial_ft]
    path = Path(path)
    atomic_write_bytes(path, (json.dumps(doc, indent=1, allow_nan=False) + "\n").encode())
    return path


def load_champion(path: str | Path) -> Champion:
    """Read a champion file. Raises ``ChampionError`` naming the file and the field."""
    from evolution.encodings.controller import TeamController

    path = Path(path)
    doc = read_json(path, "champion file", ChampionError)
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise ChampionError(f"{path}: field 'format' must be {FORMAT!r}")
    if doc.get("version") != VERSION:
        raise ChampionError(f"{path}: field 'version' is {doc.get('version')!r}; this package reads {VERSION}")
    for key in ("method", "morphology", "controller", "objectives", "environment"):
        if key not in doc:
            raise ChampionError(f"{path}: field {key!r} is missing")
    objectives = champion_objectives(path, doc)
    if not isinstance(doc["environment"], dict):
        raise ChampionError(f"{path}: field 'environment' must be an object of world parameters")
    try:
        WorldConfig.from_kwargs(**doc["environment"])
    except (ValueError, TypeError) as err:
        raise ChampionError(f"{path}: field 'environment': {err}") from None
    for key in ("generation", "genome_key"):
        if not isinstance(doc.get(key, -1), int) or isinstance(doc.get(key), bool):
            raise ChampionError(f"{path}: field {key!r} is {doc.get(key)!r}; allowed: an integer")
    try:
        morphology = Morphology.from_dict(doc["morphology"])
    except (ValueError, TypeError, AttributeError) as err:
        raise ChampionError(f"{path}: field 'morphology': {err}") from None
    try:
        controller = TeamController.from_dict(doc["controller"])
    except (ValueError, KeyError, TypeError, AttributeError, IndexError) as err:
        raise ChampionError(f"{path}: field 'controller': {err!s}") from None
    seeds = doc.get("trial_seeds", [])
    if not isinstance(seeds, list) or not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0
                                               for s in seeds):
        raise ChampionError(f"{path}: field 'trial_seeds' is {seeds!r}; allowed: a list of episode seeds "
                            "(integers >= 0)")
    fts = doc.get("trial_ft", [])
    if not isinstance(fts, list) or not all(isinstance(f, (int, float)) and not isinstance(f, bool)
                                            and math.isfinite(f) for f in fts) or len(fts) not in (0, len(seeds)):
        raise ChampionError(f"{path}: field 'trial_ft' is {fts!r}; allowed: a finite ft for each of the "
                            f"{len(seeds)} trial_seeds")
    if controller.num_inputs != len(morphology):
        raise ChampionError(f"{path}: field 'controller' reads {controller.num_inputs} inputs but the morphology "
                            f"has {len(morphology)} sensors; allowed: one input per sensor")
    return Champion(
        method=str(doc["method"]), morphology=morphology, controller=controller,
        objectives=objectives, environment=dict(doc["environment"]),
        experiment=str(doc.get("experiment", "")), generation=doc.get("generation", -1),
        genome_key=doc.get("genome_key", -1), genome=doc.get("genome"), trial_seeds=tuple(seeds),
        trial_ft=tuple(float(f) for f in fts),
    )


def read_json(path: Path, what: str, error: type[ValueError] = ValueError) -> Any:
    """Parse a JSON file; every failure raises ``error`` naming the file."""
    path = Path(path)
    if path.is_dir():
        raise error(f"{path}: is a folder; allowed: a {what} (JSON)")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise error(f"{path}: {what} not found") from None
    except (json.JSONDecodeError, UnicodeDecodeError, RecursionError) as err:
        raise error(f"{path}: not valid JSON (truncated?): {err}") from None


def champion_objectives(path: Path, doc: Any) -> dict[str, float]:
    """The finite objective values of a champion document (``task`` required)."""
    objectives = doc.get("objectives") if isinstance(doc, dict) else None
    if not isinstance(objectives, dict):
        raise ChampionError(f"{path}: field 'objectives' is missing or not an object; allowed: "
                            "{\"task\": ft, ...}")
    values = {}
    for key, value in objectives.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ChampionError(f"{path}: objectives.{key} = {value!r}; allowed: a finite number")
        values[key] = float(value)
    if "task" not in values:
        raise ChampionError(f"{path}: objectives.task is missing; allowed: an object with 'task'")
    return values
