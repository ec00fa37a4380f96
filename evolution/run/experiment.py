"""Experiment files: one TOML file describes a run (method, objectives, budget, world).

Layout (every key optional except where noted; defaults are the paper's, docs/model.md §7)::

    [experiment]
    name = "S2"                  # label used in file names and the analysis
    method = "hyperneat-m"       # "hyperneat-m" | "neat-m"
    objectives = ["task"]        # any of "task", "morphology", "controller"
    seed = 1                     # run seed: every random choice flows from it
    generations = 250
    population = 150
    trials = 5                   # trials (episodes) per genome, mean ft is the fitness
    convergence_stop = true      # SO only: stop once the best genome gathers all blocks in
                                 # half the allowed steps (mean ft >= 100 + bonus / 2)
    speciation = "adaptive"      # optional: overrides the neat config's species_mode
                                 # ("adaptive" | "original" | "fixed", evolution.reproduction.species)
    neat_config = "hyperneat_m.neat.cfg"   # neat-python config (see "neat_config" below)
    protocol = "original"        # a named bundle of the options below (evolution.run.protocol)
    protocol_version = 4         # optional: which version of the bundle (default: the newest;
                                 # experiment.json records it, evolution.run.protocol)
    layout = "per_trial"         # "per_trial": fresh layouts from (seed, generation, trial);
                                 # "per_run": one layout for the whole run (the original code)
    elitism = "species"          # "species": the [NEATReproduction] elites, re-evaluated;
                                 # "ratchet" (SO): only the best-ever genome is carried over,
                                 # with its stored score, never re-evaluated (the original code)
    complexity = "paper"         # eq. 2: "paper" or "original" (gathering_env.morphological_complexity)
    truncation = "neat"          # how many of a species' best parent_fraction breed: "neat" (ceil,
                                 # at least two) or "encog" (floor, at least one: the original code)
    weights = "neat"             # link weights: "neat" (the neat config's weight_/bias_ keys) or
                                 # "encog" (the original's: uniform in +-5, its weight operations)
    species_bookkeeping = "membership"   # SO with speciation = "original" and the ratchet:
                                 # "encog" keeps Encog's species pointers, zombie species and
                                 # generation 0 (evolution.reproduction.bookkeeping)

    [environment]                # any gathering_env keyword: environment, max_cycles, ...
    environment = 2
    max_cycles = 10000

    [substrate]                  # HyperNEAT-M substrate options (evolution.encodings.substrate.Substrate)
    bottom_on_node0 = true

``load_experiment(path, overrides)`` validates everything and raises ``ExperimentError``
(a ``ValueError``) naming the file and the key.

``neat_config``: an absolute path is used as is; a relative one is looked up next to the
experiment file first and, if no such file exists there, among the shipped presets. So a
preset written out with ``gathering-evolve --dump S1 > my.toml`` keeps working anywhere.

Presets (the shipped experiment files and neat configs, by name) are ``evolution.run.presets``.
"""

from __future__ import annotations

import hashlib
import math
import tomllib
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from evolution.reproduction.bookkeeping import BOOKKEEPING
from evolution.reproduction.breeding import TRUNCATIONS
from evolution.reproduction.encog import WEIGHT_SCHEMES
from evolution.run.presets import CONFIG_DIR, DEFAULT_NEAT_CONFIGS
from evolution.run.protocol import PROTOCOLS, apply_protocol, newest_version, saved_version, versions
from gathering_env.config import WorldConfig
from gathering_env.sensors import COMPLEXITY_FORMULAS
from gathering_env.world import GatheringWorld

METHODS = ("hyperneat-m", "neat-m")
LAYOUTS = ("per_trial", "per_run")
ELITISM = ("species", "ratchet")
OBJECTIVES = ("task", "morphology", "controller")


#: Allowed ranges of the integer keys. The upper bounds stop a typo (population = 1500000)
#: before it allocates towards the out-of-memory killer: 10 000 genomes of the shipped
#: configs take about 150 MB (the paper uses 150).
LIMITS: dict[str, tuple[int, float]] = {
    "seed": (0, math.inf), "generations": (1, 100_000), "population": (2, 10_000), "trials": (1, 1_000),
}


def _species_modes() -> tuple[str, ...]:
    from evolution.reproduction.species import MODES

    return MODES


#: Keys whose value is one of a few names.
CHOICES = {"method": lambda: METHODS, "speciation": _species_modes, "protocol": lambda: PROTOCOLS,
           "layout": lambda: LAYOUTS, "elitism": lambda: ELITISM, "complexity": lambda: COMPLEXITY_FORMULAS,
           "truncation": lambda: TRUNCATIONS, "weights": lambda: WEIGHT_SCHEMES,
           "species_bookkeeping": lambda: BOOKKEEPING}


class ExperimentError(ValueError):
    """A broken or inconsistent experiment file or override."""


@dataclass(frozen=True)
class Experiment:
    """A validated experiment: what to evolve, for how long, in which world."""

    name: str = "experiment"
    method: str = "hyperneat-m"
    objectives: tuple[str, ...] = ("task",)
    seed: int = 1
    generations: int = 250
    population: int = 150
    trials: int = 5
    convergence_stop: bool = True
    speciation: str | None = None  # None: the neat config's [GatheringSpeciesSet] species_mode
    protocol: str | None = None
    protocol_version: int | None = None  # with a protocol: the bundle's version (None: no protocol)
    layout: str = "per_trial"
    elitism: str = "species"
    complexity: str = "paper"
    truncation: str = "neat"  # evolution.reproduction.breeding.truncate
    weights: str = "neat"  # "encog": evolution.reproduction.encog.use_encog_weights
    species_bookkeeping: str = "membership"  # "encog": evolution.reproduction.bookkeeping
    neat_config: Path = field(default_factory=lambda: CONFIG_DIR / DEFAULT_NEAT_CONFIGS["hyperneat-m"])
    environment: dict[str, Any] = field(default_factory=lambda: {"environment": 2, "max_cycles": 10_000})
    substrate: dict[str, Any] = field(default_factory=dict)
    source: str = "<defaults>"

    @property
    def multi_objective(self) -> bool:
        return len(self.objectives) > 1

    def world_config(self) -> WorldConfig:
        return WorldConfig.from_kwargs(**self.environment)

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe form (experiment.json, checkpoints) that holds no absolute path, so a run
        directory moves between folders and machines: ``neat_config`` is a shipped preset's name
        or the file's name alone (a run uses its own copy, ``neat.cfg``),
        ``neat_config_sha256`` identifies the file by its content, and ``source`` is the
        experiment file's name."""
        d = asdict(self)
        d["neat_config"] = portable_name(self.neat_config)
        d["neat_config_sha256"] = file_sha256(self.neat_config)
        d["source"] = self.source if self.source.startswith("<") else Path(self.source).name
        d["objectives"] = list(self.objectives)
        return d


def portable_name(path: Path) -> str:
    """A neat config's name without the machine's folders: relative to the shipped presets if
    it is one of them, else the file name."""
    path = Path(path)
    try:
        return path.resolve().relative_to(CONFIG_DIR.resolve()).as_posix()
    except ValueError:
        return path.name


def file_sha256(path: Path) -> str | None:
    """SHA-256 of a file's bytes, None if it cannot be read (a resumed run's source may be gone)."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return None


_EXPERIMENT_KEYS = {f.name for f in fields(Experiment)} - {"environment", "substrate", "source"}


def load_experiment(path: str | Path | None = None, overrides: dict[str, Any] | None = None) -> Experiment:
    """Read a TOML experiment file (or the defaults if ``path`` is None) and apply overrides.

    Args:
        path: the TOML file. overrides: flat keys of ``[experiment]`` (e.g. ``generations``)
            or ``environment.<key>`` / ``substrate.<key>``.

    Raises:
        ExperimentError: unreadable/invalid TOML, unknown section or key, bad value.
    """
    raw: dict[str, Any] = {}
    base = CONFIG_DIR
    source = "<defaults>"
    if path is not None:
        path = Path(path)
        source = str(path)
        if path.is_dir():
            hint = f" (it holds a run: continue it with --resume {path})" if (path / "checkpoints").is_dir() else ""
            raise ExperimentError(f"{path}: is a folder; allowed: a TOML experiment file (see configs/){hint}")
        try:
            raw = tomllib.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise ExperimentError(f"{path}: experiment file not found") from None
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
            raise ExperimentError(f"{path}: not valid TOML: {err}") from None
        if not raw:
            raise ExperimentError(f"{path}: experiment file is empty; allowed: an [experiment] and/or "
                                  "[environment] section (or no file at all for the built-in defaults)")
        base = path.resolve().parent
    return _validate(raw, source, base, overrides)


def experiment_from_run(saved: dict[str, Any], source: str, overrides: dict[str, Any] | None = None,
                        neat_config: Path | None = None) -> Experiment:
    """The experiment of a run from its ``experiment.json`` form (``Experiment.to_dict()``).

    ``overrides`` as for ``load_experiment``; ``neat_config`` replaces the recorded neat
    config path (the run's own copy). Raises ``ExperimentError`` naming ``source``.
    """
    if not isinstance(saved, dict):
        raise ExperimentError(f"{source}: the saved experiment is not a JSON object")
    saved = with_protocol_version(saved)
    section = {k: v for k, v in saved.items() if k in _EXPERIMENT_KEYS and v is not None}  # None: not set
    if neat_config is not None:
        section["neat_config"] = str(Path(neat_config).resolve())
    raw = {"experiment": section, "environment": saved.get("environment"), "substrate": saved.get("substrate", {})}
    # a resumed run takes its neat config from the checkpoint: the file need not exist any more
    return _validate(raw, source, CONFIG_DIR, overrides, need_neat_config=False, saved=True)


#: ``[experiment]`` keys added after runs were first recorded: a saved experiment without one
#: was run with its default (``with_protocol_version`` fills it in).
LATER_KEYS = ("truncation", "weights", "species_bookkeeping")


def with_protocol_version(saved: dict[str, Any]) -> dict[str, Any]:
    """A saved experiment (``Experiment.to_dict()`` form) with its ``protocol_version`` and every
    key of ``LATER_KEYS``: one saved before protocols had versions names a protocol but no version,
    and gets the version whose keys it holds (``evolution.run.protocol.saved_version``); one saved
    before a later key existed gets that key's default, with which it ran."""
    if not isinstance(saved, dict):
        return saved
    defaults = {f.name: f.default for f in fields(Experiment) if f.name in LATER_KEYS}
    saved = {**{k: v for k, v in defaults.items() if k not in saved}, **saved}
    if saved.get("protocol") not in PROTOCOLS or saved.get("protocol_version") is not None:
        return saved
    sections = {"experiment": saved, "environment": saved.get("environment") or {},
                "substrate": saved.get("substrate") or {}}
    return {**saved, "protocol_version": saved_version(saved["protocol"], sections)}


def _validate(raw: dict[str, Any], source: str, base: Path, overrides: dict[str, Any] | None,
              need_neat_config: bool = True, saved: bool = False) -> Experiment:
    unknown_sections = sorted(set(raw) - {"experiment", "environment", "substrate"})
    if unknown_sections:
        raise ExperimentError(
            f"{source}: unknown section(s) {unknown_sections}; allowed: [experiment], [environment], [substrate]"
        )
    for section in ("experiment", "environment", "substrate"):
        if section in raw and not isinstance(raw[section], dict):
            raise ExperimentError(f"{source}: {section} = {raw[section]!r}; allowed: a [{section}] table")
    exp_section = dict(raw.get("experiment", {}))
    env_section = dict(raw.get("environment", {"environment": 2, "max_cycles": 10_000}))
    sub_section = dict(raw.get("substrate", {}))
    for key, value in (overrides or {}).items():
        if value is None:
            continue
        if key.startswith("environment."):
            env_section[key.split(".", 1)[1]] = value
        elif key.startswith("substrate."):
            sub_section[key.split(".", 1)[1]] = value
        else:
            exp_section[key] = value

    unknown = sorted(set(exp_section) - _EXPERIMENT_KEYS)
    if unknown:
        raise ExperimentError(f"{source}: unknown key(s) {unknown} in [experiment]; allowed: {sorted(_EXPERIMENT_KEYS)}")
    if exp_section.get("protocol", "") is None:
        del exp_section["protocol"]  # a saved experiment without a protocol
    if exp_section.get("protocol_version", "") is None:
        del exp_section["protocol_version"]
    if "protocol_version" in exp_section and "protocol" not in exp_section:
        raise ExperimentError(f"{source}: [experiment] protocol_version={exp_section['protocol_version']!r} without "
                              "a protocol; allowed: with protocol = 'original' (or no protocol_version key)")
    if "protocol" in exp_section:
        protocol = _check_key(source, "protocol", exp_section["protocol"])  # before its bundle is applied
        version = exp_section.setdefault("protocol_version", newest_version(protocol))
        if isinstance(version, bool) or version not in versions(protocol):
            raise ExperimentError(f"{source}: [experiment] protocol_version={version!r}; allowed for protocol = "
                                  f"{protocol!r}: {list(versions(protocol))}")
        try:
            apply_protocol(protocol, {"experiment": exp_section, "environment": env_section,
                                      "substrate": sub_section},
                           source, exp_section.get("method", "hyperneat-m"), version, fill=not saved)
        except ValueError as err:
            raise ExperimentError(str(err)) from None
    values: dict[str, Any] = {"source": source}
    for key, value in exp_section.items():
        values[key] = _check_key(source, key, value)
    method = values.get("method", "hyperneat-m")
    neat_cfg = values.get("neat_config", DEFAULT_NEAT_CONFIGS[method])
    neat_path = Path(neat_cfg)
    if not neat_path.is_absolute():
        candidates = [base / neat_path, CONFIG_DIR / neat_path]
        neat_path = next((p for p in candidates if p.exists()), candidates[0])
    if need_neat_config and not neat_path.is_file():
        raise ExperimentError(f"{source}: [experiment] neat_config: file {neat_path} not found")
    values["neat_config"] = neat_path
    if "layout_seed" in env_section and values.get("layout", "per_trial") == "per_run":
        raise ExperimentError(f"{source}: [environment] layout_seed with [experiment] layout = 'per_run': the run "
                              "lays out its one layout from its seed; allowed: no layout_seed, or layout = 'per_trial'")
    try:
        world = WorldConfig.from_kwargs(**env_section)
        GatheringWorld.check_placement(world)  # an impossible world fails now, not in every evaluation
    except (ValueError, TypeError) as err:
        raise ExperimentError(f"{source}: [environment] {err}") from None
    if sub_section and method == "hyperneat-m":
        from evolution.encodings.substrate import Substrate

        try:
            Substrate(**sub_section)
        except (TypeError, ValueError) as err:
            raise ExperimentError(f"{source}: [substrate] {err}") from None
    elif sub_section:
        raise ExperimentError(f"{source}: [substrate] is used by method 'hyperneat-m' only; allowed: no "
                              f"[substrate] section for method {method!r}")
    values["environment"] = env_section
    values["substrate"] = sub_section
    experiment = Experiment(**values)
    if experiment.species_bookkeeping == "encog" and not experiment.multi_objective and (
            experiment.speciation != "original" or experiment.elitism != "ratchet"):
        raise ExperimentError(f"{source}: [experiment] species_bookkeeping = 'encog' keeps Encog's books of its "
                              "species of leaders; allowed: with speciation = 'original' and elitism = 'ratchet' "
                              "(or species_bookkeeping = 'membership')")
    return experiment


def _check_key(source: str, key: str, value: Any) -> Any:
    where = f"{source}: [experiment] {key}"
    if key == "name":
        if not isinstance(value, str) or not value or any(c in value for c in "/\\"):
            raise ExperimentError(f"{where}={value!r} must be a non-empty name without slashes")
        return value
    if key in CHOICES:
        if value not in CHOICES[key]():
            raise ExperimentError(f"{where}={value!r}; allowed: {list(CHOICES[key]())}")
        return value
    if key == "objectives":
        if isinstance(value, str):
            value = [value]
        if not isinstance(value, list) or not value or any(v not in OBJECTIVES for v in value):
            raise ExperimentError(f"{where}={value!r}; allowed: a non-empty list of {list(OBJECTIVES)}")
        if "task" not in value:
            raise ExperimentError(f"{where}={value!r} must include 'task'")
        if len(set(value)) != len(value):
            raise ExperimentError(f"{where}={value!r} lists an objective twice")
        return tuple(value)
    if key in LIMITS:
        low, high = LIMITS[key]
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            allowed = f">= {low}" if high == math.inf else f"in [{low}, {high}]"
            raise ExperimentError(f"{where}={value!r}; allowed: an integer {allowed}")
        return value
    if key == "protocol_version":
        return value  # checked against the protocol's versions before its bundle is applied
    if key == "convergence_stop":
        if not isinstance(value, bool):
            raise ExperimentError(f"{where}={value!r} must be true or false")
        return value
    if key == "neat_config":
        if not isinstance(value, (str, Path)):
            raise ExperimentError(f"{where}={value!r} must be a file path")
        return value
    raise ExperimentError(f"{where}: unknown key")  # pragma: no cover - filtered above


def with_overrides(experiment: Experiment, **changes: Any) -> Experiment:
    """A copy of ``experiment`` with top-level fields replaced (no re-validation of files)."""
    return replace(experiment, **changes)
