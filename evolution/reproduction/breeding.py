"""One breeding routine for both arms: truncation, then one variation operator per offspring.

SO and MO runs differ only in how parents are *selected* (NEAT fitness sharing with
stagnation in ``NEATReproduction``, speciated NSGA-II in ``evolution.reproduction.mods``); both then breed
each species' offspring with ``breed``, so Table 4 compares selection and nothing else.

``breed`` (docs/model.md §5 and §6.5, the original's Encog scheme):

1. **truncation**: the species' candidates, best first by the arm's score (fitness in SO,
   NSGA-II rank score in MO), are cut to the best ``parent_fraction`` f (0.3). How many that
   is, is the experiment's ``truncation`` (``config.genome_config.truncation``): ``"neat"``
   (the default, neat-python's rule) keeps ceil(f n), at least two where the species has
   two; ``"encog"`` (the original code's ``TruncationSelection``) keeps max(floor(f n), 1),
   so a species of fewer than 7 genomes breeds from its best genome alone;
2. each offspring gets **one operator**, drawn in proportion to its probability:
   ``crossover`` (two distinct parents; matching genes from either, disjoint and excess genes
   from the parent with the better score, so in MO the better-ranked one), or a copy of one
   parent changed by exactly one mutation operator of the genome class (``weights``,
   ``add_node``, ``add_link``, ``remove_link``, ``remove_node``; NEAT-M adds its sensor
   operators). A species with a single parent cannot cross over: a drawn crossover becomes
   a mutation operator drawn from the others. Under ``"encog"`` truncation a crossover with
   k parents also fails, as Encog's does, when six draws of the second parent (with
   replacement) all repeat the first (probability k^-6), and the operator is drawn again.

The operators and their probabilities belong to the genome class
(``evolution.reproduction.operators.BreedingGenome``).
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable
from typing import Any

import neat
from neat.config import ConfigParameter, DefaultClassConfig
from neat.math_util import mean

from evolution.reproduction.bookkeeping import inherit_pointer, levelled_order
from evolution.reproduction.encog import (
    ORIGINAL_ELITE_MIN_MEMBERS,
    ORIGINAL_ELITE_RATE,
    original_leader,
    original_spawn,
)

TRUNCATIONS = ("neat", "encog")  # how many of a species' best parent_fraction breed (see truncate)
ENCOG_PARENT_DRAWS = 6  # Encog's draws of a second parent different from the first (1 + 5 retries)


class _Scored:
    """A parent seen by neat-python's crossover with ``fitness`` replaced by the breeding score."""

    def __init__(self, genome: Any, score: float) -> None:
        self._genome = genome
        self.fitness = score

    def __getattr__(self, name: str) -> Any:
        return getattr(self._genome, name)


def truncate(candidates: list[int], fraction: float, rule: str = "neat") -> list[int]:
    """The best ``fraction`` of ``candidates`` (sorted best first): ceil(fraction n), at least
    two where possible (``rule = "neat"``), or max(floor(fraction n), 1) (``"encog"``)."""
    if rule == "encog":
        keep = max(int(fraction * len(candidates)), 1)  # Java's (int) cast of the same double
    else:
        keep = max(int(math.ceil(fraction * len(candidates))), min(2, len(candidates)))
    return candidates[:keep]


def breed(candidates: list[int], genomes: dict[int, Any], score: dict[int, float], count: int,
          config: Any, new_key: Callable[[], int], ancestors: dict[int, tuple[int, ...]]) -> dict[int, Any]:
    """``count`` offspring of one species (see the module docstring).

    Args:
        candidates: genome ids of the species, sorted best first by ``score``.
        genomes: id -> genome. score: id -> the arm's breeding score (higher is better).
        config: the ``neat.Config``. new_key: gives the next genome id.
        ancestors: filled with child id -> parent ids.
    """
    gcfg = config.genome_config
    rule = getattr(gcfg, "truncation", "neat")
    parents = truncate(candidates, gcfg.parent_fraction, rule)
    ops = config.genome_type.operators(gcfg)
    names, weights = [n for n, _ in ops], [w for _, w in ops]
    children: dict[int, Any] = {}
    for _ in range(count):
        key = new_key()
        child = config.genome_type(key)
        if gcfg.variation == "one_operator":
            op = random.choices(names, weights)[0]
            if rule == "encog" and sum(weights[1:]) > 0:
                while op == "crossover" and (len(parents) < 2
                                             or random.random() < len(parents) ** -ENCOG_PARENT_DRAWS):
                    op = random.choices(names, weights)[0]  # Encog: no child, another operator
            elif op == "crossover" and len(parents) < 2 and sum(weights[1:]) > 0:
                op = random.choices(names[1:], weights[1:])[0]  # one parent: a mutation instead
            crossover = op == "crossover"
        else:
            op = None
            crossover = random.random() < gcfg.crossover_prob
        if crossover and len(parents) > 1:
            p1, p2 = random.sample(parents, 2)
            child.configure_crossover(_Scored(genomes[p1], score[p1]), _Scored(genomes[p2], score[p2]), gcfg)
            ancestors[key] = (p1, p2)
        else:
            p1 = random.choice(parents)
            copy = _Scored(genomes[p1], 0.0)
            child.configure_crossover(copy, copy, gcfg)  # a copy of one parent
            ancestors[key] = (p1,)
            if op is not None and op != "crossover":
                child.apply_operator(op, gcfg)
        if op is None:
            child.mutate(gcfg)
        children[key] = child
    return children


class NEATReproduction(neat.DefaultReproduction):
    """neat-python's NEAT selection (fitness sharing, stagnation, elitism) with ``breed``.

    Config section ``[NEATReproduction]``: ``elitism`` and ``min_species_size`` as in
    neat-python's ``DefaultReproduction``, ``original_elite_rate`` for Encog's selection
    (below); the truncation fraction is the genome section's ``parent_fraction`` (one value
    shared with the MO arm).

    **Ratchet** (``config.reproduction_config.ratchet = True``, set from the experiment's
    ``elitism = "ratchet"``; the original code's SO elitism): the best genome ever seen (by
    fitness; a later genome replaces it only by beating it) is carried into every new
    population as it is, with its fitness, and ``carried`` names it so that the trainer does
    not evaluate it again; no other genome survives (the per-species ``elitism`` is not used)
    and the other ``pop_size - 1`` genomes are offspring.

    **Encog's selection** (with the species set's Encog ``leaders``: ``speciation =
    "original"`` in SO): offspring counts by ``original_spawn`` from each species' mean
    fitness (no damping by the previous size, no minimum per species); with
    ``original_elite_rate`` r > 0 (default 0, the 2018 code's), the best fraction r of every
    species of more than 5 genomes survives unchanged (carried unscored with the ratchet, as
    Encog does not score them again) and counts towards its offspring; each species' best
    genome becomes its leader for the next speciation (``original_leader``: on a tie the
    leader keeps its place).
    """

    def __init__(self, config: Any, reporters: Any, stagnation: Any) -> None:
        super().__init__(config, reporters, stagnation)
        self.best: Any = None
        self.carried: set[int] = set()

    @classmethod
    def parse_config(cls, param_dict: dict[str, str]) -> DefaultClassConfig:
        if "survival_threshold" in param_dict:
            raise ValueError(f"[{cls.__name__}] survival_threshold: set the truncation fraction as parent_fraction "
                             "in the genome section (shared by the SO and MO arms)")
        return DefaultClassConfig(param_dict, [ConfigParameter("elitism", int, 0),
                                               ConfigParameter("min_species_size", int, 1),
                                               ConfigParameter("original_elite_rate", float, ORIGINAL_ELITE_RATE)],
                                  cls.__name__)

    def _exact_spawn(self, spawn: list[int], total: int, min_size: int) -> list[int]:
        """neat-python's ``_adjust_spawn_exact``, repeated: it gives up after one pass over the
        species even when a further pass could still take genomes from species above the minimum
        (and raises), but it changes ``spawn`` in place, so each call gets closer."""
        for _ in range(total + len(spawn)):
            try:
                return self._adjust_spawn_exact(spawn, total, min_size)
            except RuntimeError as err:
                if "Internal error" not in str(err):
                    raise
        return self._adjust_spawn_exact(spawn, total, min_size)

    def reproduce(self, config: Any, species: Any, pop_size: int, generation: int) -> dict[int, Any]:
        config.genome_config.innovation_tracker = self.innovation_tracker
        self.innovation_tracker.reset_generation()
        ratchet = getattr(self.reproduction_config, "ratchet", False)
        if getattr(species, "deferred", False):
            self._speciate_scored(config, species, generation)
        elif ratchet:
            for s in species.species.values():
                self._raise_best(s.members)
        self.carried = set()
        remaining, fitnesses = [], []
        spared = self._best_species(species, ratchet)
        updated = self.stagnation.update(species, generation)
        if getattr(species, "deferred", False) and all(stagnant and sid != spared for sid, _, stagnant in updated):
            spared = list(species.species)[-1]  # Encog never removes the last species
        for sid, s, stagnant in updated:
            stagnant = stagnant and sid != spared
            if stagnant:
                self.reporters.species_stagnant(sid, s)
            else:
                fitnesses.extend(m.fitness for m in s.members.values())
                remaining.append(s)
        if not remaining:
            species.species = {}
            return {}
        low, span = min(fitnesses), max(1.0, max(fitnesses) - min(fitnesses))
        for s in remaining:  # neat-python's adjusted fitness
            s.adjusted_fitness = (mean([m.fitness for m in s.members.values()]) - low) / span
        cfg = self.reproduction_config
        offspring = pop_size - 1 if ratchet else pop_size
        if getattr(species.species_set_config, "leaders", False):
            return self._reproduce_original(config, species, remaining, offspring, ratchet)
        elitism = 0 if ratchet else cfg.elitism
        min_size = max(cfg.min_species_size, elitism)
        if len(remaining) * min_size > offspring:
            # more species than offspring places (the original's speciation can form many): the
            # species with the lowest adjusted fitness get none and die out (Encog's levelOff)
            ranked_species = sorted(remaining, key=lambda s: (s.adjusted_fitness, -s.key), reverse=True)
            kept = {s.key for s in ranked_species[:max(offspring // min_size, 1)]}
            remaining = [s for s in remaining if s.key in kept]
        spawn = self.compute_spawn([s.adjusted_fitness for s in remaining], [len(s.members) for s in remaining],
                                   offspring, min_size)
        spawn = self._exact_spawn(spawn, offspring, min_size)

        new_population = self._start_population(ratchet)
        species.species = {}
        for n, s in zip(spawn, remaining):
            n = max(n, elitism)
            members = dict(s.members)
            s.members = {}
            species.species[s.key] = s
            ranked = sorted(members, key=lambda k: (members[k].fitness, k), reverse=True)
            elites = ranked[:elitism]
            for k in elites:
                new_population[k] = members[k]
            n -= len(elites)
            score = {k: float(members[k].fitness) for k in ranked}
            new_population.update(breed(ranked, members, score, n, config, lambda: next(self.genome_indexer),
                                        self.ancestors))
        return new_population

    def _speciate_scored(self, config: Any, species: Any, generation: int) -> None:
        """Encog's books (``evolution.reproduction.bookkeeping``): the ratchet's best genome (before
        the first breeding the first valid genome, whatever it scored; then a genome replaces it
        only by beating it), then the speciation of the scored population."""
        from evolution.reproduction.bookkeeping import first_best

        population = species.pending
        if self.best is None:
            self.best = first_best(population)  # generation 0's scores do not count
        else:
            self._raise_best(population)
        species.speciate_scored(config, generation, self.best)

    def _raise_best(self, genomes: dict[int, Any]) -> None:
        """The ratchet: a genome (in key order) replaces the best only by beating it."""
        for k in sorted(genomes):
            if self.best is None or genomes[k].fitness > self.best.fitness:
                self.best = genomes[k]

    def _best_species(self, species: Any, ratchet: bool) -> int | None:
        """With Encog's selection, the species that stagnation never removes: the one holding the
        best genome (``_best_key``), with Encog's books the one the best genome points at (None if
        it points at none); None with neat-python's selection (its ``species_elitism`` spares the
        fittest species)."""
        if not getattr(species.species_set_config, "leaders", False):
            return None
        if getattr(species, "deferred", False):
            from evolution.reproduction.bookkeeping import pointer

            sid = pointer(self.best)
            return sid if sid in species.species else None
        holder = {k: sid for sid, s in species.species.items() for k in s.members}
        fitness = {k: g.fitness for s in species.species.values() for k, g in s.members.items()}
        return holder.get(self._best_key(fitness, ratchet)) if fitness else None

    def _best_key(self, fitness: dict[int, float], ratchet: bool) -> int:
        """Encog's best genome: the ratchet's best-ever, else the highest score (then key)."""
        return self.best.key if ratchet and self.best is not None else max(fitness, key=lambda k: (fitness[k], k))

    def _start_population(self, ratchet: bool) -> dict[int, Any]:
        """The new population before any offspring: the ratchet's best genome, as it is (not
        evaluated again), or nothing."""
        if not ratchet:
            return {}
        self.carried = {self.best.key}
        return {self.best.key: self.best}

    def _reproduce_original(self, config: Any, species: Any, remaining: list[Any], offspring: int,
                            ratchet: bool) -> dict[int, Any]:
        """Encog's selection (see the class docstring) over the non-stagnant species."""
        ranked = {s.key: sorted(s.members, key=lambda k: (s.members[k].fitness, k), reverse=True) for s in remaining}
        fitness = {k: g.fitness for s in remaining for k, g in s.members.items()}
        books = getattr(species, "deferred", False)  # Encog's books: evolution.reproduction.bookkeeping
        if books:
            spared = self._best_species(species, ratchet)
            best_index = next((i for i, s in enumerate(remaining) if s.key == spared), None)
        else:
            best_key = self._best_key(fitness, ratchet)
            best_index = next((i for i, s in enumerate(remaining) if best_key in s.members), 0)
        order_before = list(species.species)
        counts = original_spawn([mean([m.fitness for m in s.members.values()]) for s in remaining],
                                [s.members[ranked[s.key][0]].fitness for s in remaining], best_index, offspring)
        new_population = self._start_population(ratchet)
        species.species = {}
        for n, s in zip(counts, remaining):
            if n <= 0:
                continue  # the species dies out
            members = dict(s.members)
            order = ranked[s.key]
            s.members = {}
            if not books:  # Encog's books chose the leader during the speciation
                s.representative = members[original_leader(members, s.representative.key)]  # of the next speciation
            species.species[s.key] = s
            if len(order) > ORIGINAL_ELITE_MIN_MEMBERS:
                for k in order[:min(n, int(len(order) * config.reproduction_config.original_elite_rate))]:
                    if ratchet and k == self.best.key:
                        continue  # already carried (Encog skips the old best without counting it)
                    new_population[k] = members[k]
                    n -= 1
                    if ratchet:
                        self.carried.add(k)
            score = {k: float(members[k].fitness) for k in order}
            children = breed(order, members, score, n, config, lambda: next(self.genome_indexer), self.ancestors)
            if books:
                for k, child in children.items():
                    inherit_pointer(child, tuple(members[p] for p in self.ancestors[k]))
            new_population.update(children)
        if books:  # Encog's levelOff sorts the species for the next speciation
            species.species = levelled_order({sid: species.species[sid] for sid in order_before
                                              if sid in species.species})
        return new_population
