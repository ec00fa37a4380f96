"""A species set that speciates: a compatibility threshold that holds a number of species.

neat-python's ``DefaultSpeciesSet`` keeps one fixed ``compatibility_threshold``. Its genome
distance is normalised by genome size, so a threshold tuned elsewhere can leave a whole
population in one species (measured on the shipped HyperNEAT-M config at N = 150: 1.6 gives
1-4 species), and NEAT's protection of new structure, and NEAT-MODS's species bound and round
robin, are then gone. ``GatheringSpeciesSet`` is that species set (the same assignment of
genomes to species, in the same deterministic order) with the threshold moved after every
speciation, by ``species_mode`` in its config section ``[GatheringSpeciesSet]``:

* ``adaptive`` (default): the threshold holds the species count near ``target_species``.
  After each speciation (``adapted_threshold``): with fewer species than the target it is
  multiplied by ``1 - threshold_step * (target - count) / target`` (down, in proportion to the
  shortfall); with more, by ``1 + threshold_step``, but only in a generation that formed a new
  species: existing species keep their closest genome whatever the threshold, so a surplus
  shrinks only by extinction (stagnation, no offspring, NEAT-MODS's species bound) and a higher
  threshold merely stops new species — raising it further while none form would wind it up.
  Multiplicative steps reach the right scale from any start (neat-python's distances of CPPNs
  lie around 0.3-3). Never below ``threshold_min``.
* ``original``: the rule of the original implementation (Encog's original NEAT speciation):
  the distance is ``E + D + 0.4 * mean |dw|`` over connection genes aligned by innovation
  number, on raw weights, not normalised by size (``original_distance``), plus for genomes with
  sensor genes (NEAT-M) their sensor term; before genomes are assigned, the threshold moves by
  ``threshold_step`` (0.01, additive): up when more than ``max_species`` species (40 in SO,
  the population in MO) survived from the previous generation, down when fewer than
  ``min_species`` (2) did; it starts at ``compatibility_threshold`` (1.0) and has no floor (below 0
  every genome but the leaders founds a species; ``threshold_min`` is the adaptive rule's). The
  count that moves it is of the species that *survived*: with the ratchet and elite rate 0 (the
  2018 SO set-up) only the best genome's species does, so the threshold falls by 0.01 every
  generation, below 0 from generation 100, and from then on every genome is its own species.
  (In the original a second, leaderless species can survive and hold the threshold still:
  Encog's species-pointer bookkeeping, ``species_bookkeeping = "encog"``, with which a population
  is speciated after scoring: ``evolution.reproduction.bookkeeping``.) In single-objective runs
  species are also Encog's (``leaders``, set by ``use_original_rule``): generation 0 is one
  species; a species is represented by its *leader* (its best genome, which
  ``NEATReproduction`` names after each evaluation; on a tie the leader keeps its place) and
  is disbanded when its leader is not in the new population; a genome joins the first
  species, oldest first, whose leader is within the threshold (``<=``), else it founds a new
  one. If every species was disbanded, the population is one species again, as in generation
  0 (Encog keeps its last species instead; under the ratchet neither happens, as the best genome
  leads its species). (neat-python instead keeps every species that finds a closest genome and
  puts a genome in the nearest species.)
* ``fixed``: neat-python's behaviour (the threshold never moves).

The threshold and the species count of every generation are in ``history`` (and the run's
statistics, ``threshold`` and ``species``). Keys and defaults: ``compatibility_threshold``
(the start), ``species_mode = adaptive``, ``target_species = 0.1`` (a count, or a fraction of
the population: 15 at N = 150), ``threshold_step = 0.1``,
``threshold_min = 0.01`` (``adaptive`` only), ``max_species = 40``, ``min_species = 2`` (the
last two only for ``original``).
"""

from __future__ import annotations

import math
from typing import Any

import neat
from neat.config import ConfigParameter, DefaultClassConfig

MODES = ("adaptive", "original", "fixed")
SECTION = "GatheringSpeciesSet"

#: Encog's coefficients of excess genes, disjoint genes and the mean weight difference.
ORIGINAL_COEFFICIENTS = (1.0, 1.0, 0.4)


def original_distance(a: Any, b: Any, coefficients: tuple[float, float, float] = ORIGINAL_COEFFICIENTS) -> float:
    """Original NEAT distance of two genomes' connection genes, aligned by innovation number.

    Genes of one genome with an innovation number above the other's largest are *excess*,
    the other unmatched ones *disjoint*; matching genes contribute ``|w_a - w_b|`` to the mean
    weight difference. Raw counts and raw weights: no normalisation by genome size.
    """
    ca = {_innovation(g): g.weight for g in a.connections.values()}
    cb = {_innovation(g): g.weight for g in b.connections.values()}
    if not ca and not cb:
        return 0.0
    top_a, top_b = max(ca, default=-1), max(cb, default=-1)
    excess = disjoint = 0
    for keys, top_other in ((ca.keys() - cb.keys(), top_b), (cb.keys() - ca.keys(), top_a)):
        for k in keys:
            if k > top_other:
                excess += 1
            else:
                disjoint += 1
    common = ca.keys() & cb.keys()
    mean_dw = sum(abs(ca[k] - cb[k]) for k in common) / len(common) if common else 0.0
    c_excess, c_disjoint, c_weight = coefficients
    return c_excess * excess + c_disjoint * disjoint + c_weight * mean_dw


def _innovation(gene: Any) -> Any:
    innovation = getattr(gene, "innovation", None)
    return gene.key if innovation is None else innovation


#: Encog's rule as the original implementation set it: start, step, fewest species; the most
#: species is 40 in single-objective runs and the population size in multi-objective ones.
ORIGINAL_RULE = {"compatibility_threshold": 1.0, "threshold_step": 0.01, "min_species": 2, "max_species_so": 40}


def use_original_rule(config: SpeciesSetConfig, multi_objective: bool, population: int) -> None:
    """Set a species set config to the original implementation's rule (``species_mode = original``)."""
    config.species_mode = "original"
    config.compatibility_threshold = ORIGINAL_RULE["compatibility_threshold"]
    config.threshold_step = ORIGINAL_RULE["threshold_step"]
    config.min_species = ORIGINAL_RULE["min_species"]
    config.max_species = population if multi_objective else ORIGINAL_RULE["max_species_so"]
    config.leaders = not multi_objective


def adapted_threshold(threshold: float, count: int, target: int, step: float, minimum: float,
                      new_species: bool = True) -> float:
    """The adaptive rule (see the module docstring): the threshold for the next speciation."""
    if count > target and new_species:
        return threshold * (1.0 + step)
    if count < target:
        return max(minimum, threshold * (1.0 - step * (target - count) / target))
    return threshold


TARGET_ALLOWED = "a count (an integer >= 1, at most the population) or a fraction of the population in (0, 1)"


def target_count(setting: str | float, population: int | None) -> int:
    """The species count a ``target_species`` setting asks for in a population of ``population``:
    an integer >= 1 is a count, a number in (0, 1) a fraction (rounded, at least 1).
    ``ValueError`` for anything else, or a count above the population."""
    try:
        value = float(setting)
    except (TypeError, ValueError):
        raise ValueError(f"target_species = {setting}; allowed: {TARGET_ALLOWED}") from None
    if 0.0 < value < 1.0:
        return max(1, round(value * population)) if population is not None else 1
    if not (value >= 1.0 and value == int(value)) or (population is not None and value > population):
        raise ValueError(f"target_species = {setting}; allowed: {TARGET_ALLOWED}"
                         + (f" ({population})" if population is not None else ""))
    return int(value)


class SpeciesSetConfig(DefaultClassConfig):
    """The ``[GatheringSpeciesSet]`` section, checked; errors name the section and key."""

    def __init__(self, param_dict: dict[str, Any]) -> None:
        super().__init__(param_dict, [
            ConfigParameter("compatibility_threshold", float),
            ConfigParameter("species_mode", str, "adaptive"),
            ConfigParameter("target_species", str, "0.1"),
            ConfigParameter("threshold_step", float, 0.1),
            ConfigParameter("threshold_min", float, 0.01),
            ConfigParameter("max_species", int, 40),
            ConfigParameter("min_species", int, 2),
        ])
        self.leaders = False  # Encog's species of leaders (SO, original mode): set by use_original_rule
        self.bookkeeping = "membership"  # or "encog" (evolution.reproduction.bookkeeping): set by neat_setup
        problems = []
        if self.species_mode not in MODES:
            problems.append(("species_mode", self.species_mode, " / ".join(MODES)))
        if not 0.0 < self.compatibility_threshold < math.inf:
            problems.append(("compatibility_threshold", self.compatibility_threshold, "a number > 0"))
        if not 0.0 < self.threshold_step < math.inf:
            problems.append(("threshold_step", self.threshold_step, "a number > 0"))
        if not 0.0 < self.threshold_min < math.inf:
            problems.append(("threshold_min", self.threshold_min, "a number > 0"))
        try:
            target_count(self.target_species, None)
        except ValueError:
            problems.append(("target_species", self.target_species, TARGET_ALLOWED))
        if self.min_species < 1 or self.max_species < self.min_species:
            problems.append(("max_species", self.max_species, f"an integer >= min_species ({self.min_species}) >= 1"))
        if problems:
            key, value, allowed = problems[0]
            raise ValueError(f"[{SECTION}] {key} = {value}; allowed: {allowed}")


class GatheringSpeciesSet(neat.DefaultSpeciesSet):
    """``DefaultSpeciesSet`` whose compatibility threshold moves (see the module docstring)."""

    def __init__(self, config: SpeciesSetConfig, reporters: Any) -> None:
        super().__init__(config, reporters)
        self.threshold = float(config.compatibility_threshold)
        self.history: list[tuple[int, float, int]] = []  # (generation, threshold used, species)
        self.pending: dict[int, Any] | None = None  # Encog's books: the population to speciate once scored

    @classmethod
    def parse_config(cls, param_dict: dict[str, Any]) -> SpeciesSetConfig:
        return SpeciesSetConfig(param_dict)

    @property
    def deferred(self) -> bool:
        """Encog's books (``evolution.reproduction.bookkeeping``): a population is speciated
        after it has been scored (``speciate_scored``), not when it is made."""
        cfg = self.species_set_config
        return cfg.species_mode == "original" and getattr(cfg, "leaders", False) and \
            getattr(cfg, "bookkeeping", "membership") == "encog"

    def speciate(self, config: Any, population: dict[int, Any], generation: int) -> None:
        cfg = self.species_set_config
        if self.deferred:  # kept until it is scored: NEATReproduction calls speciate_scored
            self.pending = population
            return
        leaders = cfg.species_mode == "original" and getattr(cfg, "leaders", False)
        if leaders:
            # Encog's resetSpecies: a species whose leader did not survive is disbanded
            for sid in [sid for sid, s in self.species.items() if s.representative.key not in population]:
                del self.species[sid]
        if cfg.species_mode == "original" and self.history:
            # Encog decides before assigning, from the number of species that survived
            survivors = len(self.species)
            if survivors > cfg.max_species:
                self.threshold += cfg.threshold_step
            elif survivors < cfg.min_species:
                self.threshold -= cfg.threshold_step  # Encog has no floor: below 0 no genome joins a leader
        used = self.threshold
        before = set(self.species)
        if leaders:
            self._speciate_leaders(config, population, generation, used)
        else:
            self._speciate_at(config, population, generation, used)
        count = len(self.species)
        self.history.append((int(generation), used, count))
        if cfg.species_mode == "adaptive":
            target = target_count(cfg.target_species, getattr(config, "pop_size", None) or len(population))
            self.threshold = adapted_threshold(used, count, target, cfg.threshold_step,
                                               cfg.threshold_min, new_species=bool(set(self.species) - before))

    def speciate_scored(self, config: Any, generation: int, best: Any) -> None:
        """Encog's speciation of the population kept by ``speciate``, now scored, with the
        ratchet's ``best`` genome (``evolution.reproduction.bookkeeping.speciate_scored``)."""
        from evolution.reproduction.bookkeeping import speciate_scored

        population, self.pending = self.pending, None
        used, count = speciate_scored(self, config, population, generation, best)
        self.history.append((int(generation), used, count))

    def speciate_pool(self, config: Any, population: dict[int, Any], generation: int) -> None:
        """Speciate at the current threshold without a step or a record: NEAT-MODS speciates
        its pool of parents and offspring before selection, and the generation's one step
        comes with the speciation of the new offspring."""
        self._speciate_at(config, population, generation, self.threshold)

    def _speciate_at(self, config: Any, population: dict[int, Any], generation: int, threshold: float) -> None:
        """neat-python's assignment (``DefaultSpeciesSet.speciate``: the same deterministic order)
        at ``threshold``, with the mode's distance."""
        original = self.species_set_config.species_mode == "original"
        cache: dict[tuple[int, int], float] = {}

        def distance(a: Any, b: Any) -> float:
            key = (a.key, b.key) if a.key <= b.key else (b.key, a.key)
            d = cache.get(key)
            if d is None:
                d = cache[key] = self._original(a, b, config) if original else a.distance(b, config.genome_config)
            return d

        unspeciated = sorted(population)
        representatives: dict[int, int] = {}
        members: dict[int, list[int]] = {}
        for sid in sorted(self.species):
            rep = self.species[sid].representative
            new_rep = min((population[gid] for gid in unspeciated), key=lambda g: distance(rep, g))
            representatives[sid], members[sid] = new_rep.key, [new_rep.key]
            unspeciated.remove(new_rep.key)
        for gid in unspeciated:
            genome = population[gid]
            close = [(distance(population[rid], genome), sid) for sid, rid in representatives.items()]
            close = [c for c in close if c[0] < threshold]
            if close:
                members[min(close)[1]].append(gid)
            else:
                sid = next(self.indexer)
                representatives[sid], members[sid] = gid, [gid]
        self._install(population, generation, sorted(representatives), representatives, members)
        # species that found no member are gone (neat-python drops them the same way)
        for sid in [sid for sid in self.species if sid not in representatives]:
            del self.species[sid]

    def _speciate_leaders(self, config: Any, population: dict[int, Any], generation: int, threshold: float) -> None:
        """Encog's assignment (see the module docstring): leaders stay in their species; every other
        genome, in key order, joins the first species (oldest first, founded ones included) whose
        leader is within ``threshold``, or founds one. Generation 0 (no species yet) is one species."""
        order = sorted(self.species)
        leader = {sid: self.species[sid].representative.key for sid in order}
        members = {sid: [leader[sid]] for sid in order}
        leaders = set(leader.values())
        others = [gid for gid in sorted(population) if gid not in leaders]
        if not order and others:
            sid = next(self.indexer)
            order, leader, members = [sid], {sid: others[0]}, {sid: list(others)}
            others = []
        for gid in others:
            genome = population[gid]
            for sid in order:
                if self._original(population[leader[sid]], genome, config) <= threshold:
                    members[sid].append(gid)
                    break
            else:
                sid = next(self.indexer)
                order.append(sid)
                leader[sid], members[sid] = gid, [gid]
        self._install(population, generation, order, leader, members)

    def _install(self, population: dict[int, Any], generation: int, order: list[int], representative: dict[int, int],
                 members: dict[int, list[int]]) -> None:
        """Make the species ``order`` hold ``members`` (ids) with ``representative`` (an id each),
        creating the new ones, and record ``genome_to_species``."""
        self.genome_to_species = {}
        for sid in order:
            species = self.species.get(sid)
            if species is None:
                species = self.species[sid] = neat.species.Species(sid, generation)
            for gid in members[sid]:
                self.genome_to_species[gid] = sid
            species.update(population[representative[sid]], {gid: population[gid] for gid in members[sid]})

    @staticmethod
    def _original(a: Any, b: Any, config: Any) -> float:
        d = original_distance(a, b)
        sensor_term = getattr(a, "sensor_distance", None)  # NEAT-M's sensor genes
        return d + sensor_term(b, config.genome_config) if sensor_term is not None else d

    def __setstate__(self, state: dict[str, Any]) -> None:
        super().__setstate__(state)
        self.__dict__.setdefault("threshold", float(self.species_set_config.compatibility_threshold))
        self.__dict__.setdefault("history", [])
        self.__dict__.setdefault("pending", None)


__all__ = ["GatheringSpeciesSet", "MODES", "ORIGINAL_COEFFICIENTS", "ORIGINAL_RULE", "use_original_rule", "SECTION", "SpeciesSetConfig",
           "original_distance", "target_count"]
