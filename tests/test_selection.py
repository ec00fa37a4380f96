"""Direction of selection in both arms, on populations whose scores are set by hand.

A selection turned upside down (the worst genomes kept as elite, bred as parents, or given
the most offspring) still returns a population of the right size, so these tests set every
genome's score and check *which* genomes survive and breed:

* SO (``NEATReproduction``): the elite of each species are its fittest genomes, every
  offspring's parents lie in the fittest ``parent_fraction`` of its species, and each species
  spawns what neat-python's rule gives its adjusted fitness (computed here by hand);
* MO (``MODSReproduction``): each species breeds from its best-ranked parents, and the next
  parents are chosen from parents + offspring, so an elite parent survives a generation of
  bad offspring.
"""

from __future__ import annotations

import math
import random

import neat
import numpy as np
import pytest
from neat.species import Species
from test_mods import NEAT_CFG

from evolution.reproduction.breeding import NEATReproduction
from evolution.reproduction.mods import MODSReproduction
from evolution.reproduction.operators import BreedingGenome

SO_SECTION = """
[NEATReproduction]
elitism = 2
min_species_size = 2
"""


def so_config(tmp_path, pop):
    text = NEAT_CFG.format(pop=pop, threshold=3.0, progression="by_front")
    text = text[:text.index("[MODSReproduction]")] + SO_SECTION
    path = tmp_path / "so.cfg"
    path.write_text(text)
    return neat.Config(BreedingGenome, NEATReproduction, neat.DefaultSpeciesSet, neat.DefaultStagnation, str(path))


def mo_config(tmp_path, pop, progression="by_front"):
    path = tmp_path / "mo.cfg"
    path.write_text(NEAT_CFG.format(pop=pop, threshold=3.0, progression=progression))
    return neat.Config(BreedingGenome, MODSReproduction, neat.DefaultSpeciesSet, neat.DefaultStagnation, str(path))


def truncated(ranked: list[int], fraction: float = 0.3) -> set[int]:
    """The parents breed() may use: the best ceil(fraction * n), at least two (by hand)."""
    return set(ranked[:max(math.ceil(fraction * len(ranked)), min(2, len(ranked)))])


def parents_of(children: dict, ancestors: dict) -> set[int]:
    return {p for c in children for p in ancestors[c]}


# ---------------------------------------------------------------------------- SO arm
def test_so_elite_parents_and_spawn_come_from_the_best_of_each_species(tmp_path):
    config = so_config(tmp_path, pop=20)
    population = neat.Population(config, seed=4)
    repro, species_set = population.reproduction, population.species
    genomes = dict(population.population)
    keys = sorted(genomes)
    # Species 1 holds the first 10 genomes with fitnesses 10..19, species 2 the others with 0..9,
    # each in a shuffled order so that neither key order nor insertion order is the ranking.
    rng = np.random.default_rng(0)
    fitness = {}
    for sid, (members, base) in enumerate([(keys[:10], 10), (keys[10:], 0)], start=1):
        for k, f in zip(members, base + rng.permutation(10)):
            genomes[k].fitness = float(f)
            fitness[k] = float(f)
        s = Species(sid, 0)
        s.update(genomes[members[0]], {k: genomes[k] for k in members})
        species_set.species[sid] = s
    by_species = {sid: sorted(s.members, key=lambda k: -fitness[k]) for sid, s in species_set.species.items()}
    random.seed(1)
    new = repro.reproduce(config, species_set, 20, 1)

    assert len(new) == 20
    survivors = set(new) & set(genomes)
    assert survivors == set(by_species[1][:2]) | set(by_species[2][:2])       # the two fittest of each
    children = {k: g for k, g in new.items() if k not in genomes}
    species_of = {k: sid for sid, ks in by_species.items() for k in ks}
    spawned = {1: 0, 2: 0}
    for child in children:
        parents = repro.ancestors[child]
        sids = {species_of[p] for p in parents}
        assert len(sids) == 1                                                  # bred within one species
        sid = sids.pop()
        assert set(parents) <= truncated(by_species[sid]), (child, parents)    # from its best 30 %
        spawned[sid] += 1
    # Both top-3 parents of the big species do breed (30 % of 10 = 3, not 2 and not all 10).
    assert parents_of([c for c in children if species_of[repro.ancestors[c][0]] == 1], repro.ancestors) \
        == truncated(by_species[1])
    # neat-python's spawn rule by hand: adjusted fitness (mean - min) / range = 14.5/19 and 4.5/19,
    # target 20 * af = 15.26 and 4.74; half the step from the previous size 10: 10 + 3 and 10 - 3.
    assert spawned[1] + 2 == 13 and spawned[2] + 2 == 7


# ---------------------------------------------------------------------------- MO arm
class FixedSpecies:
    """A species set that puts genomes into species given by a rule (for the MO arm)."""

    def __init__(self, rule):
        self.rule = rule
        self.species: dict[int, Species] = {}
        self.genome_to_species: dict[int, int] = {}

    def speciate(self, config, population, generation):
        self.genome_to_species = {k: self.rule(k) for k in population}
        self.species = {}
        for k, sid in sorted(self.genome_to_species.items()):
            self.species.setdefault(sid, Species(sid, generation)).members[k] = population[k]


def mo_population(config, seed=5):
    population = neat.Population(config, seed=seed)
    return population.reproduction, dict(population.population)


def test_mo_each_species_breeds_from_its_best_ranked_parents(tmp_path):
    config = mo_config(tmp_path, pop=20)
    repro, genomes = mo_population(config)
    keys = sorted(genomes)
    # Both objectives equal: every genome is its own front, so rank = order of x (distinct values).
    x = dict(zip(keys, np.random.default_rng(2).permutation(20).astype(float)))
    for k, g in genomes.items():
        g.objectives = (x[k], x[k])
        g.fitness = x[k]
    rule = {k: 1 + (i % 2) for i, k in enumerate(keys)}          # two species, interleaved keys
    species = FixedSpecies(rule.get)
    species.species = {1: Species(1, 0)}
    species.species[1].members = dict(genomes)
    random.seed(3)
    new = repro.reproduce(config, species, 20, 0)
    assert set(repro.parents) == set(genomes)                    # 20 parents of 20 candidates: all
    for sid in (1, 2):
        members = sorted((k for k in keys if rule[k] == sid), key=lambda k: -x[k])
        children = [c for c in new if rule[repro.ancestors[c][0]] == sid]
        assert children
        assert parents_of(children, repro.ancestors) <= truncated(members), sid   # best 30 % by rank
        assert all(rule[p] == sid for c in children for p in repro.ancestors[c])
    # offspring in proportion to the parents' summed rank scores (40 - position in the sorted pool
    # of 20: 20..1): species holding the larger x values gets more; by hand from the ranks.
    ranked = sorted(keys, key=lambda k: -x[k])
    score = {k: 20.0 - i for i, k in enumerate(ranked)}
    sums = {sid: sum(score[k] for k in keys if rule[k] == sid) for sid in (1, 2)}
    counts = {sid: sum(1 for c in new if rule[repro.ancestors[c][0]] == sid) for sid in (1, 2)}
    exact = {sid: 20 * sums[sid] / (sums[1] + sums[2]) for sid in (1, 2)}
    assert counts == {sid: round(exact[sid]) for sid in (1, 2)} and sum(counts.values()) == 20


@pytest.mark.parametrize("progression", ["by_front", "round_robin"])
def test_mo_next_parents_come_from_parents_and_offspring(tmp_path, progression):
    """An elite parent survives a generation of bad offspring (NSGA-II's elitism)."""
    config = mo_config(tmp_path, pop=10, progression=progression)
    repro, genomes = mo_population(config)
    for k, g in genomes.items():
        g.objectives = (float(k), float(-k))                      # all on the first front
        g.fitness = float(k)
    species = FixedSpecies(lambda k: 1)
    species.species = {1: Species(1, 0)}
    species.species[1].members = dict(genomes)
    random.seed(4)
    offspring = repro.reproduce(config, species, 10, 0)
    first_parents = dict(repro.parents)
    assert set(first_parents) == set(genomes)
    for g in offspring.values():                                  # every offspring dominated by every parent
        g.objectives = (-100.0 - g.key, -100.0 - g.key)
        g.fitness = -100.0
    species.species[1].members = dict(offspring)
    second = repro.reproduce(config, species, 10, 1)
    assert set(repro.parents) == set(first_parents)               # the parents, not their offspring
    assert {k for k, _ in repro.front} == set(first_parents)
    # The other way round: offspring better than every parent replace them all.
    for g in second.values():
        g.objectives = (1000.0 + g.key, 1000.0 + g.key)
        g.fitness = 1000.0
    species.species[1].members = dict(second)
    repro.reproduce(config, species, 10, 2)
    assert set(repro.parents) == set(second)
